"""astro stage of eclipsebench."""
