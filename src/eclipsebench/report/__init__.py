"""report stage of eclipsebench."""
