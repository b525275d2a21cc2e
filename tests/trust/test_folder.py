"""Issue 37: a trust folder records its inputs by content, is one kind of run, refuses cleanly.

A rerun into the same ``--out`` whose table, planet or pixel map changed under
the same path or name used to return the old answer with exit 0; now it is
refused in one line that says what changed and how to go on. A refused first
run leaves the folder as it found it, so the corrected command goes on.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from astropy.table import Table

import eclipsebench.trust.run as trust_run
from eclipsebench.cli import main
from eclipsebench.photometry.table import read_table, write_photometry

from .test_trust import FAST, small_table  # noqa: F401  (small_table: a module fixture)


def _code(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def _listing(root) -> dict[str, int]:
    """Every file under ``root`` with its modification time (ns)."""
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in sorted(root.rglob("*"))}


@pytest.fixture(scope="module")
def finished(small_table, tmp_path_factory):  # noqa: F811
    """A finished trust run of a copy of the small table, after a refused first attempt into
    the same folder: ``(table copy, folder, what the refused attempt printed and left)``."""
    root = tmp_path_factory.mktemp("trust_inputs")
    table, out = root / "real.fits", root / "trust"
    shutil.copyfile(small_table, table)
    refused = [_code(["trust", str(table), "--out", str(out), "--methods", "kr-pmap",
                      "--sampler", "leastsq", "--twins", "10", "--quiet", "--workers", "1"]),
               out.exists()]
    assert main(["trust", str(table), "--out", str(out), "--workers", "1"] + FAST) == 0
    return table, out, refused


def test_a_refused_trust_leaves_the_folder_so_the_corrected_command_goes_on(finished):
    _, out, (code, left) = finished
    # KR/Pmap alone, without a map: no method could reduce the table (exit 2); nothing left ...
    assert code == 2 and not left
    # ... and the corrected command in the same --out ran (the fixture) and answered
    assert json.loads((out / "trust.json").read_text())["n_twins"] == 10


def test_a_table_replaced_at_the_same_path_is_refused_not_answered_from_the_old(finished,
                                                                               tmp_path, capsys):
    table, out, _ = finished
    before = (out / "trust.json").read_bytes()
    kept = tmp_path / "kept.fits"
    shutil.copyfile(table, kept)
    redone = read_table(table)
    redone["flux"] = redone["flux"] * (1.0 + 1e-3 * np.sin(np.arange(len(redone))))
    try:
        table.unlink()
        write_photometry(redone, table)            # photometry redone, at the same path
        assert _code(["trust", str(table), "--out", str(out)] + FAST) == 2
        err = _one_line(capsys)
        assert f"the table {table}" in err and "changed since this folder was made" in err
        assert "another --out" in err
        # growing the twins is refused too: it would score new twins against the old recipe
        more = [a if a != "10" else "12" for a in FAST]
        assert _code(["trust", str(table), "--out", str(out)] + more) == 2
        assert "changed since" in _one_line(capsys)
        assert (out / "trust.json").read_bytes() == before
    finally:
        shutil.copyfile(kept, table)
    # the table as it was: the folder resumes (nothing to redo) and grows
    assert main(["trust", str(table), "--out", str(out), "--json"] + FAST) == 0
    assert (out / "trust.json").read_bytes() == before
    capsys.readouterr()


def test_run_into_a_trust_folder_is_refused_before_any_write(finished, capsys):
    _, out, _ = finished
    before = _listing(out)
    assert _code(["run", "--out", str(out), "--quiet", "--workers", "1"]) == 2
    err = _one_line(capsys)
    assert "'eclipsebench trust'" in err and "another --out" in err
    assert _listing(out) == before


def _interrupted(monkeypatch, argv: list[str]) -> None:
    """``argv`` stopped by Ctrl-C as its first task starts: the folder holds its marker and
    settings, as after any interrupted or finished run."""
    def stop(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(trust_run, "run_tasks", stop)
        assert _code(argv) == 130


def _catalogue(path, ecc: float) -> None:
    path.write_text(f'["my-b"]\nperiod_days = 3.1915239\nt_transit_bjd = 2454449.86816\n'
                    f'ecc = {ecc}\nomega_deg = 346.0\ninc_deg = 84.20\na_rs = 7.07\n'
                    'rp_rs = 0.0906\nteff_star_k = 6429.0\nr_star_rsun = 1.377\n')


def test_a_catalogue_planet_changed_under_the_same_name_is_refused(small_table, tmp_path,  # noqa: F811
                                                                   monkeypatch, capsys):
    cat, out = tmp_path / "cat.toml", tmp_path / "t"
    _catalogue(cat, 0.2884)
    argv = ["trust", str(small_table), "--out", str(out), "--catalogue", str(cat),
            "--system", "my-b"] + FAST
    _interrupted(monkeypatch, argv)
    capsys.readouterr()
    _catalogue(cat, 0.25)                      # edited in place, same name
    assert _code(argv) == 2
    err = _one_line(capsys)
    assert "the elements of planet 'my-b' changed since this folder was made" in err


def test_planet_options_with_the_same_name_and_other_elements_are_refused(small_table,  # noqa: F811
                                                                          tmp_path, monkeypatch,
                                                                          capsys):
    out = tmp_path / "t"
    values = {"name": "my-b", "period_days": 3.1915239, "t_transit_bjd": 2454449.86816,
              "ecc": 0.2884, "omega_deg": 346.0, "inc_deg": 84.2, "a_rs": 7.07,
              "rp_rs": 0.0906, "teff_star_k": 6429.0}

    def argv(**changes):
        planet = [a for k, v in {**values, **changes}.items() for a in ("--planet", f"{k}={v}")]
        return ["trust", str(small_table), "--out", str(out), *planet] + FAST

    _interrupted(monkeypatch, argv())
    capsys.readouterr()
    assert _code(argv(a_rs=7.2)) == 2
    assert "the elements of planet 'my-b' changed" in _one_line(capsys)


def _calibration(path, scale: float) -> None:
    """A KR/Pmap calibration-star table (as the simulator writes) at ``path``."""
    rng = np.random.default_rng(5)
    n = 400
    Table({"x": 15.0 + 0.2 * rng.standard_normal(n), "y": 15.0 + 0.2 * rng.standard_normal(n),
           "noise_pixels": np.full(n, 4.0), "flux": scale * (1 + 0.01 * rng.standard_normal(n)),
           "flux_err": np.full(n, 0.01)}).write(path, overwrite=True)


def test_a_pixel_map_replaced_at_the_same_path_is_refused(small_table, tmp_path,  # noqa: F811
                                                          monkeypatch, capsys):
    pmap, out = tmp_path / "pmap_calibration.fits", tmp_path / "t"
    _calibration(pmap, 1.0)
    argv = ["trust", str(small_table), "--out", str(out), "--pmap", str(pmap)] + FAST
    _interrupted(monkeypatch, argv)
    capsys.readouterr()
    _calibration(pmap, 1.01)
    assert _code(argv) == 2
    assert f"the pixel map {pmap} changed since this folder was made" in _one_line(capsys)


def test_the_estimate_of_what_trust_writes_is_checked_against_the_free_space(
        small_table, tmp_path, monkeypatch, capsys):  # noqa: F811
    import shutil as shutil_module
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    out = tmp_path / "t"
    monkeypatch.setattr(shutil_module, "disk_usage", lambda path: usage(10**9, 10**9 - 10**6,
                                                                        10**6))
    # ten twins of a 0.7 MB table and their reductions: about 9 MB, 1 MB free
    assert _code(["trust", str(small_table), "--out", str(out)] + FAST) == 3
    err = _one_line(capsys)
    assert str(out) in err and "free" in err and "10 twin tables" in err
    assert not out.exists()
