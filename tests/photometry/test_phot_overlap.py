"""Exact circle/pixel overlap against photutils and against analytic areas."""

from __future__ import annotations

import numpy as np
import pytest
from photutils.aperture import CircularAperture

from eclipsebench.photometry.overlap import circle_overlap_grid, pixel_overlap


def test_overlap_matches_photutils_exact_on_random_circles():
    rng = np.random.default_rng(3)
    for _ in range(200):
        x, y = rng.uniform(6.0, 14.0, 2)
        r = rng.uniform(0.2, 5.5)
        ours = circle_overlap_grid((21, 21), x, y, r)
        ref = CircularAperture((x, y), r).to_mask(method="exact").to_image((21, 21))
        assert np.max(np.abs(ours - ref)) < 1e-10


@pytest.mark.parametrize("x, y, r", [(10.0, 10.0, 0.5), (10.5, 10.5, 1.0), (10.0, 10.5, 2.25),
                                     (10.25, 9.75, 4.0), (10.5, 10.0, np.sqrt(0.5))])
def test_weights_sum_to_circle_area_and_respect_symmetry(x, y, r):
    w = circle_overlap_grid((21, 21), x, y, r)
    assert w.sum() == pytest.approx(np.pi * r * r, rel=1e-13)
    assert w.min() >= 0.0 and w.max() <= 1.0


def test_pixel_overlap_hand_cases():
    # a unit square centred on the circle centre, circle of radius 0.5: inscribed disk
    assert pixel_overlap(-0.5, 0.5, -0.5, 0.5, 0.5) == pytest.approx(np.pi / 4, rel=1e-14)
    # circle containing the square
    assert pixel_overlap(-0.5, 0.5, -0.5, 0.5, 1.0) == pytest.approx(1.0, rel=1e-14)
    # quarter disk in the first quadrant, r = 1, square [0, 1]^2
    assert pixel_overlap(0.0, 1.0, 0.0, 1.0, 1.0) == pytest.approx(np.pi / 4, rel=1e-14)
    # square far outside
    assert pixel_overlap(2.0, 3.0, 2.0, 3.0, 1.0) == 0.0
    # half-plane strip: [0, 2] x [-2, 2] with r = 1 holds half of the disk
    assert pixel_overlap(0.0, 2.0, -2.0, 2.0, 1.0) == pytest.approx(np.pi / 2, rel=1e-14)
