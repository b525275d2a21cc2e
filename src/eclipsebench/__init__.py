"""eclipsebench: simulate, reduce and score Spitzer/IRAC eclipse photometry."""

__version__ = "0.1.0"
