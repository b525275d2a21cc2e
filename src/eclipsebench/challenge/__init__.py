"""challenge stage of eclipsebench."""
