"""Package data: the system catalogue, the default challenge, fitted gain-map coefficients."""
