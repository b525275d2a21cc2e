"""``[photometry]``: how cubes become per-frame tables."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .base import check


@dataclass(frozen=True)
class PhotometrySection:
    """Centroiding, apertures and background, shared by every method.

    The defaults follow Section 3.1 of the paper: center-of-light centroids
    over a 7x7 box, a 2.25 px aperture, a 3-7 px background annulus, and the
    first frame of each subarray cube dropped.
    """

    centroid: Literal["col", "gauss", "gauss-fixed", "lsq-asym"] = "col"
    box_px: int = 7
    radius_px: float = 2.25
    radii_px: tuple[float, ...] = (1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0, 3.25, 3.5, 3.75, 4.0)
    annulus_px: tuple[float, ...] = (3.0, 7.0)
    background: Literal["mean", "median"] = "mean"
    drop_first_frame: bool = True

    def validate(self) -> None:
        check(self.box_px >= 3 and self.box_px % 2 == 1, "box_px", "an odd integer >= 3")
        check(0.5 <= self.radius_px <= 10.0, "radius_px", "an aperture radius in 0.5-10 px")
        check(len(self.radii_px) >= 1 and all(0.5 <= r <= 10.0 for r in self.radii_px),
              "radii_px", "a list of radii in 0.5-10 px")
        check(len(self.annulus_px) == 2 and 0 < self.annulus_px[0] < self.annulus_px[1] <= 15,
              "annulus_px", "[inner, outer] with 0 < inner < outer <= 15 px")
