"""Statistics: the photon limit, ensemble statistics, method comparisons."""
