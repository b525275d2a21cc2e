"""``eclipsebench stats`` end to end: CSV/ECSV in, JSON and the Table-4 text out."""

from __future__ import annotations

import json
import math

import pytest
from astropy.table import Table

from eclipsebench.cli import main

DEPTHS = {"bliss": [1800.0, 1900.0, 1850.0, 1700.0, 2000.0, 1950.0, 1875.0, 1825.0, 1750.0, 1925.0],
          "pld": [1840.0, 1890.0, 1800.0, 1760.0, 1990.0, 1900.0, 1870.0, 1800.0, 1790.0, 1950.0]}


def write_csv(path, rows):
    path.write_text("method,epoch,depth_ppm,error_ppm\n"
                    + "".join(f"{m},{e},{d},{s}\n" for m, e, d, s in rows))
    return path


def rows():
    return [(m, i + 1, d, 100.0) for m, ds in DEPTHS.items() for i, d in enumerate(ds)]


def test_json_from_csv(tmp_path, capsys):
    path = write_csv(tmp_path / "d.csv", rows())
    assert main(["stats", str(path), "--sigma-phot", "53", "--truth", "1875", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) >= {"methods", "anova", "ttest"}
    b = out["methods"]["bliss"]
    mean = sum(DEPTHS["bliss"]) / 10
    sd = math.sqrt(sum((x - mean) ** 2 for x in DEPTHS["bliss"]) / 9)
    assert b["D_mean"] == pytest.approx(mean)
    assert b["SD"] == pytest.approx(sd)
    assert b["r"] == pytest.approx(53 / sd)
    assert b["closest_match"] == "pld"
    assert out["ttest"]["p"]["bliss"]["pld"] == pytest.approx(out["ttest"]["p"]["pld"]["bliss"])
    assert out["anova"]["all"]["methods"] == ["bliss", "pld"]


def test_ecsv_and_text_table(tmp_path, capsys):
    t = Table(rows=rows(), names=["method", "epoch", "depth_ppm", "error_ppm"])
    path = tmp_path / "d.ecsv"
    t.write(path, format="ascii.ecsv")
    assert main(["stats", str(path), "--sigma-phot", "53", "--truth", "1875"]) == 0
    text = capsys.readouterr().out
    header = next(line for line in text.splitlines() if line.startswith("Method"))
    for col in ("D_mean", "sigma_mean", "SD", "sigma_orig", "f_dis", "sigma_tot", "R", "r",
                "Closest match", "RMSE", "bias", "a"):
        assert col in header
    assert "Average" in text and "ANOVA" in text


def test_methods_option(tmp_path, capsys):
    path = write_csv(tmp_path / "d.csv", rows())
    assert main(["stats", str(path), "--methods", "pld", "--json"]) == 0
    assert list(json.loads(capsys.readouterr().out)["methods"]) == ["pld"]


@pytest.mark.parametrize("content, message", [
    ("method,epoch,depth_ppm\nbliss,1,1800\nbliss,2,1900\n", "missing column(s) error_ppm"),
    ("method,epoch,depth_ppm,error_ppm\nbliss,1,1800,100\nbliss,2,nan,100\n", "NaN"),
    ("method,epoch,depth_ppm,error_ppm\nbliss,1,1800,100\nbliss,2,,100\n", "NaN or missing"),
    ("method,epoch,depth_ppm,error_ppm\nbliss,1,1800,100\npld,1,1900,100\npld,2,1850,90\n",
     "at least 2 epochs"),
    ("method,epoch,depth_ppm,error_ppm\nbliss,1,1800,100\nbliss,1,1900,100\n", "more than once"),
    ("method,epoch,depth_ppm,error_ppm\nbliss,1,1800,100\nbliss,2,1900,-1\n", "positive"),
])
def test_bad_tables_exit_2_with_one_line(tmp_path, capsys, content, message):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    assert main(["stats", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert str(path) in err and message in err


def test_missing_file_and_unknown_method(tmp_path, capsys):
    assert main(["stats", str(tmp_path / "nope.csv")]) == 2
    assert "no such file" in capsys.readouterr().err
    path = write_csv(tmp_path / "d.csv", rows())
    assert main(["stats", str(path), "--methods", "gp"]) == 2
    assert "--methods: gp" in capsys.readouterr().err
