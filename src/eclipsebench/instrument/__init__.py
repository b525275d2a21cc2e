"""instrument stage of eclipsebench."""
