"""Issue 38, item 3: friendly refusals shared by ``trust`` and ``reduce``.

A table missing several columns is refused with all of them named in one
line and the command that makes a complete table; an unknown method name
gets a "did you mean" (one helper, ``decorrelate.base.unknown_methods``).
"""

from __future__ import annotations

import pytest

from eclipsebench.cli import main

from ..conftest import simulate_eclipse_epoch


def _run(argv: list[str], capsys) -> tuple[int, str]:
    try:
        code = main(argv)
    except SystemExit as exc:   # argparse's usage errors
        code = int(exc.code)
    return code, capsys.readouterr().err


def _partial_table(path):
    """Another pipeline's table with a time and a flux only (no error, no centroids)."""
    path.write_text("t,f\n" + "".join(f"{57000.0 + i / 1440:.6f},{1.0 + 1e-4 * i}\n"
                                      for i in range(200)))
    return path


@pytest.mark.parametrize("command", ["reduce", "trust"])
def test_a_table_missing_several_columns_names_them_all_and_the_photometry_command(
        tmp_path, capsys, command):
    table = _partial_table(tmp_path / "lc.csv")
    out = tmp_path / "out"
    args = ([command, str(table), "--system", "XO-3b"]
            + (["--method", "bliss"] if command == "reduce" else ["--out", str(out)]))
    code, err = _run(args, capsys)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert str(table) in err
    for column in ("time_bmjd", "flux", "flux_err", "x", "y"):   # all at once, not the first
        assert column in err.split("(the table has")[0], (column, err)
    assert "'eclipsebench photometry'" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lc.csv"]


@pytest.mark.parametrize("args, option, wrong, meant", [
    (["reduce", "{table}", "--method", "blis", "--system", "XO-3b"], "--method", "blis",
     "bliss"),
    (["trust", "{table}", "--out", "{out}", "--methods", "kr-dat,bliss,pdl", "--system", "XO-3b"],
     "--methods", "kr-dat", "kr-data"),
])
def test_an_unknown_method_gets_a_did_you_mean_in_its_one_line(tmp_path, capsys, args, option,
                                                               wrong, meant):
    table = _partial_table(tmp_path / "lc.csv")
    argv = [a.format(table=table, out=tmp_path / "out") for a in args]
    code, err = _run(argv, capsys)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert f"{option}: unknown method" in err
    assert f"'{wrong}' (did you mean {meant}" in err, err   # the closest first
    if option == "--methods":   # every unknown name at once, each with its nearest
        assert "'pdl' (did you mean pld?)" in err and "'bliss'" not in err.split("; known")[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lc.csv"]


def test_a_name_near_no_method_gets_the_list_only():
    from eclipsebench.decorrelate.base import unknown_methods

    problem = unknown_methods(["zzz"])
    assert problem.startswith("unknown method 'zzz'; known: bliss") and "did you mean" not in problem
    assert unknown_methods(["bliss", "pld"]) is None


def test_a_table_given_as_photometry_s_but_short_of_columns_names_them_all():
    from astropy.table import Table

    from eclipsebench.errors import InputError
    from eclipsebench.trust.observation import observation_from_table

    table = Table({"time_bmjd": [57000.0, 57000.1], "flux": [1.0, 1.0], "x": [15.0, 15.0],
                   "y": [15.0, 15.0]})
    with pytest.raises(InputError) as err:
        observation_from_table(table, "lc.fits")
    text = str(err.value)
    assert "missing column(s) aorkey, expid, frame, background, flag" in text, text
    assert "'eclipsebench photometry'" in text


@pytest.fixture(scope="module")
def two_frame_cubes_table(tmp_path_factory):
    """A simulated observation of 111 cubes of 2 frames, measured: photometry flags each
    cube's first frame, so every cube holds one good frame (110 good frames in all, enough
    for the count of good frames, too few per cube for the twins' calibration)."""
    root = tmp_path_factory.mktemp("two_frame_cubes")
    return simulate_eclipse_epoch(root, ["observation.pre_cubes=1",
                                         "observation.frames_per_cube=2",
                                         "observation.main_cubes=110",
                                         "observation.cube_interval_s=220.0",
                                         "simulation.subsamples=2"], 0.12)


def _says_cubes_need_two_good_frames(text: str, table) -> None:
    assert str(table) in text, text
    assert "0 of 111 cubes (aorkey, expid) hold 2 or more good frames" in text, text
    assert "expected at least 2 such cubes" in text and "calibrated" in text, text


def test_a_table_of_two_frame_cubes_is_refused_in_one_line_before_any_file(
        two_frame_cubes_table, tmp_path, capsys):
    """It was a task failure ('recipe: ValueError: need at least one array to concatenate',
    exit 1) after the real reduction had written to the folder."""
    out = tmp_path / "out"
    code, err = _run(["trust", str(two_frame_cubes_table), "--out", str(out), "--twins", "10",
                      "--sampler", "leastsq", "--methods", "bliss", "--workers", "1"], capsys)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    _says_cubes_need_two_good_frames(err, two_frame_cubes_table)
    assert not out.exists()


def test_eb_trust_refuses_a_table_of_two_frame_cubes(two_frame_cubes_table, tmp_path):
    import eclipsebench as eb

    out = tmp_path / "out"
    with pytest.raises(eb.InputError) as err:
        eb.trust(two_frame_cubes_table, out, twins=10, methods=["bliss"], sampler="leastsq",
                 workers=1)
    _says_cubes_need_two_good_frames(str(err.value), two_frame_cubes_table)
    assert not out.exists()
