"""photometry stage of eclipsebench."""
