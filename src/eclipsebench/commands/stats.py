"""``eclipsebench stats``: ensemble statistics of a depth table (Tables 3 and 4)."""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

from ..errors import DataError
from ..limits import MAX_BOOTSTRAP
from .options import method_list, nonnegative_float, positive_float, positive_int

NAME = "stats"
HELP = ("Per-method eclipse-depth statistics (weighted mean, f_dis, repeatability, reliability, "
        "accuracy), closest matches, t-tests and ANOVA from a CSV/ECSV depth table "
        "(Ingalls et al. 2016, Sections 3.2-3.5).")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("depths", metavar="DEPTHS",
                   help="CSV or ECSV table with columns method, epoch, depth_ppm, error_ppm")
    p.add_argument("--sigma-phot", type=positive_float(), metavar="PPM",
                   help="photon-noise limit of one depth (gives reliability r and accuracy a)")
    p.add_argument("--truth", type=nonnegative_float(), metavar="PPM",
                   help="true eclipse depth (gives RMSE, bias, accuracy a and coverage)")
    p.add_argument("--methods", type=method_list, metavar="A,B,...",
                   help="only these methods (also for the t-tests and ANOVA)")
    p.add_argument("--seed", type=positive_int(minimum=0), default=0, metavar="N",
                   help="seed of the bootstrap resampling")
    p.add_argument("--bootstrap", type=positive_int(minimum=0, maximum=MAX_BOOTSTRAP),
                   default=2000, metavar="N",
                   help="bootstrap resamples for the intervals on R, r and a (0: none)")


_BOMS = {b"\xef\xbb\xbf": "UTF-8", b"\xff\xfe": "UTF-16", b"\xfe\xff": "UTF-16"}


def _check_text(path: Path) -> None:
    """Refuse a byte-order mark (it glues itself to the first column's name)."""
    try:
        with path.open("rb") as fh:
            head = fh.read(4)
    except OSError:
        return  # read_depth_table names the file and the problem
    for bom, encoding in _BOMS.items():
        if head.startswith(bom):
            raise DataError(path, f"starts with a {encoding} byte-order mark; expected plain "
                                  "UTF-8 text without one (save it as 'CSV UTF-8' without BOM)")


def _check_methods(path: Path) -> None:
    """Refuse a row whose method name is blank (astropy would read it as masked '--')."""
    import numpy as np
    from astropy.table import Table

    try:
        if path.suffix.lower() == ".ecsv":
            column = Table.read(path, format="ascii.ecsv")["method"]
            mask = np.asarray(getattr(column, "mask", np.zeros(len(column), bool)), bool)
            names = ["" if m else str(v) for v, m in zip(column, mask, strict=True)]
        else:
            with path.open(newline="", encoding="utf-8") as fh:
                rows = list(csv.reader(line for line in fh if line.strip()))
            header = [h.strip() for h in rows[0]]
            col = header.index("method")
            names = [r[col] if col < len(r) else "" for r in rows[1:]]
    except Exception:
        return  # read_depth_table names the file and the problem
    for row, name in enumerate(names, start=1):
        if not name.strip():
            raise DataError(path, f"column 'method': blank method name in row {row} "
                                  "(expected a method name in every row)")


def run(args: argparse.Namespace) -> dict:
    from ..photometry.table import check_text_table

    path = Path(args.depths)
    _check_text(path)
    if path.is_file():   # rows counted and ECSV metadata checked before any read
        check_text_table(path, "ecsv" if path.suffix.lower() == ".ecsv" else "csv")
    _check_methods(path)
    from ..stats.depth_table import read_depth_table
    from ..stats.summary import summarize

    table = read_depth_table(args.depths)
    return summarize(table, sigma_phot_ppm=args.sigma_phot, truth_ppm=args.truth,
                     methods=args.methods, seed=args.seed, n_bootstrap=args.bootstrap)


def format_text(result: dict) -> str:
    from ..report.tables import format_text_table  # astropy: not at CLI start

    return format_text_table(result)
