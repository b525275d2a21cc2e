"""``[photometry]``: how cubes become per-frame tables."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from .base import check


@dataclass(frozen=True)
class PhotometrySection:
    """Centroiding, apertures, background and cleaning, shared by every method.

    The defaults follow Section 3.1 of the paper: center-of-light centroids
    over a 7x7 box, a 2.25 px aperture, a 3-7 px background annulus (mean per
    pixel), and the first frame of each subarray cube dropped (flagged).
    ``docs/photometry.md`` describes every key.
    """

    centroid: Literal["col", "gauss", "gauss-fixed", "lsq-asym"] = "col"
    box_px: int = 7
    radius_px: float = 2.25
    radii_px: tuple[float, ...] = (1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0, 3.25, 3.5, 3.75, 4.0)
    annulus_px: tuple[float, ...] = (3.0, 7.0)
    background: Literal["mean", "median"] = "mean"
    drop_first_frame: bool = True
    #: variable apertures r = a sqrt(noise_pixels) + b, as [[a, b], ...]
    variable_apertures: tuple[tuple[float, ...], ...] = ((1.0, 0.0),)
    #: fixed Gaussian width (px) for centroid = "gauss-fixed"; unset = the
    #: median free-fit width of the epoch's good frames
    gauss_width_px: float | None = None
    gauss_max_iter: int = 30
    #: half-width (px) of the box searched for the brightest pixel about the
    #: star's position in the median frame of each AOR
    search_px: int = 3
    clip_sigma: float = 3.0
    clip_iters: int = 5
    #: per-pixel outliers against a running median in time: window (frames,
    #: odd; 0 disables) and threshold (robust sigma)
    cosmic_ray_window: int = 9
    cosmic_ray_sigma: float = 6.0
    #: centroid / flux outliers against a running median: window and threshold
    outlier_window: int = 65
    outlier_sigma: float = 5.0
    #: bimsk bits that make a pixel unusable (radhit 512, saturation 8192, bad 16384)
    bimsk_bits: int = 25088
    #: read noise per aperture pixel ("pixels") or once per aperture as in the
    #: paper's Section 3.3 ("paper")
    noise_read: Literal["pixels", "paper"] = "pixels"
    epoch_gap_days: float = 1.0
    #: full-array frames: side of the square window cut about the star
    window_px: int = 32

    def validate(self) -> None:
        check(self.box_px >= 3 and self.box_px % 2 == 1, "box_px", "an odd integer >= 3")
        check(0.5 <= self.radius_px <= 10.0, "radius_px", "an aperture radius in 0.5-10 px")
        check(len(self.radii_px) >= 1 and all(0.5 <= r <= 10.0 for r in self.radii_px),
              "radii_px", "a list of radii in 0.5-10 px")
        check(len(set(round(r, 2) for r in self.radii_px)) == len(self.radii_px), "radii_px",
              "distinct radii (to 0.01 px)")
        check(len(self.annulus_px) == 2 and 0 < self.annulus_px[0] < self.annulus_px[1] <= 15,
              "annulus_px", "[inner, outer] with 0 < inner < outer <= 15 px")
        check(all(len(ab) == 2 and ab[0] >= 0 for ab in self.variable_apertures),
              "variable_apertures", "a list of [a, b] pairs with a >= 0")
        check(self.gauss_width_px is None or 0.1 <= self.gauss_width_px <= 5.0,
              "gauss_width_px", "a width in 0.1-5 px")
        check(1 <= self.gauss_max_iter <= 500, "gauss_max_iter", "an integer in 1-500")
        check(1 <= self.search_px <= 15, "search_px", "an integer in 1-15")
        check(self.clip_sigma >= 0, "clip_sigma", "a number >= 0 (0 = no clipping)")
        check(1 <= self.clip_iters <= 100, "clip_iters", "an integer in 1-100")
        check(self.cosmic_ray_window == 0 or (self.cosmic_ray_window >= 3
                                              and self.cosmic_ray_window % 2 == 1),
              "cosmic_ray_window", "0 (off) or an odd integer >= 3")
        check(self.cosmic_ray_sigma > 0, "cosmic_ray_sigma", "a positive number")
        check(self.outlier_window == 0 or (self.outlier_window >= 3
                                           and self.outlier_window % 2 == 1),
              "outlier_window", "0 (off) or an odd integer >= 3")
        check(self.outlier_sigma > 0, "outlier_sigma", "a positive number")
        check(0 <= self.bimsk_bits < 2**31, "bimsk_bits", "a bit mask in 0-2^31")
        check(self.epoch_gap_days > 0, "epoch_gap_days", "a positive number of days")
        check(16 <= self.window_px <= 256, "window_px", "an integer in 16-256")
