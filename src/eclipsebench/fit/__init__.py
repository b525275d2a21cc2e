"""fit stage of eclipsebench."""
