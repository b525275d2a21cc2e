"""pytest: the Markdown pages run as doctests; the Sphinx configuration and build do not."""

collect_ignore = ["conf.py"]
collect_ignore_glob = ["_build/*", "generated/*"]
