"""All-zero, constant and negated cubes: their own flags, and their neighbours stay good."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits

from eclipsebench.config.photometry import PhotometrySection
from eclipsebench.photometry.clean import FLAG_BITS, frame_faults
from eclipsebench.photometry.pipeline import photometry_tables

FAULTS = {"zero": "no_star", "constant": "constant", "negative": "negative"}


def _spoil(data: np.ndarray, kind: str) -> np.ndarray:
    return {"zero": np.zeros_like(data), "constant": np.full_like(data, 7.0),
            "negative": -data}[kind]


def _reasons(flags: np.ndarray) -> dict[str, int]:
    return {name: int(np.count_nonzero(flags & bit)) for name, bit in FLAG_BITS.items()
            if np.count_nonzero(flags & bit)}


def test_frame_faults_by_kind(bad):
    cube = bad.star_cube(4)
    cube[1] = 0.0
    cube[2] = 7.0
    cube[3] = -cube[3]
    assert frame_faults(cube).tolist() == [0, FLAG_BITS["no_star"], FLAG_BITS["constant"],
                                           FLAG_BITS["negative"]]
    cube[0, 3, 3] = np.nan  # a NaN pixel does not make a good frame faulty
    cube[1, 3, 3] = np.nan
    assert frame_faults(cube)[:2].tolist() == [0, FLAG_BITS["no_star"]]
    assert frame_faults(np.full((2, 4, 4), np.nan)).tolist() == [0, 0]


def _negated_by_the_median(frames: np.ndarray) -> np.ndarray:
    """The ``negative`` rule with every frame's median taken (frames all finite)."""
    flat = frames.reshape(len(frames), -1).astype(np.float64)
    hi, lo, med = flat.max(axis=1), flat.min(axis=1), np.median(flat, axis=1)
    return (hi != lo) & ((med - lo) > 2.0 * (hi - med))


def test_the_negated_rule_with_its_median_bounded_is_the_rule_with_every_median():
    """frame_faults takes a frame's median only where mean + SD could not clear it (issue 40);
    on frames at the rule's edge either way, and on star frames, it flags what the median
    of every frame flags."""
    rng = np.random.default_rng(40)
    frames = []
    for k in range(400):
        f = rng.normal(0.0, 1.0, size=(5, 5))
        # set the median near the rule's edge 3 med = 2 hi + lo, on one side or the other
        flat = np.sort(f.ravel())
        hi, lo = flat[-1] + 10.0 * rng.random(), flat[0] - 10.0 * rng.random()
        edge = (2.0 * hi + lo) / 3.0 + (k % 5 - 2) * 1e-12 * max(abs(hi), abs(lo))
        flat[12] = edge
        flat[0], flat[-1] = lo, hi
        flat[1:12] = np.minimum(flat[1:12], edge)
        flat[13:24] = np.maximum(flat[13:24], edge)
        frames.append(rng.permutation(flat).reshape(5, 5))
    star = rng.normal(35.0, 6.0, size=(200, 9, 9))
    star[:, 4, 4] += 2e4
    for cube in (np.array(frames), star, -star, star.astype(np.float32), -star.astype(np.float32)):
        want = np.where(_negated_by_the_median(cube), FLAG_BITS["negative"], 0)
        assert frame_faults(cube).tolist() == want.tolist()
    assert 0 < np.count_nonzero(_negated_by_the_median(np.array(frames))) < 400


def _table(folder):
    (_, table), = photometry_tables(folder, PhotometrySection())
    return table


@pytest.mark.parametrize("kind", sorted(FAULTS))
def test_synthetic_faulty_cube_flagged_alone(kind, tmp_path, bad):
    for name in ("clean", "spoilt"):
        for k in range(5):
            cube = bad.star_cube(64, seed=k)
            if name == "spoilt" and k == 2:
                cube = _spoil(cube, kind)
            bad.write_cube(tmp_path / name, cube, expid=k)
    clean, spoilt = _table(tmp_path / "clean"), _table(tmp_path / "spoilt")
    flags = np.asarray(spoilt["flag"])
    assert _reasons(flags[128:192]) == {"first_frame": 1, FAULTS[kind]: 64}
    others = np.r_[0:128, 192:320]
    assert _reasons(flags[others]) == _reasons(np.asarray(clean["flag"])[others])
    assert spoilt.meta["FLAGCNT"][FAULTS[kind]] == 64


@pytest.mark.shared_data
@pytest.mark.parametrize("kind", sorted(FAULTS))
def test_real_faulty_cube_does_not_flag_its_neighbours(kind, real_cubes, tmp_path):
    paths = real_cubes((0, 1, 2, 3, 4))
    clean = _table(paths[0].parent)
    with fits.open(paths[2], mode="update") as hdul:
        hdul[0].data = _spoil(hdul[0].data, kind)
    spoilt = _table(paths[0].parent)
    flags, ref = np.asarray(spoilt["flag"]), np.asarray(clean["flag"])
    assert _reasons(flags[128:192]) == {"first_frame": 1, FAULTS[kind]: 64}
    others = np.r_[0:128, 192:320]
    cr = FLAG_BITS["cosmic_ray"]
    # before: 48 good neighbours became cosmic_ray; now at most one decision differs
    assert abs(np.count_nonzero(flags[others] & cr) - np.count_nonzero(ref[others] & cr)) <= 1
    assert np.count_nonzero(flags[others] == 0) >= np.count_nonzero(ref[others] == 0) - 1
    same = (flags[others] == 0) & (ref[others] == 0)
    rel = np.asarray(spoilt["flux"])[others][same] / np.asarray(clean["flux"])[others][same] - 1
    assert np.count_nonzero(np.abs(rel) > 1e-6) <= 1
