"""``eclipsebench stats``: ensemble statistics of a depth table (Tables 3 and 4)."""

from __future__ import annotations

import argparse

from ..report.tables import format_text_table
from ..stats.depth_table import read_depth_table
from ..stats.summary import summarize
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
    p.add_argument("--bootstrap", type=positive_int(minimum=0), default=2000, metavar="N",
                   help="bootstrap resamples for the intervals on R, r and a (0: none)")


def run(args: argparse.Namespace) -> dict:
    table = read_depth_table(args.depths)
    return summarize(table, sigma_phot_ppm=args.sigma_phot, truth_ppm=args.truth,
                     methods=args.methods, seed=args.seed, n_bootstrap=args.bootstrap)


def format_text(result: dict) -> str:
    return format_text_table(result)
