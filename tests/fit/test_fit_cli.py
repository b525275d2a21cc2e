"""``eclipsebench reduce`` end to end: files written, JSON keys, one-line errors."""

from __future__ import annotations

import json

import pytest
from astropy.table import Table

from eclipsebench.cli import main


@pytest.fixture
def table_file(tmp_path, xo3_epoch):
    path = tmp_path / "epoch_03.fits"
    xo3_epoch["table"](seed=21)[::2].write(path)
    return path


def test_reduce_writes_result_and_lightcurve(tmp_path, table_file, polygain, capsys, kit):
    out = tmp_path / "res" / "r.json"
    code = main(["reduce", str(table_file), "--method", polygain.name, "--phase", "quadratic",
                 "--prayer-bead", "3", "--out", str(out), "--plot", str(tmp_path / "lc.png"),
                 "--json"])
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    saved = json.loads(out.read_text())
    for key in ("method", "depth_ppm", "depth_err_ppm", "t_ecl_bmjd", "bic", "aic", "rms_ppm",
                "beta_red", "n_frames", "epoch"):
        assert key in saved
    assert saved["depth_ppm"] == printed["depth_ppm"]
    assert abs(saved["depth_ppm"] - kit.TRUE_DEPTH * 1e6) < 3 * saved["depth_err_ppm"]
    lc = Table.read(tmp_path / "res" / "r.lc.ecsv", format="ascii.ecsv")
    assert lc.colnames == ["time_bmjd", "flux_corrected", "astro_model", "residual", "flux_err",
                           "systematics_model"]   # the last two since issue 29
    assert len(lc) == saved["n_points"]
    assert (tmp_path / "lc.png").read_bytes()[:4] == b"\x89PNG"


def test_mcmc_writes_the_chain_and_a_corner_plot(tmp_path, table_file, polygain, capsys):
    """Issue 14 point 3: asymmetric posterior errors, the chain beside the result, a corner plot."""
    import numpy as np
    out = tmp_path / "r.json"
    code = main(["reduce", str(table_file), "--method", polygain.name, "--phase", "flat",
                 "--sampler", "mcmc", "--walkers", "12", "--steps", "300", "--prayer-bead", "0",
                 "--out", str(out), "--plot", str(tmp_path / "lc.png")])
    assert code == 0
    text = capsys.readouterr().out
    saved = json.loads(out.read_text())
    assert "posterior" in text and saved["chain_file"] == str(tmp_path / "r.chain.npz")
    chain = np.load(tmp_path / "r.chain.npz")
    assert list(chain["names"][:2]) == ["depth", "t_ecl_bmjd"]
    depth = chain["samples"][:, 0] * 1e6
    lo, med, hi = np.percentile(depth, [15.865525393145708, 50, 84.13447460685429])
    assert saved["mcmc_depth_err_lo_ppm"] == pytest.approx(med - lo)
    assert saved["mcmc_depth_err_hi_ppm"] == pytest.approx(hi - med)
    if saved["depth_err_method"] == "mcmc":
        assert saved["depth_err_lo_ppm"] == pytest.approx(med - lo)
    else:
        assert saved["depth_err_lo_ppm"] == saved["depth_err_hi_ppm"] == saved["depth_err_ppm"]
    assert (tmp_path / "lc.corner.png").read_bytes()[:4] == b"\x89PNG"


def test_default_output_beside_the_table_and_text(table_file, polygain, capsys):
    code = main(["reduce", str(table_file), "--method", polygain.name, "--prayer-bead", "0",
                 "--compare-phases", "--phase", "linear"])
    assert code == 0
    text = capsys.readouterr().out
    assert "depth" in text and "BIC picks" in text
    saved = json.loads((table_file.parent / f"epoch_03.{polygain.name}.json").read_text())
    assert saved["phase"] == "linear"
    assert {m["phase"] for m in saved["phase_models"]["models"]} == {"flat", "linear",
                                                                     "quadratic", "sinusoid"}
    assert (table_file.parent / f"epoch_03.{polygain.name}.lc.ecsv").is_file()


def test_errors_are_one_line_exit_2(tmp_path, table_file, polygain, capsys, xo3_epoch):
    assert main(["reduce", str(tmp_path / "nope.fits"), "--method", polygain.name]) == 2
    err = capsys.readouterr().err
    assert "no such photometry table" in err and err.count("\n") == 1
    assert main(["reduce", str(table_file), "--method", "nonesuch"]) == 2
    assert "unknown method" in capsys.readouterr().err
    early = tmp_path / "early.fits"
    t = xo3_epoch["table"]()
    t[t["time_bmjd"] < xo3_epoch["t_pred"] - 0.1].write(early)
    assert main(["reduce", str(early), "--method", polygain.name]) == 2
    assert "outside the time span" in capsys.readouterr().err
    assert main(["reduce", str(table_file), "--method", polygain.name, "--option", "k"]) == 2
    assert "--option" in capsys.readouterr().err


def test_several_tables_are_fitted_jointly(tmp_path, xo3_epoch, polygain, capsys):
    """Issue 17 point 4: one depth over epochs, beside the epochs fitted alone."""
    folder = tmp_path / "phot"
    folder.mkdir()
    for i, seed in enumerate((31, 32, 33), start=1):
        t = xo3_epoch["table"](seed=seed, noise=5e-4)[::2]
        t.meta["EPOCH"] = i
        t.write(folder / f"epoch_{i:02d}.fits")
    code = main(["reduce", str(folder), "--method", polygain.name, "--phase", "quadratic",
                 "--prayer-bead", "0", "--json"])
    assert code == 0
    res = json.loads(capsys.readouterr().out)
    assert res["joint"] and res["epochs"] == [1, 2, 3] and len(res["per_epoch"]) == 3
    assert (folder / f"joint.{polygain.name}.json").is_file()
    alone = [e["depth_alone_err_ppm"] for e in res["per_epoch"]]
    assert res["depth_combined_err_ppm"] == pytest.approx(sum(a**-2 for a in alone) ** -0.5)
    # one depth from three epochs: about the combination of the three errors
    assert 0.7 < res["depth_err_ppm"] / res["depth_combined_err_ppm"] < 1.4
    assert abs(res["depth_ppm"] - 1875.0) < 3 * res["depth_err_ppm"]
    assert main(["reduce", str(folder), "--method", polygain.name, "--sampler", "mcmc"]) == 2
    assert "applies to one table" in capsys.readouterr().err


def test_text_summary_with_no_beta_red():
    """A fit of too few points has beta_red null: the text summary says n/a, not a crash."""
    from eclipsebench.commands.reduce import format_text
    result = {"method": "m", "epoch": 1, "phase": "flat", "sampler": "leastsq",
              "depth_ppm": 1800.0, "depth_err_ppm": 90.0, "depth_err_method": "jacobian",
              "t_ecl_bmjd": 57000.0, "t_ecl_err_d": 1e-3, "rms_ppm": 900.0, "beta_red": None,
              "chi2_red": 1.0, "bic": 1.0, "aic": 1.0, "k": 3, "result_file": "r.json",
              "lightcurve_file": "r.lc.ecsv"}
    assert "beta_red n/a" in format_text(result)
