"""Print the package-level import graph of eclipsebench and any cycle in it.

Usage: python tools/import_graph.py  (exit 1 if a module-level or package-level cycle exists)
The house rule (docs/architecture.md): imports point down the layers, never back up.
"""

from __future__ import annotations

import ast
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "src" / "eclipsebench"


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> set[str]:
    """Modules of the package that ``path`` imports at run time (TYPE_CHECKING blocks skipped)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    here = module_name(path).split(".")
    if path.name != "__init__.py":
        here = here[:-1]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            node.body = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[:len(here) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("eclipsebench"):
                found.add(target)
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("eclipsebench")}
    return found


def package(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    out, state, stack = [], {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                out.append(stack[stack.index(m):] + [m])
            elif not state.get(m):
                visit(m)
        stack.pop()
        state[n] = 2

    for n in sorted(graph):
        if not state.get(n):
            visit(n)
    return out


def main() -> int:
    packages: dict[str, set[str]] = defaultdict(set)
    for path in ROOT.rglob("*.py"):
        src = package(module_name(path))
        for target in imports(path):
            dst = package(target)
            if dst != src and src not in ("api", "cli", "__main__", "eclipsebench"):
                packages[src].add(dst)
    for src in sorted(packages):
        print(f"{src:12s} -> {', '.join(sorted(packages[src]))}")
    found = cycles(packages)
    for c in found:
        print("cycle:", " -> ".join(c))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
