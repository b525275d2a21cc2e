"""Results read back from their files equal the results that wrote them (issue 29).

Synthetic epochs (the conftest's test-only method): an MCMC fit (the ``mcmc_*``
keys and the chain), a result without its light curve, a joint fit, written
the run's way (``write_json`` without the command line's null-for-NaN). A
transit's round trip is in ``test_transit.py``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from eclipsebench import InputError, read_result
from eclipsebench.cli import main
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.fit.reduce import JointResult, reduce_epoch, reduce_joint
from eclipsebench.io.atomic import write_json


def _write_like_the_run(result, out):
    result.lightcurve_table().write(out.with_suffix(".lc.ecsv"), format="ascii.ecsv")
    write_json(out, result.to_dict())


def test_an_mcmc_result_comes_back_equal_with_its_chain(tmp_path, polygain, xo3_epoch):
    table = xo3_epoch["table"](seed=5)
    res = reduce_epoch(table, polygain.name, options=ReduceSection(
        phase="flat", sampler="mcmc", mcmc_walkers=12, mcmc_steps=200, prayer_bead_shifts=0))
    assert res.mcmc is not None
    out = tmp_path / "epoch_03.json"
    _write_like_the_run(res, out)
    res.write_chain(tmp_path / "epoch_03.chain.npz")
    back = read_result(out)
    assert back == res
    assert back.to_dict() == json.loads(out.read_text())
    np.testing.assert_array_equal(back.chain["samples"], res.chain["samples"])
    assert set(back.lightcurve) == set(res.lightcurve)


def test_a_result_without_its_light_curve_reads_but_cannot_plot(tmp_path, polygain, xo3_epoch):
    res = reduce_epoch(xo3_epoch["table"](seed=6), polygain.name,
                       options=ReduceSection(phase="linear", prayer_bead_shifts=0))
    out = tmp_path / "r.json"
    write_json(out, res.to_dict())
    back = read_result(out)
    assert back == res and back.lightcurve == {}
    with pytest.raises(InputError, match="no light curve"):
        back.plot()


def test_a_joint_result_comes_back_equal(tmp_path, polygain, xo3_epoch, capsys):
    tables = [xo3_epoch["table"](seed=11), xo3_epoch["table"](seed=12)]
    joint = reduce_joint(tables, polygain.name, options=ReduceSection(phase="quadratic"),
                         epochs=[1, 2])
    out = tmp_path / "joint.json"
    write_json(out, joint.to_dict())
    back = read_result(out)
    assert isinstance(back, JointResult) and back == joint
    assert f"JointResult: {polygain.name}, epoch 1, 2" in repr(joint)
    assert joint.to_dict()["bic_n_points"] == joint.n_points
    assert len(joint._repr_html_()) < 2000


def test_the_command_line_text_says_what_bic_was_computed_on(tmp_path, xo3_epoch, polygain,
                                                             capsys):
    path = tmp_path / "epoch_03.fits"
    xo3_epoch["table"](seed=21)[::2].write(path)
    assert main(["reduce", str(path), "--method", polygain.name, "--phase", "linear",
                 "--prayer-bead", "0", "--out", str(tmp_path / "r.json")]) == 0
    text = capsys.readouterr().out
    line = next(x for x in text.splitlines() if x.startswith("BIC / AIC"))
    n = json.loads((tmp_path / "r.json").read_text())["bic_n_points"]
    assert f"on {n} frames: comparable only with fits of the same points" in line


def test_an_old_or_damaged_result_is_one_line_naming_the_file(tmp_path, polygain, xo3_epoch):
    res = reduce_epoch(xo3_epoch["table"](seed=7), polygain.name,
                       options=ReduceSection(phase="flat", prayer_bead_shifts=0))
    old = {k: v for k, v in res.to_dict().items() if k not in ("params", "param_errors")}
    write_json(tmp_path / "old.json", old)
    with pytest.raises(InputError, match=r"old.json: not a result of this eclipsebench .*older"):
        read_result(tmp_path / "old.json")
    _write_like_the_run(res, tmp_path / "cut.json")
    (tmp_path / "cut.lc.ecsv").write_text("# %ECSV 1.0\n# ---\n# datatype: [oops\n")
    with pytest.raises(InputError, match="cut.lc.ecsv: not a readable light curve"):
        read_result(tmp_path / "cut.json")
