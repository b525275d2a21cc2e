"""Point response functions (PRFs) of IRAC channels 1 and 2 (paper Appendix A.2).

A PRF here is a table ``C(dy, dx)`` of the charge a pixel collects when the
star sits ``(dx, dy)`` pixels *from* it (the PSF integrated over the pixel),
sampled ``oversample`` times per pixel. A star at
``(x, y)`` (0-based pixel coordinates, centre of the first pixel at 0) gives
pixel ``(px, py)`` the value ``G(x, y) C(py - y, px - x)``, interpolated with
cubic B-splines; ``G`` is an optional position-dependent scalar gain (the warm
rescaling of cryogenic PRFs). Derivatives with respect to the star position
come from the same splines, so ``render_taylor`` is consistent with ``render``.

Normalisation: the total of all pixels of a star at a pixel centre (integer
``x, y``) is exactly 1 (the whole table support, about 25 px across).

Centring: as in the paper (Appendix A.2, "all PRF centres were shifted..."),
the offset origin of the table is moved so that the centre-of-light centroid
(Eqs. ``x_centroid``/``y_centroid``) over a 7x7 box of a noiseless star at a
pixel centre equals the input position.

Two PRFs:

:class:`BuiltinPRF`
    The package's own: the polychromatic (4.0-5.0 um for channel 2,
    3.18-3.93 um for channel 1) PSF of an 85 cm telescope with a central
    obstruction, blurred by a Gaussian (detector diffusion; its width makes
    the noise pixels of frames jittered by the default pointing model match
    real frames: XO-3 for channel 2, HD 209458 for channel 1), sampled at
    1/20 px and integrated over the pixel, times the intra-pixel gain: a
    smooth function ``G`` of the star's sub-pixel position fitted so that
    aperture photometry across the sweet-spot pixel follows the channel's
    warm gain map (``tools/fit_gainmap.py``, ``data/gainmap_ch<N>.json``).

    Why a flux multiplier and not a response inside the pixel integral: the
    optics cut off spatial frequencies above ``D / lambda`` = 1.1-1.4 cycles
    per pixel (5.0-4.0 um), so whatever the response inside a pixel, the
    aperture flux of a star can only vary as ``a0 + a1 cos(2 pi x) + ...``
    with the first harmonic damped by the optical MTF (a few %) and the
    blur; reproducing the 5% peak-to-peak gain map that way needs a pixel
    response varying by more than 100% (a least-squares fit of a Legendre
    pixel response, tried while building this model, ran from -1500 to
    +2800). IRACSIM did the same
    for its warm PRFs (Appendix A.2: the realisations were scaled with
    respect to each other).
:class:`IrsaPRF`
    The IRSA/IRACSIM files (128x128, 5x sub-sampled, one file per array
    position), nearest array position, with an optional scalar rescaling that
    makes aperture photometry follow the gain map (the paper's warm rescaling
    of cryogenic PRFs).
"""

from __future__ import annotations

import functools
import json
import re
import warnings
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import NamedTuple

import numpy as np
from astropy.io import fits
from astropy.utils.exceptions import AstropyUserWarning
from scipy import signal, special

from eclipsebench.errors import DataError, InputError

from ..detector import constants
from ..photometry.estimators import aperture_flux, centroid_col
from . import _spline

__all__ = ["PRF", "BuiltinPRF", "IrsaPRF", "TaylorStamps", "GainPolynomial", "polynomial_powers",
           "true_grid_photometry",
           "load_gainmap_coefficients", "irsa_prf_channel",
           "electrons_per_second_scale", "jy_to_electrons_per_second", "psf_fine",
           "pixel_integrated_table", "warm_rescaling"]


class TaylorStamps(NamedTuple):
    """Stamps of a star and their derivatives with respect to its position.

    ``value[n, a, b]`` is pixel ``(x0[n] + b, y0[n] + a)``; ``dx``, ``dy`` the
    first derivatives with respect to the star's x and y (per px), ``dxx``,
    ``dxy``, ``dyy`` the second.
    """

    value: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    dxx: np.ndarray
    dxy: np.ndarray
    dyy: np.ndarray
    x0: np.ndarray
    y0: np.ndarray


@dataclass(frozen=True)
class GainPolynomial:
    """A 2-D polynomial ``sum c_mn u^m v^n`` in the sub-pixel phase ``(u, v) = (x - X, y - Y)``
    about the nearest pixel centre ``(X, Y)``; a position-dependent flux multiplier."""

    powers: tuple[tuple[int, int], ...]
    coeffs: tuple[float, ...]

    box: tuple[tuple[float, float], tuple[float, float]] | None = None

    def phase(self, x, y):
        """Sub-pixel phase about the nearest pixel centre."""
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        return x - np.rint(x), y - np.rint(y)

    def evaluate(self, x, y, order: int = 0):
        """Value (and derivatives up to ``order``) at positions ``x, y``.

        With ``box = ((u_lo, u_hi), (v_lo, v_hi))`` the phase is clamped to
        the box (where the fitted map can be trusted), so ``G`` is constant
        along a clamped direction outside it (its derivatives there are 0).

        Returns ``g`` or ``(g, gx, gy)`` or ``(g, gx, gy, gxx, gxy, gyy)``.
        """
        u, v = self.phase(x, y)
        inside_u = inside_v = None
        if self.box is not None:
            (u_lo, u_hi), (v_lo, v_hi) = self.box
            inside_u = ((u >= u_lo) & (u <= u_hi)).astype(float)
            inside_v = ((v >= v_lo) & (v <= v_hi)).astype(float)
            u, v = np.clip(u, u_lo, u_hi), np.clip(v, v_lo, v_hi)
        out = [np.zeros_like(u) for _ in range(1 if order == 0 else 3 if order == 1 else 6)]
        for (m, n), c in zip(self.powers, self.coeffs, strict=True):
            out[0] += c * u**m * v**n
            if order >= 1:
                if m:
                    out[1] += c * m * u ** (m - 1) * v**n
                if n:
                    out[2] += c * n * u**m * v ** (n - 1)
            if order >= 2:
                if m > 1:
                    out[3] += c * m * (m - 1) * u ** (m - 2) * v**n
                if m and n:
                    out[4] += c * m * n * u ** (m - 1) * v ** (n - 1)
                if n > 1:
                    out[5] += c * n * (n - 1) * u**m * v ** (n - 2)
        if inside_u is not None and order >= 1:
            out[1] *= inside_u
            out[2] *= inside_v
            if order >= 2:
                out[3] *= inside_u
                out[4] *= inside_u * inside_v
                out[5] *= inside_v
        return out[0] if order == 0 else tuple(out)

    @classmethod
    def from_dict(cls, d: dict) -> GainPolynomial:
        """From ``{"powers": [[m, n], ...], "coeffs": [...]}`` and an optional
        ``"box": [[u_lo, u_hi], [v_lo, v_hi]]``."""
        box = d.get("box")
        if box is not None:
            box = ((float(box[0][0]), float(box[0][1])), (float(box[1][0]), float(box[1][1])))
        return cls(tuple((int(m), int(n)) for m, n in d["powers"]),
                   tuple(float(c) for c in d["coeffs"]), box)


def load_gainmap_coefficients(channel: int = 2) -> dict:
    """The committed gain-map fit of a channel (``eclipsebench/data/gainmap_ch<N>.json``).

    Examples
    --------
    >>> sorted(load_gainmap_coefficients(1))[:3]
    ['builtin', 'made_by', 'pmap_poly']
    """
    constants.channel_constants(channel)  # 1 or 2, else one line
    name = f"gainmap_ch{int(channel)}.json"
    text = resources.files("eclipsebench.data").joinpath(name).read_text()
    return json.loads(text)


class PRF:
    """A tabulated PRF (see the module docstring for the conventions).

    Parameters
    ----------
    table : ndarray (ny_t, nx_t)
        ``C`` sampled ``oversample`` times per pixel.
    oversample : int
        Samples per pixel of the table.
    centre : (float, float)
        Table index coordinates ``(cx, cy)`` of offset 0 before recentring.
    gain : GainPolynomial or None
        Position-dependent scalar multiplier.
    recentre : bool
        Shift the origin so the 7x7 centre of light of a star at a pixel
        centre is the input position.
    normalise : bool
        Scale so a star at a pixel centre totals 1.
    """

    def __init__(self, table, oversample: int, centre, *, gain: GainPolynomial | None = None,
                 recentre: bool = True, normalise: bool = True):
        table = np.asarray(table, float)
        if table.ndim != 2 or min(table.shape) < 8:
            raise InputError(f"PRF table: expected a 2-D array, got shape {table.shape}")
        self.oversample = int(oversample)
        self.gain = gain
        self._coef = _spline.spline_coefficients(table)
        self.cx, self.cy = float(centre[0]), float(centre[1])
        self.support_px = 0.5 * (min(table.shape) - 1) / self.oversample
        self.scale = 1.0
        if recentre:
            self._recentre()
        if normalise:
            ref = 15.0 + np.zeros(1)
            self.scale = 1.0 / float(self.render(ref, ref, shape=(32, 32)).sum())

    # ----- evaluation -------------------------------------------------------
    def _eval(self, x, y, x0, y0, ny: int, nx: int, order: int) -> np.ndarray:
        x = np.ascontiguousarray(np.atleast_1d(np.asarray(x, float)))
        y = np.ascontiguousarray(np.atleast_1d(np.asarray(y, float)))
        if x.shape != y.shape or x.ndim != 1:
            raise InputError("PRF positions: expected 1-D arrays x and y of equal length")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise InputError("PRF positions: expected finite x and y")
        nq = 1 if order == 0 else 3 if order == 1 else 6
        out = np.empty((x.size, nq, ny, nx))
        _spline.stamps_kernel(self._coef, self.cx, self.cy, float(self.oversample), x, y,
                              np.asarray(x0, np.int64), np.asarray(y0, np.int64), ny, nx, order,
                              out)
        out *= self.scale
        if self.gain is not None:
            g = self.gain.evaluate(x, y, order)
            if order == 0:
                out *= g[:, None, None, None]
            else:
                g = [gi[:, None, None] for gi in g]
                v = out[:, 0].copy()
                d = [out[:, q].copy() for q in range(nq)]
                out[:, 0] = g[0] * v
                out[:, 1] = g[0] * d[1] + g[1] * v
                out[:, 2] = g[0] * d[2] + g[2] * v
                if order >= 2:
                    out[:, 3] = g[0] * d[3] + 2 * g[1] * d[1] + g[3] * v
                    out[:, 4] = g[0] * d[4] + g[1] * d[2] + g[2] * d[1] + g[4] * v
                    out[:, 5] = g[0] * d[5] + 2 * g[2] * d[2] + g[5] * v
        return out

    def render(self, x, y, shape=(32, 32)) -> np.ndarray:
        """Noiseless images (n, ny, nx) of unit-flux stars at positions ``x, y`` (arrays)."""
        x = np.atleast_1d(np.asarray(x, float))
        zeros = np.zeros(x.size, np.int64)
        return self._eval(x, y, zeros, zeros, int(shape[0]), int(shape[1]), 0)[:, 0]

    def render_stamp(self, x, y, half: int = 6):
        """Stamps ``(n, 2 half + 1, 2 half + 1)`` centred on the nearest pixel.

        Returns
        -------
        stamps, x0, y0
            ``stamps[n, a, b]`` is pixel ``(x0[n] + b, y0[n] + a)``.
        """
        x = np.atleast_1d(np.asarray(x, float))
        y = np.atleast_1d(np.asarray(y, float))
        x0 = np.rint(x).astype(np.int64) - half
        y0 = np.rint(y).astype(np.int64) - half
        n = 2 * half + 1
        return self._eval(x, y, x0, y0, n, n, 0)[:, 0], x0, y0

    def render_taylor(self, x, y, half: int = 6) -> TaylorStamps:
        """Stamps with first and second derivatives with respect to the star position.

        For sub-samples at ``(x + u, y + v)`` the stamp is
        ``value + u dx + v dy + (u^2 dxx + 2 u v dxy + v^2 dyy) / 2`` to second order.
        """
        x = np.atleast_1d(np.asarray(x, float))
        y = np.atleast_1d(np.asarray(y, float))
        x0 = np.rint(x).astype(np.int64) - half
        y0 = np.rint(y).astype(np.int64) - half
        n = 2 * half + 1
        out = self._eval(x, y, x0, y0, n, n, 2)
        return TaylorStamps(out[:, 0], out[:, 1], out[:, 2], out[:, 3], out[:, 4], out[:, 5],
                            x0, y0)

    # ----- centring ---------------------------------------------------------
    def _recentre(self) -> None:
        """Move the origin so the 7x7 centre of light at a pixel centre equals the input."""
        gain, self.gain = self.gain, None
        ref = np.array([15.0])
        for _ in range(8):
            xc, yc = centroid_col(self.render(ref, ref), around=(15, 15))
            ex, ey = float(xc[0] - 15.0), float(yc[0] - 15.0)
            if abs(ex) < 1e-9 and abs(ey) < 1e-9:
                break
            # the image moves by -delta/os px when the origin index moves by delta
            self.cx += ex * self.oversample
            self.cy += ey * self.oversample
        self.gain = gain


def psf_fine(oversample: int, half_px: float, *, obscuration: float, blur_px: float,
             n_wavelengths: int = 11, band_um: tuple[float, float] = constants.BAND_UM,
             pixel_scale_arcsec: float = constants.PIXEL_SCALE_ARCSEC) -> np.ndarray:
    """Polychromatic PSF on a grid of ``1/oversample`` px, points at ``(i + 1/2)/os - half_px``.

    Annular-aperture Airy pattern of an 85 cm telescope (central obstruction
    ratio ``obscuration``) averaged over ``band_um`` (channel 2's 4.0-5.0 um
    by default) with equal photon weights, on pixels of
    ``pixel_scale_arcsec``, convolved with a Gaussian of ``blur_px`` (px),
    arbitrary units.
    """
    psf = _airy_band(int(oversample), float(half_px), float(obscuration), int(n_wavelengths),
                     (float(band_um[0]), float(band_um[1])), float(pixel_scale_arcsec))
    if not blur_px > 0:
        return psf.copy()
    k = np.arange(-int(np.ceil(5 * blur_px * oversample)),
                  int(np.ceil(5 * blur_px * oversample)) + 1) / oversample
    gk = np.exp(-0.5 * (k / blur_px) ** 2)
    gk /= gk.sum()
    psf = signal.fftconvolve(psf, gk[None, :], mode="same")
    return signal.fftconvolve(psf, gk[:, None], mode="same")


@functools.lru_cache(maxsize=4)
def _airy_band(oversample: int, half_px: float, obscuration: float, n_wavelengths: int,
               band_um: tuple[float, float], pixel_scale_arcsec: float) -> np.ndarray:
    """:func:`psf_fine` before its blur (read-only), once per process and optics: the
    Airy patterns are nine tenths of its time and do not depend on the blur, of which the
    twins' calibration tries nine (issue 40)."""
    n = int(round(2 * half_px * oversample))
    u = (np.arange(n) + 0.5) / oversample - half_px
    r_px = np.hypot(u[None, :], u[:, None])
    r_rad = r_px * pixel_scale_arcsec / 206264.80624709636
    psf = np.zeros_like(r_px)
    eps = obscuration
    for lam_um in np.linspace(band_um[0], band_um[1], n_wavelengths):
        v = np.pi * constants.TELESCOPE_DIAMETER_M * r_rad / (lam_um * 1e-6)
        v = np.where(v == 0, 1e-12, v)
        amp = 2 * special.j1(v) / v - eps**2 * 2 * special.j1(eps * v) / (eps * v)
        psf += (amp / (1 - eps**2)) ** 2 * (lam_um / band_um[0]) ** -2
    psf.setflags(write=False)
    return psf


def pixel_integrated_table(psf: np.ndarray, oversample: int) -> np.ndarray:
    """``C(d) = sum_s PSF(d + s) / os^2``: integrate the fine PSF over a pixel.

    The pixel is sampled at ``s = (j + 1/2)/os - 1/2``; with the PSF on the
    half-shifted grid of :func:`psf_fine`, ``C`` falls on the integer grid
    ``d = (i - c)/os``. The full correlation keeps every sample, so ``C``
    vanishes half a pixel beyond the PSF support and the sum over the pixels
    of a star equals the PSF total at every sub-pixel position.
    """
    kern = np.full((oversample, oversample), 1.0 / oversample**2)
    return np.clip(signal.fftconvolve(psf, kern, mode="full"), 0.0, None)


@functools.lru_cache(maxsize=16)
def _builtin_table(oversample: int, half_px: float, obscuration: float, blur_px: float,
                   band_um: tuple[float, float], pixel_scale_arcsec: float) -> np.ndarray:
    """The pixel-integrated table of :func:`psf_fine` (read-only), once per process and
    optics: a twin task builds a PRF per blur it renders with (0.2 s each)."""
    psf = psf_fine(oversample, half_px, obscuration=obscuration, blur_px=blur_px,
                   band_um=band_um, pixel_scale_arcsec=pixel_scale_arcsec)
    table = pixel_integrated_table(psf, oversample)
    table.setflags(write=False)
    return table


class BuiltinPRF(PRF):
    """The package's own PRF of IRAC channel 1 or 2 (see the module docstring).

    Parameters
    ----------
    gain : bool
        Apply the fitted intra-pixel gain (False: flux independent of the
        sub-pixel position, for tests and for users who want none).
    coefficients : dict or None
        The ``"builtin"`` entry of ``gainmap_ch<channel>.json`` (default: the
        committed one): ``obscuration``, ``blur_px``, optionally
        ``pixel_scale_arcsec`` (default 1.2) and the gain polynomial
        ``powers``/``coeffs`` (optionally ``box``).
    oversample : int
        Table samples per pixel.
    half_px : float
        Half-width of the PSF support (px); 12.8 like the IRSA files.
    channel : {1, 2}
        The band of the PSF (:class:`~eclipsebench.detector.constants.ChannelConstants`)
        and the committed coefficients.
    """

    def __init__(self, *, gain: bool = True, coefficients: dict | None = None,
                 oversample: int = 20, half_px: float = 12.8, channel: int = 2):
        self.channel = constants.channel_constants(channel).channel
        coeff = (load_gainmap_coefficients(self.channel)["builtin"] if coefficients is None
                 else coefficients)
        self.coefficients = coeff
        table = _builtin_table(oversample, half_px - 0.5, float(coeff["obscuration"]),
                               float(coeff["blur_px"]),
                               constants.channel_constants(self.channel).band_um,
                               float(coeff.get("pixel_scale_arcsec",
                                               constants.PIXEL_SCALE_ARCSEC)))
        gp = GainPolynomial.from_dict(coeff["gain"]) if gain else None
        super().__init__(table, oversample, (0.5 * (table.shape[1] - 1),
                                             0.5 * (table.shape[0] - 1)), gain=gp)


_IRSA_NAME = re.compile(r"col(\d+)_row(\d+)\.fits$", re.IGNORECASE)
# IRACSIM ``IRAC<ch>_...`` and IRSA ``IRACPC<ch>_...`` file names carry the channel
_IRSA_CHANNEL = re.compile(r"^IRAC(?:PC)?(\d)_", re.IGNORECASE)


def irsa_prf_channel(folder) -> int | None:
    """The channel the PRF files of ``folder`` are for (from ``IRAC[PC]<N>_`` names), or None.

    Raises
    ------
    DataError
        When the folder mixes channels.
    """
    folder = Path(folder)
    found = {int(m.group(1)) for p in folder.glob("*.fits") if _IRSA_NAME.search(p.name)
             for m in [_IRSA_CHANNEL.match(p.name)] if m}
    if len(found) > 1:
        raise DataError(folder, f"PRF files of channels {sorted(found)} mixed in one folder")
    return found.pop() if found else None


class IrsaPRF(PRF):
    """A PRF from the IRSA/IRACSIM file set (see :meth:`from_files`)."""

    #: The file it was read from, and its channel (set by :meth:`from_files`).
    path: Path
    channel: int

    @classmethod
    def from_files(cls, folder, *, array_position=None, gain_rescale: bool = False,
                   subarray: bool = True, channel: int | None = None) -> IrsaPRF:
        """Load the PRF of the array position nearest to ``array_position``.

        Parameters
        ----------
        folder : path
            A folder of ``*col<NNN>_row<NNN>.fits`` files (128x128,
            ``PRFXRSMP = PRFYRSMP`` samples per pixel, BCD orientation). The
            numbers are 1-based full-array pixel (column, row).
        array_position : (x, y) or None
            0-based pixel in the subarray (``subarray=True``, the default) or
            the full array; default the subarray sweet spot (15, 15), i.e.
            full-array (23, 231) whose nearest file is ``col025_row233``.
        gain_rescale : bool
            Rescale the realisations so that aperture photometry follows the
            warm gain map (:func:`warm_rescaling`), as the paper did for the
            cryogenic PRFs. The ``warm_2015`` set is said to contain such a
            rescaling already.
        channel : {1, 2}, optional
            The channel expected; files named for another channel
            (``IRAC[PC]<N>_``) are refused. Default: the files' own channel
            (2 when the names do not say).

        Notes
        -----
        Between array positions the nearest file is used (the subarray lies
        entirely inside one file's region). Between the 5x5 sub-pixel
        realisations the table is interpolated with cubic B-splines.
        """
        folder = Path(folder)
        files = sorted(p for p in folder.glob("*.fits") if _IRSA_NAME.search(p.name))
        if not files:
            raise DataError(folder, "no IRSA PRF files named *col<NNN>_row<NNN>.fits")
        named = irsa_prf_channel(folder)
        if channel is not None and named is not None and named != int(channel):
            raise DataError(folder, f"PRF files of channel {named}, expected channel {channel}")
        channel = int(channel if channel is not None else named if named is not None else 2)
        x, y = (15.0, 15.0) if array_position is None else map(float, array_position)
        if subarray:
            x, y = x + constants.SUBARRAY_ORIGIN_FULL[0], y + constants.SUBARRAY_ORIGIN_FULL[1]
        names = [_IRSA_NAME.search(p.name) for p in files]   # every file matched the glob's filter
        pos = np.array([[int(m.group(1)) - 1, int(m.group(2)) - 1] for m in names if m is not None],
                       dtype=float)
        best = files[int(np.argmin(np.hypot(pos[:, 0] - x, pos[:, 1] - y)))]
        try:
            with warnings.catch_warnings():
                # the 2014 warm set's headers end with a non-standard trailer; data read fine
                warnings.filterwarnings("ignore", message="Unexpected bytes trailing END",
                                        category=AstropyUserWarning)
                with fits.open(best) as hdul:
                    data = np.asarray(hdul[0].data, float)
                    hdr = hdul[0].header.copy()
        except OSError as exc:
            raise DataError(best, f"unreadable FITS file ({exc})") from None
        if data.ndim != 2:
            raise DataError(best, f"expected a 2-D PRF image, got shape {data.shape}")
        osx, osy = int(hdr.get("PRFXRSMP", 0)), int(hdr.get("PRFYRSMP", 0))
        if osx < 1 or osx != osy:
            raise DataError(best, "expected equal positive PRFXRSMP and PRFYRSMP")
        obj = cls(np.where(np.isfinite(data), data, 0.0), osx,
                  (0.5 * (data.shape[1] - 1), 0.5 * (data.shape[0] - 1)))
        obj.path = best
        obj.channel = channel
        if gain_rescale:
            obj.gain = warm_rescaling(obj, channel=channel)
            obj.scale /= float(obj.render([15.0], [15.0]).sum())
        return obj


def polynomial_powers(degree: int) -> list[tuple[int, int]]:
    """The ``(m, n)`` powers of ``u^m v^n`` of a 2-D polynomial of total ``degree``.

    Examples
    --------
    >>> polynomial_powers(1)
    [(0, 0), (1, 0), (0, 1)]
    """
    return [(m, t - m) for t in range(degree + 1) for m in range(t, -1, -1)]


def true_grid_photometry(prf: PRF, step_px: float, radius_px: float) -> tuple[np.ndarray, ...]:
    """Stars of ``prf`` without its gain on a grid of true positions across pixel (15, 15)
    (step ``step_px``), measured: ``(x, y, x_centroid, y_centroid, aperture_sum)``.

    The 7x7 centre-of-light centroid and the aperture sum of radius
    ``radius_px`` at it; ``prf``'s own gain is restored afterwards.
    """
    g = np.arange(-0.5, 0.5 + 1e-9, step_px)
    gx, gy = np.meshgrid(15.0 + g, 15.0 + g)
    xs, ys = gx.ravel(), gy.ravel()
    saved, prf.gain = prf.gain, None
    try:
        images = prf.render(xs, ys)
    finally:
        prf.gain = saved
    xc, yc = centroid_col(images, around=(15, 15))
    return xs, ys, xc, yc, aperture_flux(images, xc, yc, radius_px)


def warm_rescaling(prf: PRF, *, step_px: float = 0.05, degree: int = 6,
                   channel: int = 2) -> GainPolynomial:
    """The gain that makes aperture photometry of ``prf`` follow the warm gain map.

    Paper Appendix A.2: realisations are scaled with respect to each other so
    that aperture photometry (radius as in ``gainmap_ch<channel>.json``,
    3 px) at the 7x7 centre-of-light centroid varies like the warm gain map
    (its committed polynomial ``pmap_poly`` in the centroid phase, clamped to
    its trusted box when it has one). Solved on a grid of true sub-pixel
    positions and fitted with a polynomial of total ``degree`` in the true
    phase. (:func:`eclipsebench.instrument.gain_fit.fit_true_phase_gain` fits
    the gridded map itself, weighted by its occupancy.)
    """
    coeff = load_gainmap_coefficients(channel)
    pmap = GainPolynomial.from_dict(coeff["pmap_poly"])
    radius = float(coeff["builtin"]["aperture_radius_px"])
    xs, ys, xc, yc, ap_flux = true_grid_photometry(prf, step_px, radius)
    ratio = pmap.evaluate(xc, yc) / ap_flux
    powers = polynomial_powers(degree)
    design = np.stack([(xs - 15.0) ** m * (ys - 15.0) ** n for m, n in powers], axis=-1)
    c, *_ = np.linalg.lstsq(design, ratio / ratio.mean(), rcond=None)
    return GainPolynomial(tuple(powers), tuple(float(v) for v in c))


def electrons_per_second_scale(prf: PRF, flux_aperture_e: float, radius_px: float = 2.25, *,
                               t_exp_s: float, x_px: float = 15.0, y_px: float = 15.0) -> float:
    """Multiplier that turns ``prf.render`` into electrons per second.

    The scale ``k`` is such that a star at ``(x_px, y_px)`` (default the
    sweet-spot pixel centre) observed for ``t_exp_s`` collects
    ``flux_aperture_e`` electrons inside a circle of ``radius_px`` centred on
    it: ``k = flux_aperture_e / (t_exp_s A(r))`` with ``A(r)`` the exact
    aperture sum of the unit-normalised PRF (the role of
    ``E_peak(3) a(r) / (PRF_peak a(3))`` in the paper's Eq. for e-dot).
    """
    if not flux_aperture_e > 0:
        raise InputError(f"flux_aperture_e: expected a positive flux in electrons, "
                         f"got {flux_aperture_e}")
    if not radius_px > 0 or not t_exp_s > 0:
        raise InputError("radius_px and t_exp_s: expected positive values")
    im = prf.render(np.array([x_px]), np.array([y_px]), shape=(32, 32))
    a = float(aperture_flux(im, x_px, y_px, radius_px)[0])
    return flux_aperture_e / (t_exp_s * a)


def jy_to_electrons_per_second(flux_jy, *, gain: float = constants.GAIN_E_PER_DN,
                               fluxconv: float = constants.FLUXCONV_WARM_CH2,
                               pixel_solid_angle_sr: float = constants.PIXEL_SOLID_ANGLE_SR):
    """Electron rate of a flux density: ``F_Jy GAIN / (1e6 Omega_pix FLUXCONV)`` e/s.

    (BCD = FLUXCONV e / (GAIN t) in MJy/sr; summing MJy/sr x Omega_pix x 1e6
    over the pixels of a source gives Jy.)
    """
    return np.asarray(flux_jy, float) * gain / (1e6 * pixel_solid_angle_sr * fluxconv)
