"""simulate stage of eclipsebench."""
