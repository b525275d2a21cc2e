"""The 30 real channel-1 (3.6 um) 0.1 s subarray cubes of HD 209458 (AOR 41629440, issue 16).

Photometry reads every frame or flags it with a reason; per cube, the median
centroid, noise pixels and flux; and the noise pixels of stars rendered with the
real channel-1 PRFs (``prf/warm_2014_ch1``, ``prf/warm_2015_ch1``) at the
measured centroids are within 5% of the real frames' (acceptance).
"""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits

from eclipsebench.cli import main
from eclipsebench.instrument.prf import IrsaPRF
from eclipsebench.photometry.clean import FLAG_BITS
from eclipsebench.photometry.estimators import noise_pixels
from eclipsebench.photometry.table import read_photometry

pytestmark = pytest.mark.shared_data

FOLDER = "real_hd209458_ch1_0p1s_41629440"


@pytest.fixture(scope="module")
def real_ch1(tmp_path_factory, shared_irac):
    folder = shared_irac / FOLDER
    out = tmp_path_factory.mktemp("ch1") / "hd209458.fits"
    assert main(["photometry", str(folder), "--out", str(out), "--quiet"]) == 0
    return folder, read_photometry(out)


def per_cube_medians(table) -> dict[str, np.ndarray]:
    """Median x, y, noise pixels and flux of the good frames of each cube (EXPID order)."""
    good = np.asarray(table["flag"]) == 0
    expid = np.asarray(table["expid"])
    cubes = np.unique(expid)
    out = {"expid": cubes}
    for name in ("x", "y", "noise_pixels", "flux"):
        values = np.asarray(table[name], float)
        out[name] = np.array([np.median(values[good & (expid == e)]) for e in cubes])
    return out


def test_every_frame_is_read_or_flagged_with_a_reason(real_ch1):
    folder, table = real_ch1
    files = sorted(folder.glob("*_bcd.fits"))
    assert len(files) == 30
    headers = [fits.getheader(f) for f in files]
    assert all(h["CHNLNUM"] == 1 and h["FRAMTIME"] == 0.1 and h["AFOWLNUM"] == 2
               and h["AWAITPER"] == 6 for h in headers)
    assert len(table) == sum(h["NAXIS3"] for h in headers) == 1920
    assert table.meta["CHANNEL"] == 1 and table.meta["AORKEYS"] == [41629440]
    flag = np.asarray(table["flag"])
    known = np.bitwise_or.reduce(list(FLAG_BITS.values()))
    assert np.all((flag & ~known) == 0)
    first = np.asarray(table["frame"]) == 0
    assert np.all(flag[first] & FLAG_BITS["first_frame"])
    assert np.count_nonzero(flag == 0) >= 1850
    good = flag == 0
    for name in ("x", "y", "flux", "flux_err", "background", "noise_pixels"):
        assert np.all(np.isfinite(table[name][good])), name
    # frames 0.1 s apart inside a cube (FRAMTIME; the reader's rule), cubes 8.3-8.5 s apart
    t = np.asarray(table["time_bmjd"]) * 86400.0
    frame = np.asarray(table["frame"])
    inside = np.diff(t)[frame[1:] > 0]
    assert np.allclose(inside, 0.1, atol=1e-4)
    assert np.all((np.diff(t[frame == 0]) > 8.2) & (np.diff(t[frame == 0]) < 8.6))


def test_per_cube_centroid_noise_pixels_and_flux(real_ch1):
    _, table = real_ch1
    m = per_cube_medians(table)
    assert m["expid"].tolist() == list(range(30))
    # the star sits near the lower-left corner of pixel (15, 15): (14.88, 14.68) on average
    assert np.all((m["x"] > 14.7) & (m["x"] < 15.05)), m["x"]
    assert np.all((m["y"] > 14.55) & (m["y"] < 14.85)), m["y"]
    # a broad image at the pixel corner, and a steady star: 48,700 e in 2.25 px every 0.08 s
    assert np.all((m["noise_pixels"] > 6.8) & (m["noise_pixels"] < 8.0)), m["noise_pixels"]
    assert np.all(np.abs(m["flux"] / np.median(m["flux"]) - 1.0) < 0.02), m["flux"]
    assert 46000 < np.median(m["flux"]) < 51000


@pytest.mark.parametrize("prf_set", ["warm_2014_ch1", "warm_2015_ch1"])
def test_real_channel1_prfs_give_the_real_noise_pixels_within_5_percent(real_ch1, shared_irac,
                                                                         prf_set):
    _, table = real_ch1
    good = np.asarray(table["flag"]) == 0
    x, y = np.asarray(table["x"])[good], np.asarray(table["y"])[good]
    prf = IrsaPRF.from_files(shared_irac / "prf" / prf_set)
    assert prf.channel == 1 and prf.path.name.endswith("col025_row233.fits")
    # stars rendered (noiseless, static) at the measured centroids of every 8th good frame
    rendered = noise_pixels(prf.render(x[::8], y[::8]))
    real = float(np.median(np.asarray(table["noise_pixels"])[good]))
    ratio = float(np.median(rendered)) / real
    assert abs(ratio - 1.0) < 0.05, (prf_set, real, float(np.median(rendered)))
