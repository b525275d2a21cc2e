"""``eclipsebench photometry``: BCD cubes to per-epoch photometry tables."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..config import load_config
from ..errors import InputError
from .options import check_output_path, positive_float, positive_int

# numpy, astropy and the stage's modules are imported where the work is done, so the
# command line's parser stays light (tests/foundation/test_cli_startup.py).

NAME = "photometry"
HELP = ("Measure IRAC BCD cubes (archive or simulated): centroids, noise pixels, apertures, "
        "background, stamps; one FITS table per epoch (Ingalls et al. 2016, Section 3.1).")
CENTROIDS = ("col", "gauss", "gauss-fixed", "lsq-asym")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("input_dir", metavar="INPUT_DIR",
                   help="folder of SPITZER_I<ch>_*_bcd.fits files (one AOR, or an archive-style "
                        "or simulated tree of several)")
    p.add_argument("--out", required=True, metavar="TABLE_OR_DIR",
                   help="output .fits table (one epoch) or folder (gets epoch_NN.fits per epoch)")
    p.add_argument("--centroid", choices=CENTROIDS, default=None,
                   help="centroid that places the apertures and fills x, y "
                        "(default: photometry.centroid of the configuration, 'col')")
    p.add_argument("--radius", type=positive_float(), default=None, metavar="R",
                   help="aperture radius (px) of the flux and flux_err columns (default 2.25)")
    p.add_argument("--radii", type=positive_float(), nargs="+", default=None, metavar="R",
                   help="fixed aperture radii (px) for the flux_rXpXX columns "
                        "(default 1.5 to 4.0 in 0.25 px steps)")
    p.add_argument("--channel", type=positive_int(), default=None, choices=(1, 2, 3, 4),
                   help="IRAC channel when INPUT_DIR holds several")
    p.add_argument("--config", default=None, metavar="CONFIG",
                   help="configuration file (TOML) whose [photometry] section is used")
    p.add_argument("--set", dest="overrides", action="append", default=[],
                   metavar="photometry.KEY=VALUE",
                   help="override one configuration value (repeatable), e.g. "
                        "--set photometry.background=median")


def _options(args: argparse.Namespace):
    from ..photometry.pipeline import replace_options

    opt = load_config(args.config, args.overrides).photometry
    changes = {}
    if args.centroid is not None:
        changes["centroid"] = args.centroid
    if args.radius is not None:
        changes["radius_px"] = float(args.radius)
    if args.radii is not None:
        changes["radii_px"] = tuple(float(r) for r in args.radii)
    return replace_options(opt, **changes) if changes else opt


def run(args: argparse.Namespace) -> dict:
    import numpy as np

    from ..photometry.clean import flag_counts
    from ..photometry.pipeline import photometry_tables
    from ..photometry.table import write_photometry
    from ..progress import progress

    out = Path(args.out)
    as_file = out.suffix.lower() in (".fits", ".fit", ".fts")
    check_output_path(out, "--out", "file" if as_file else "folder")
    options = _options(args)
    bar = None

    def on_start(total: int):
        nonlocal bar
        bar = progress(total=total, desc="photometry", unit="file")
        return lambda: bar.update(1)

    epochs = []
    try:
        tables = photometry_tables(args.input_dir, options, channel=args.channel,
                                   progress=on_start)
        first = next(tables)
        second = next(tables, None)
        if second is not None and as_file:
            raise InputError(f"--out {out}: the input holds several epochs; give a folder "
                             "(it gets epoch_NN.fits per epoch)")
        pending = [first] + ([second] if second is not None else [])
        while pending:
            epoch, table = pending.pop(0)
            path = out if as_file else out / f"epoch_{epoch.number:02d}.fits"
            write_photometry(table, path)
            good = np.asarray(table["flag"]) == 0
            epochs.append({
                "epoch": int(epoch.number), "path": str(path),
                "aorkeys": [int(a) for a in epoch.aorkeys], "frames": len(table),
                "flagged": flag_counts(np.asarray(table["flag"])),
                "mean_x": float(np.mean(table["x"][good])) if good.any() else float("nan"),
                "mean_y": float(np.mean(table["y"][good])) if good.any() else float("nan"),
                "mean_flux": float(np.mean(table["flux"][good])) if good.any() else float("nan"),
                "simdir": table.meta.get("SIMDIR"),
            })
            if not pending:
                nxt = next(tables, None)
                if nxt is not None:
                    pending.append(nxt)
    finally:
        if bar is not None:
            bar.close()
    total = sum(e["frames"] for e in epochs)
    flagged: dict[str, int] = {}
    for e in epochs:
        for k, v in e["flagged"].items():
            flagged[k] = flagged.get(k, 0) + v
    good = [e["flagged"]["good"] for e in epochs]

    def mean_of(key: str) -> float:
        w = [g for g, e in zip(good, epochs, strict=True) if g and np.isfinite(e[key])]
        v = [e[key] for g, e in zip(good, epochs, strict=True) if g and np.isfinite(e[key])]
        return float(np.average(v, weights=w)) if w else float("nan")

    return {"out": str(out), "epochs": epochs, "frames": total, "flagged": flagged,
            "mean_x": mean_of("mean_x"), "mean_y": mean_of("mean_y"),
            "mean_flux": mean_of("mean_flux"), "centroid": options.centroid,
            "radius_px": options.radius_px}


def format_text(result: dict) -> str:
    lines = [f"{result['frames']} frames in {len(result['epochs'])} epoch(s), centroid "
             f"{result['centroid']}, r = {result['radius_px']} px"]
    for e in result["epochs"]:
        bad = {k: v for k, v in e["flagged"].items() if k not in ("good", "total") and v}
        lines.append(f"epoch {e['epoch']:2d}  AORs {','.join(map(str, e['aorkeys']))}  "
                     f"{e['frames']} frames, {e['flagged']['good']} good  "
                     f"x={e['mean_x']:.3f} y={e['mean_y']:.3f} flux={e['mean_flux']:.1f} e  "
                     f"-> {e['path']}")
        if bad:
            lines.append("          flagged: " + ", ".join(f"{k} {v}" for k, v in bad.items()))
    return "\n".join(lines)
