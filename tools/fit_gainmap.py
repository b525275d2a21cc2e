"""Fit the gain-map models committed in ``src/eclipsebench/data/gainmap_ch<N>.json``.

Usage (from the project root, with ``../shared/data/irac/pmap_ch<N>/`` present)::

    .venv/bin/python tools/fit_gainmap.py [--channel 2] [--pmap-dir DIR] [--radius 3.0]
                                          [--degree 6] [--out src/eclipsebench/data/gainmap_ch2.json]
    .venv/bin/python tools/fit_gainmap.py --channel 1      # gainmap_ch1.json

``--channel 1`` changes the defaults to channel 1's: the map ``pmap_ch1``,
the band 3.18-3.93 um, IRACSIM's channel-1 pixel scale (1.2233"), and the
noise pixels of the 30 real 0.1 s cubes of HD 209458 (AOR 41629440: 7.43,
median of the good frames, at their mean centroid (14.877, 14.684)) with the
jitter the Table-5 FBM puts inside a 0.1 s frame (0.075 px RMS per axis).

Cells that no calibration measurement reached (NaN in ``pmap_ch1``): every fit
uses only the box spanned by the cells with occupancy > 20 (finite cells
inside it with low occupancy at the low weight); the polynomials carry that
``box`` and are evaluated with the phase clamped to it (see
``GainPolynomial.evaluate``), so nothing is extrapolated. ``pmap_ch2`` has no
NaN: no box, as before.

Nothing from ``shared/`` is copied into the repository; only coefficients.

``pmap_poly``
    A 2-D polynomial of total degree ``--degree`` in the *centroid's*
    sub-pixel phase ``(x_c - 15, y_c - 15)`` fitted to the warm gain map
    (weight 1 where its occupancy exceeds 20, ``--low-weight`` elsewhere so
    the whole pixel stays bounded): the optional rescaling of IRSA PRFs.
``builtin``
    The PSF of :class:`eclipsebench.instrument.prf.BuiltinPRF`: its Gaussian
    blur is chosen so that the noise pixels of a star at the mean position of
    the real XO-3 peak-up AOR (15.09, 15.18), averaged over a Gaussian jitter
    of ``--jitter`` px RMS per axis (0.088 px, what the default Table-5 FBM
    gives inside a 2 s frame), equal the value measured on those frames
    (``--beta``, 4.60); then stars are rendered without gain on
    a grid of *true* positions across pixel (15, 15), their 7x7
    centre-of-light centroids and aperture sums (radius ``--radius``) are
    measured, and the gain polynomial ``G`` in the true sub-pixel phase is
    fitted so that ``G x aperture sum`` equals the gain map at the measured
    centroid (same weights). ``fit_rms`` is the RMS of the relative
    difference over the positions whose centroid has occupancy > 20.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from scipy import optimize

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from eclipsebench.instrument import gain_fit as G  # noqa: E402
from eclipsebench.instrument import prf as P  # noqa: E402
from eclipsebench.photometry.estimators import noise_pixels  # noqa: E402

CHANNEL_DEFAULTS = {
    2: {"source": "pmap_ch2_0p1s_x4_500x500_0043_120124 (Spitzer Science Center)",
        "beta": 4.60, "jitter": 0.088, "position": (15.09, 15.18), "pixel_scale": None},
    1: {"source": "pmap_ch1_500x500_0043_120828 (Spitzer Science Center)",
        "beta": 7.43, "jitter": 0.075, "position": (14.877, 14.684),
        "pixel_scale": (1.22334117768332 * 1.22328355209902) ** 0.5},
}


def load_pmap(folder: Path, channel: int = 2):
    """pmap, x grid, y grid (0-based pixel coordinates), occupancy."""
    import warnings

    from astropy.io import fits
    from astropy.io.fits.verify import VerifyWarning

    out = {}
    for key in ("pmap", "xgrid", "ygrid", "occu"):
        path = next(folder.glob(f"{key}_ch{channel}_*.fits"))
        with warnings.catch_warnings():
            # the pmap files end with a non-standard trailer (see shared/data/irac/README.md)
            warnings.simplefilter("ignore", VerifyWarning)
            out[key] = np.asarray(fits.getdata(path), float)
    return out


def psf_kwargs(channel, pixel_scale):
    from eclipsebench.detector.constants import channel_constants

    kw = {"band_um": channel_constants(channel).band_um}
    if pixel_scale is not None:
        kw["pixel_scale_arcsec"] = pixel_scale
    return kw


def beta_at(blur_px, obscuration, os_, half_px, x, y, jitter_px, **psf_kw):
    """Noise pixels of the frame-averaged image of a star jittering around (x, y)."""
    psf = P.psf_fine(os_, half_px - 0.5, obscuration=obscuration, blur_px=blur_px, **psf_kw)
    table = P.pixel_integrated_table(psf, os_)
    prf = P.PRF(table, os_, (0.5 * (table.shape[1] - 1), 0.5 * (table.shape[0] - 1)))
    # a fixed 2-D Gauss-Hermite cloud of sub-sample offsets with RMS jitter_px per axis
    nodes, weights = np.polynomial.hermite_e.hermegauss(7)
    u, v = np.meshgrid(nodes * jitter_px, nodes * jitter_px)
    w = np.outer(weights, weights).ravel() / weights.sum() ** 2
    image = np.tensordot(w, prf.render(x + u.ravel(), y + v.ravel()), axes=1)
    return float(noise_pixels(image[None])[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--channel", type=int, choices=(1, 2), default=2)
    ap.add_argument("--pmap-dir", type=Path, default=None,
                    help="default ../shared/data/irac/pmap_ch<channel>")
    ap.add_argument("--radius", type=float, default=3.0, help="aperture radius (px) of the pmap")
    ap.add_argument("--degree", type=int, default=6, help="polynomial total degree")
    ap.add_argument("--low-weight", type=float, default=0.05,
                    help="weight of gain-map cells with occupancy <= 20")
    ap.add_argument("--obscuration", type=float, default=0.14)
    ap.add_argument("--beta", type=float, default=None,
                    help="target noise pixels (channel 2: 4.60, channel 1: 7.43)")
    ap.add_argument("--jitter", type=float, default=None,
                    help="RMS (px per axis) of the jitter inside a frame that the target "
                         "noise pixels include (0.088: Table 5's FBM, A_fbm = 0.4 px, in a "
                         "2 s frame; 0.075 in a 0.1 s frame)")
    ap.add_argument("--step", type=float, default=0.02, help="true-position grid step (px)")
    ap.add_argument("--out", type=Path, default=None,
                    help="default src/eclipsebench/data/gainmap_ch<channel>.json")
    args = ap.parse_args(argv)
    ch = args.channel
    dflt = CHANNEL_DEFAULTS[ch]
    pmap_dir = args.pmap_dir or ROOT / ".." / "shared" / "data" / "irac" / f"pmap_ch{ch}"
    out_path = args.out or ROOT / "src" / "eclipsebench" / "data" / f"gainmap_ch{ch}.json"
    beta = dflt["beta"] if args.beta is None else args.beta
    jitter = dflt["jitter"] if args.jitter is None else args.jitter
    x_beta, y_beta = dflt["position"]
    psf_kw = psf_kwargs(ch, dflt["pixel_scale"])

    pm = load_pmap(pmap_dir, ch)
    result = {"source": dflt["source"],
              "made_by": "tools/fit_gainmap.py " + " ".join(sys.argv[1:] if argv is None else argv)}
    maps = (pm["xgrid"][0, :], pm["ygrid"][:, 0], pm["pmap"], pm["occu"])

    # (1) the gain map itself as a function of the centroid phase
    poly, info = G.fit_centroid_gain(*maps, degree=args.degree, low_weight=args.low_weight)
    rms, box = info["fit_rms"], info["box"]
    result["pmap_poly"] = {"powers": [list(p) for p in poly.powers],
                           "coeffs": list(poly.coeffs),
                           "variable": "centroid phase about the nearest pixel centre",
                           "occupancy_min": G.OCCUPANCY_MIN, "fit_rms": rms}
    if box is not None:
        result["pmap_poly"]["box"] = [list(box[0]), list(box[1])]
    print(f"pmap polynomial (degree {args.degree}): rms {rms:.5f} where occupancy > "
          f"{G.OCCUPANCY_MIN}" + (f", phase clamped to {box}" if box is not None else ""))

    # (2) the builtin PSF width
    os_, half = 20, 12.8
    blur = optimize.brentq(lambda b: beta_at(b, args.obscuration, os_, half, x_beta, y_beta,
                                             jitter, **psf_kw) - beta, 0.0, 1.0, xtol=1e-4)
    print(f"PSF blur {blur:.4f} px gives noise pixels {beta} with {jitter} px jitter")
    psf = P.psf_fine(os_, half - 0.5, obscuration=args.obscuration, blur_px=blur, **psf_kw)
    table = P.pixel_integrated_table(psf, os_)
    prf = P.PRF(table, os_, (0.5 * (table.shape[1] - 1), 0.5 * (table.shape[0] - 1)))

    # (3) the gain polynomial in the true phase
    poly, info = G.fit_true_phase_gain(prf, *maps, radius_px=args.radius, degree=args.degree,
                                       step_px=args.step, low_weight=args.low_weight)
    rms = info["fit_rms"]
    gain = {"powers": [list(p) for p in poly.powers], "coeffs": list(poly.coeffs),
            "variable": "true sub-pixel phase about the nearest pixel centre"}
    if poly.box is not None:
        gain["box"] = [list(poly.box[0]), list(poly.box[1])]
    print(f"builtin gain (degree {args.degree}): {info['n_positions']} positions, rms {rms:.5f}; "
          f"G over the whole pixel {info['gain_min']:.4f}..{info['gain_max']:.4f}")
    result["builtin"] = {
        "obscuration": args.obscuration, "blur_px": float(blur),
        "target_noise_pixels": beta, "noise_pixels_position": [x_beta, y_beta],
        "noise_pixels_jitter_rms_px": jitter,
        "gain": gain,
        "aperture_radius_px": args.radius,
        "centroid": "centre of light, 7x7 box on pixel (15, 15)",
        "fit_rms": rms, "n_positions": info["n_positions"],
    }
    from eclipsebench.io.atomic import atomic_path

    if dflt["pixel_scale"] is not None:
        result["builtin"]["pixel_scale_arcsec"] = float(dflt["pixel_scale"])
    with atomic_path(out_path) as tmp:
        Path(tmp).write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {out_path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
