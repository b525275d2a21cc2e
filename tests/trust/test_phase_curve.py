"""Issue 36 point 4: twins of a whole phase curve, scored on its depth, amplitude and offset.

The built-in ``xo3b-phase-curve`` challenge (one whole orbit of the 2015 challenge's XO-3b,
a Pre AOR and 12-h Main AORs, physical noise), made sparse so that the test stays small:
cubes of 8 two-second frames every 16 minutes (about 2,300 frames over 3.2 days), of a star
9 times brighter than XO-3 (photon noise a third) so that so few frames detect the phase
variation (with XO-3's flux, BLISS's amplitude error was 466 ppm on a 323 ppm amplitude). Its
photometry is the "real" table; ``trust --event phase-curve`` makes twins with the real
fit's harmonics and scores each method's depth, phase amplitude and peak offset.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from astropy.table import Table

from eclipsebench.astro.phase_curves import harmonic_summary
from eclipsebench.cli import main
from eclipsebench.photometry.table import read_table, write_photometry
from eclipsebench.trust.layout import TrustLayout

SPARSE = ["observation.frames_per_cube=8", "observation.cube_interval_s=960.0",
          "simulation.subsamples=2", "simulation.flux_aperture_e=659214"]
TRUST = ["--event", "phase-curve", "--methods", "bliss", "--twins", "10", "--workers", "1",
         "--set", 'reduce.phase_curve_model="harmonic1"', "--quiet"]


@pytest.fixture(scope="module")
def phase_curve(tmp_path_factory):
    """The sparse phase curve's photometry table (several AORs)."""
    root = tmp_path_factory.mktemp("trust_pc")
    sets = [a for s in SPARSE for a in ("--set", s)]
    assert main(["simulate", "xo3b-phase-curve", "--out", str(root / "sim"), "--no-calibration",
                 "--quiet", "--workers", "1", *sets]) == 0
    assert main(["photometry", str(root / "sim"), "--out", str(root / "phot"), "--quiet"]) == 0
    return root, root / "phot" / "epoch_01.fits"


def _wrap_deg(angle):
    return (np.asarray(angle, float) + 180.0) % 360.0 - 180.0


@pytest.mark.slow
def test_twins_of_a_whole_phase_curve_score_its_depth_amplitude_and_offset(phase_curve,
                                                                            capsys):
    root, table = phase_curve
    assert len(np.unique(np.asarray(read_table(table)["aorkey"]))) >= 7   # Pre + Main AORs
    out = root / "trust"
    capsys.readouterr()
    assert main(["trust", str(table), "--out", str(out), *TRUST]) == 0
    stdout = capsys.readouterr().out
    answer = json.loads((out / "trust.json").read_text())
    layout = TrustLayout(out)
    real = json.loads(layout.real("bliss").read_text())
    assert real["event"] == "phase-curve" and real["phase"] == "harmonic1"

    # the truth: harmonic_summary of the real fit's harmonics (no ramp, no AOR offsets)
    summary = harmonic_summary(real["depth_ppm"] * 1e-6, (real["phase_a1"], real["phase_b1"]),
                               transit_phase_rad=math.radians(
                                   real["phase_curve_model"]["transit_phase_deg"]))
    truth_amp = answer["twin_phase_amplitude_ppm"]
    truth_off = answer["twin_phase_offset_deg"]
    assert truth_amp == pytest.approx(summary["phase_amplitude"] * 1e6, rel=1e-9)
    assert truth_off == pytest.approx(summary["phase_offset_deg"], abs=1e-9)
    assert answer["twin_depth_ppm"] == pytest.approx(real["depth_ppm"])
    assert answer["twins"]["event"] == "phase-curve"

    # each statistic as the twins' own results give it
    s = answer["methods"]["bliss"]
    twins = [json.loads(layout.twin_result("bliss", i).read_text()) for i in range(1, 11)]
    amp = np.array([t["phase_amplitude_ppm"] for t in twins])
    amp_err = np.array([t["phase_amplitude_err_ppm"] for t in twins])
    off = _wrap_deg([t["phase_offset_deg"] - truth_off for t in twins])
    depth = np.array([t["depth_ppm"] for t in twins])
    assert s["n_twins"] == s["phase_amplitude_n_twins"] == s["phase_offset_n_twins"] == 10
    assert s["bias_ppm"] == pytest.approx(np.mean(depth - answer["twin_depth_ppm"]))
    assert s["phase_amplitude_bias_ppm"] == pytest.approx(np.mean(amp - truth_amp))
    assert s["phase_amplitude_rmse_ppm"] == pytest.approx(np.sqrt(np.mean((amp - truth_amp)**2)))
    assert s["phase_amplitude_coverage_1sigma"] == np.mean(np.abs(amp - truth_amp) <= amp_err)
    assert s["phase_offset_rmse_deg"] == pytest.approx(np.sqrt(np.mean(off**2)))
    assert s["phase_amplitude_ppm"] == real["phase_amplitude_ppm"]
    assert s["phase_offset_err_deg"] == real["phase_offset_err_deg"]
    assert s["phase_amplitude_honest_err_ppm"] == pytest.approx(
        real["phase_amplitude_err_ppm"] * max(1.0, s["phase_amplitude_z_rms"]))

    # sane: the phase variation is found in the twins, and its errors are about honest
    assert s["phase_amplitude_rmse_ppm"] < truth_amp, s
    assert abs(np.median(amp) - truth_amp) < 3 * s["phase_amplitude_rmse_ppm"]
    assert s["phase_offset_rmse_deg"] < 60.0, s
    for key in ("z_rms", "phase_amplitude_z_rms", "phase_offset_z_rms"):
        assert 1 / 3 < s[key] < 3, (key, s[key])
    for key in ("phase_amplitude_coverage_2sigma", "phase_offset_coverage_2sigma"):
        assert s[key] >= 0.5, (key, s[key])

    # the same numbers in trust.ecsv, on stdout and on the page
    ecsv = Table.read(out / "trust.ecsv", format="ascii.ecsv")
    assert ecsv["phase_amplitude_rmse_ppm"][0] == pytest.approx(s["phase_amplitude_rmse_ppm"])
    assert str(ecsv["phase_amplitude_rmse_ppm"].unit) == "ppm"
    assert str(ecsv["phase_offset_bias_deg"].unit) == "deg"
    assert ecsv.meta["twin_phase_offset_deg"] == pytest.approx(truth_off)
    assert f"phase amplitude, against the injected {truth_amp:.1f} ppm:" in stdout
    assert f"phase offset, against the injected {truth_off:.1f} deg:" in stdout
    assert f"{s['phase_offset_rmse_deg']:.1f}" in stdout
    page = (out / "report" / "index.html").read_text()
    assert "The phase curve" in page and f"{s['phase_amplitude_rmse_ppm']:.1f}" in page


@pytest.mark.parametrize("case", ["one AOR", "no aorkey"])
def test_a_phase_curve_needs_a_table_of_several_named_aors(phase_curve, tmp_path, capsys, case):
    _, table = phase_curve
    full = read_table(table)
    if case == "one AOR":
        keys = np.asarray(full["aorkey"])
        path = tmp_path / "one_aor.fits"
        write_photometry(full[keys == keys[-1]], path)
        expected = "column aorkey: one AOR"
    else:   # another pipeline's table: its AORs would only be guessed from gaps
        good = np.asarray(full["flag"]) == 0
        path = tmp_path / "other.csv"
        Table({c: np.asarray(full[c])[good] for c in ("time_bmjd", "flux", "flux_err", "x", "y")}
              ).write(path, format="ascii.csv")
        expected = "no column aorkey"
    out = tmp_path / "trust"
    capsys.readouterr()
    assert main(["trust", str(path), "--out", str(out), "--system", "XO-3b (2015 challenge)",
                 *TRUST]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and expected in err and str(path) in err, err
    assert not out.exists()
