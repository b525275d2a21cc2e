"""Check the house rule of docs/architecture.md: imports point down the layers.

Usage: python tools/import_graph.py [--root SRC/eclipsebench] [--doc docs/architecture.md]

Prints the package-level import graph, then one line per import that breaks
the rule, and exits 1 if there is any. The layers are read from the table in
``docs/architecture.md`` (one source: the page a developer reads is the rule
the test holds). A package may import its own modules and any package of a
row above its own in the table (a lower layer, or an earlier row of its
layer); an import of a package in its own row or below it fails, and so does
a cycle, between packages or between modules (:func:`module_cycles`). Every import statement counts: at module level, inside a
function, and under ``if TYPE_CHECKING`` (an annotation that names a higher
layer is a dependency of the reader all the same). The package root
(``eclipsebench/__init__.py``: the version and the lazily loaded public names)
is layer 0; ``__main__`` sits with ``cli``.
"""

from __future__ import annotations

import argparse
import ast
import functools
import re
import sys
from collections import defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
ROOT = REPO / "src" / "eclipsebench"
DOC = REPO / "docs" / "architecture.md"
#: Modules that the table does not name, with the (layer, row) they take.
EXTRA_LAYERS = {"eclipsebench": (0, 0), "__main__": (8, 10**6)}
_ROW = re.compile(r"^\|\s*(\d+)\s*\|(.+?)\|")


def layers(doc: Path = DOC) -> dict[str, tuple[int, int]]:
    """Package name -> (layer, row) from the ``| layer | package | ... |`` table of ``doc``.

    Rows are numbered in the table's order: within a layer, a row may import
    the rows above it (``io`` reads ``detector``'s constants), not its own.
    """
    out = {}
    row = 0
    for line in doc.read_text(encoding="utf-8").splitlines():
        match = _ROW.match(line)
        if match:
            row += 1
            for name in re.findall(r"`([A-Za-z_][\w]*)`", match.group(2)):
                out[name] = (int(match.group(1)), row)
    if not out:
        raise SystemExit(f"{doc}: no layer table found")
    return {**out, **EXTRA_LAYERS}


def module_name(path: Path, root: Path) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    """The ids of the nodes under ``if TYPE_CHECKING:`` (imports for annotations only)."""
    inside: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            inside |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    return inside


@functools.cache
def _import_nodes(source: str) -> tuple[tuple[ast.Import | ast.ImportFrom, bool], ...]:
    """The import statements of ``source`` in :func:`ast.walk`'s order, each with whether it
    sits under ``if TYPE_CHECKING:``.

    Kept by the text itself: :func:`check` reads each file twice (the package graph, then
    the module graph), and a process checking a copy of the package with one module added
    (tests/foundation/test_architecture.py) parses only that module again. The nodes are
    only read, never changed.
    """
    tree = ast.parse(source)
    inside = _type_checking_nodes(tree)
    return tuple((node, id(node) in inside) for node in ast.walk(tree)
                 if isinstance(node, ast.Import | ast.ImportFrom))


def imports(path: Path, root: Path, modules: set[str] | None = None,
            runtime_only: bool = False) -> list[tuple[int, str]]:
    """(line, module) of every eclipsebench module ``path`` imports, wherever the statement is.

    With ``modules`` (the names of the package's modules), ``from X import n`` is
    ``X.n`` where that is a module of its own; with ``runtime_only``, imports under
    ``if TYPE_CHECKING:`` (never executed) are left out.
    """
    here = module_name(path, root).split(".")
    if path.name != "__init__.py":
        here = here[:-1]
    found = []
    for node, annotations_only in _import_nodes(path.read_text(encoding="utf-8")):
        if runtime_only and annotations_only:
            continue
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[:len(here) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
                if not node.module:   # from . import x, y: each name may be a module
                    found += [(node.lineno, f"{target}.{a.name}") for a in node.names]
                    continue
            else:
                target = node.module or ""
            if target.split(".")[0] != root.name:
                continue
            if modules is None:
                found.append((node.lineno, target))
            else:
                found += [(node.lineno, f"{target}.{a.name}" if f"{target}.{a.name}" in modules
                           else target) for a in node.names]
        elif isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names
                      if a.name.split(".")[0] == root.name]
    return found


def module_cycles(root: Path = ROOT) -> list[list[str]]:
    """Cycles between modules through imports that run (a function's own included).

    The package graph cannot see a loop inside one package (``fit.result``
    importing ``fit.reduce`` in a function while ``fit.reduce`` imports it at
    the top); this graph joins modules, not packages. Imports under ``if
    TYPE_CHECKING:`` are left out: they never run, and the package rule already
    holds them to the layers.
    """
    paths = {module_name(p, root): p for p in sorted(root.rglob("*.py"))}
    names = set(paths)
    graph = {name: {t for _, t in imports(path, root, names, runtime_only=True)
                    if t in names and t != name} for name, path in paths.items()}
    return cycles(graph)


def package(module: str) -> str:
    """The top-level package of a module (``eclipsebench.fit.reduce`` -> ``fit``)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    out: list[list[str]] = []
    state: dict[str, int] = {}
    stack: list[str] = []

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


def check(root: Path = ROOT, doc: Path = DOC) -> tuple[dict[str, set[str]], list[str]]:
    """The package graph and the broken rules (one message per offending import)."""
    rank = layers(doc)
    graph: dict[str, set[str]] = defaultdict(set)
    problems = []
    for path in sorted(root.rglob("*.py")):
        src = package(module_name(path, root))
        for line, target in imports(path, root):
            dst = package(target)
            if not ((root / dst).is_dir() or (root / f"{dst}.py").exists()):
                dst = root.name     # a name the root defines ("from .. import __version__")
            if dst == src:
                continue
            graph[src].add(dst)
            where = path.relative_to(root.parent)
            unknown = [p for p in (src, dst) if p not in rank]
            if unknown:
                problems.append(f"{where}: package '{unknown[0]}' is not in the layer table "
                                f"of {doc.name}")
            elif rank[dst] >= rank[src] and dst != root.name:
                problems.append(f"{where}:{line}: '{src}' (layer {rank[src][0]}) imports "
                                f"{target} ('{dst}', layer {rank[dst][0]}, not above it in "
                                f"the table)")
    for c in cycles(graph):
        problems.append("cycle: " + " -> ".join(c))
    for c in module_cycles(root):
        problems.append("module cycle: " + " -> ".join(c))
    return graph, sorted(set(problems))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=ROOT, help="the package folder")
    parser.add_argument("--doc", type=Path, default=DOC, help="the page with the layer table")
    args = parser.parse_args(argv)
    graph, problems = check(args.root, args.doc)
    for src in sorted(graph):
        print(f"{src:12s} -> {', '.join(sorted(graph[src]))}")
    for p in problems:
        print("broken:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
