"""One module per subcommand; see :mod:`eclipsebench.cli` for the protocol."""
