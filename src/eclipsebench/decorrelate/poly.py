"""SPCA's 2-D polynomial detector models ``poly2`` ... ``poly5`` (Bell et al. 2021).

Bell et al. (2021, MNRAS 504, 3316, Sect. 2) fit Spitzer's intra-pixel
sensitivity with a polynomial of total degree 2 to 5 in the centroid, as the
public SPCA code does (``detec_models.detec_model_poly``; centroids centred on
their mean in ``helpers.get_data``)::

    flux_t = astro_t * sum_{i + j <= N} c_ij (x_t - <x>)^i (y_t - <y>)^j  [* W_t]

with the optional PSF-width term of SPCA's ``detec_model_PSFW``::

    W_t = 1 + d_x (wx_t - <wx>) + d_y (wy_t - <wy>)

The coefficients ``c_ij`` enter linearly and are solved by weighted least
squares inside every evaluation, for the given astrophysical curve (the
framework's rule for linear pieces; SPCA samples them with the astrophysical
parameters in its MCMC). ``d_x`` and ``d_y`` multiply the polynomial, so they
are the method's own nonlinear parameters (``param_names``), fitted with the
astrophysical ones.

Numerics. The columns are Legendre products ``P_i(u) P_j(v)`` with ``i + j <=
N`` of the centroids centred on their mean and scaled to [-1, 1]: they span the
same polynomials as SPCA's monomials (a triangular change of basis), so the
least-squares model is the same, with far better conditioning. The columns are
then rotated once onto the right singular vectors of the weighted design (a
second change of basis of the same space, as SPCA itself puts PLD pixels
through a PCA); directions whose singular value is below ``1e-10`` of the
largest carry no information and are left out (counted in ``diagnostics``).

Binning. SPCA fits photometry median-binned per 64-frame data cube
(``Decorrelation.py``: ``nFrames = 64``; ``helpers.get_data`` reads the binned
files). Here the whole fit is made on means of ``bin_frames`` consecutive
frames (default 64; design and flux binned alike, so the binned fit is the
fit of the binned model): the coefficients, the residuals and the likelihood
the astrophysical parameters are fitted or sampled on are those of the bins,
as :mod:`eclipsebench.decorrelate.pld` does. The coefficients are then applied
to every frame for the corrected light curve.
"""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Annotated, Any, ClassVar, Protocol, cast

import numpy as np
from numpy.polynomial import legendre

from ..errors import InputError
from .base import AtLeast, EpochData, MethodOptions, OptionsT, register
from .linear import LinearDesign, LinearSystematics
from .record import MethodRecord, team_profile

__all__ = ["polynomial_terms", "legendre_design", "scaled_coordinate", "psf_width_columns",
           "whitened_basis", "LinearDetectorModel", "PolyOptions", "Poly2", "Poly3", "Poly4",
           "Poly5"]

#: Singular values below this fraction of the largest are dropped from the basis.
SINGULAR_RTOL = 1e-10


def polynomial_terms(order: int) -> list[tuple[int, int]]:
    """Exponents ``(i, j)`` of ``x^i y^j`` with ``i + j <= order``, in SPCA's order.

    Examples
    --------
    >>> polynomial_terms(2)
    [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)]
    >>> len(polynomial_terms(5))
    21
    """
    return [(d - j, j) for d in range(order + 1) for j in range(d + 1)]


def scaled_coordinate(values: np.ndarray) -> tuple[np.ndarray, float, float]:
    """``(v - mean) / half_range`` in [-1, 1], with the mean and half range (same units as v).

    A constant coordinate gives zeros (half range 1).

    Examples
    --------
    >>> u, centre, half = scaled_coordinate(np.array([15.0, 15.1, 15.4]))
    >>> round(centre, 6), round(half, 6), float(np.abs(u).max())
    (15.166667, 0.233333, 1.0)
    """
    v = np.asarray(values, float)
    centre = float(np.mean(v))
    half = float(np.max(np.abs(v - centre)))
    if not half > 0:
        half = 1.0
    return (v - centre) / half, centre, half


def legendre_design(u: np.ndarray, v: np.ndarray, order: int) -> np.ndarray:
    """Columns ``P_i(u) P_j(v)`` for ``(i, j)`` in :func:`polynomial_terms` (shape (n, k)).

    Examples
    --------
    >>> d = legendre_design(np.array([0.0, 1.0]), np.array([1.0, -1.0]), 2)
    >>> d.shape
    (2, 6)
    >>> d[1].tolist()     # u = 1, v = -1: 1, u, v, P2(u), u v, P2(v)
    [1.0, 1.0, -1.0, 1.0, -1.0, 1.0]
    """
    vu = legendre.legvander(np.asarray(u, float), order)
    vv = legendre.legvander(np.asarray(v, float), order)
    return np.column_stack([vu[:, i] * vv[:, j] for i, j in polynomial_terms(order)])


def whitened_basis(design: np.ndarray, flux_err: np.ndarray,
                   rtol: float = SINGULAR_RTOL) -> tuple[np.ndarray, int]:
    """The same column space, rotated so that the weighted columns are orthonormal.

    Returns ``(D @ V_k / s_k, n_dropped)`` from the SVD of ``D / flux_err``,
    ``D`` the design with unit-rms columns, keeping the singular values above ``rtol`` of the
    largest. A pure change of basis: a least-squares fit on the result gives
    the same model as on ``design`` (up to the dropped null directions).
    """
    d = np.asarray(design, float)
    # unit-rms columns first, so that only collinearity (not a column's size) counts as null
    scale = np.sqrt(np.mean(d**2, axis=0))
    scale[scale == 0] = 1.0
    d = d / scale
    _, s, vt = np.linalg.svd(d / np.asarray(flux_err, float)[:, None], full_matrices=False)
    keep = s > rtol * s[0]
    return d @ (vt[keep].T / s[keep]), int(np.count_nonzero(~keep))


def psf_width_columns(data: EpochData, method: str) -> np.ndarray:
    """The PSF widths ``(wx - <wx>, wy - <wy>)`` (px), shape (n, 2), for SPCA's PSFW term.

    Raises
    ------
    InputError
        When the data carry no ``width_x`` / ``width_y`` (one line naming the method).
    """
    wx, wy = getattr(data, "width_x", None), getattr(data, "width_y", None)
    if wx is None or wy is None:
        raise InputError(f"method '{method}' option 'psf_width': the epoch's data carry no PSF "
                         "widths (width_x, width_y)")
    w = np.column_stack([np.asarray(wx, float), np.asarray(wy, float)])
    if w.shape[0] != len(data) or not np.all(np.isfinite(w)):
        raise InputError(f"method '{method}' option 'psf_width': width_x and width_y must be "
                         f"{len(data)} finite values")
    return w - w.mean(axis=0)


#: SPCA's pipeline (Bell et al. 2021) for the paper profile: not a team of the paper.
#: The section of docs/methods.md on SPCA's family.
SPCA_DOCS_ANCHOR = "spcas-model-family-poly2--poly5-pld-aper"


class LinearModelOptions(Protocol):
    """The options every :class:`LinearDetectorModel` reads (its subclasses' dataclasses have them)."""

    bin_frames: int
    psf_width: bool


class LinearDetectorModel(LinearSystematics[OptionsT]):
    """A detector model linear in its coefficients, times SPCA's optional PSF-width term.

    ``flux = astro * W(theta) * (R c)``: ``R`` are the regressors of the
    subclass (:meth:`regressors`), ``c`` solved by weighted least squares for
    each ``astro * W`` (on bins of ``options.bin_frames`` frames), ``W = 1 +
    theta . (widths - mean)`` when ``options.psf_width`` is set (``theta`` =
    ``psfw_x_per_px``, ``psfw_y_per_px``), else 1. The options dataclass of a
    subclass must have ``bin_frames`` and ``psf_width``.
    """

    #: Names of the PSF-width slopes (relative flux change per pixel of width).
    PSFW_PARAMS: ClassVar[tuple[str, ...]] = ("psfw_x_per_px", "psfw_y_per_px")

    @property
    def linear_options(self) -> LinearModelOptions:
        """``self.options`` seen as what this class reads (``bin_frames``, ``psf_width``)."""
        return cast(LinearModelOptions, self.options)

    def setup(self, data: EpochData) -> None:
        bin_frames = int(self.linear_options.bin_frames)
        self.widths = psf_width_columns(data, self.name) if self.linear_options.psf_width else None
        self.param_names = self.PSFW_PARAMS if self.widths is not None else ()
        raw = self.regressors(data)
        basis, self.n_dropped_directions = whitened_basis(raw, data.flux_err)
        self.n_raw_regressors = raw.shape[1]
        n_points = -(-len(data) // bin_frames)
        if n_points <= basis.shape[1]:
            raise InputError(f"method '{self.name}': {n_points} (binned) points for "
                             f"{basis.shape[1]} regressors; use fewer bin_frames")
        self._design = LinearDesign(basis, data.flux, data.flux_err, bin_frames,
                                    time=data.time_bmjd)

    @abstractmethod
    def regressors(self, data: EpochData) -> np.ndarray:
        """The regressors ``R`` of the model, shape (n, k)."""

    @property
    def design(self) -> LinearDesign:
        """The regression on the whitened regressors (``with_flux`` swaps its target)."""
        return self._design

    def regressed_curve(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """``astro * W``: the PSF-width term ``W`` of ``theta`` (1 without it)."""
        astro = np.asarray(astro, float)
        if self.widths is None:
            return astro
        theta = np.zeros(2) if theta is None else np.asarray(theta, float)
        return astro * (1.0 + self.widths[:, 0] * theta[0] + self.widths[:, 1] * theta[1])

    def regressed_curves(self, astro: np.ndarray, theta: np.ndarray | None) -> np.ndarray:
        """``astro * W`` of every row of ``astro`` (m, n) and ``theta`` (m, 2) or None."""
        if self.widths is None:
            return astro
        theta = np.zeros((len(astro), 2)) if theta is None else np.atleast_2d(theta)
        return astro * (1.0 + self.widths[:, 0] * theta[:, :1] + self.widths[:, 1] * theta[:, 1:2])

    def with_flux(self, flux: np.ndarray) -> LinearDetectorModel:
        """The same design on new fluxes (equal to a fresh build)."""
        new = self._copy_with_flux(flux)
        new._design = self.design.with_flux(new.data.flux)
        return new

    def n_effective_params(self) -> int:
        """Linear coefficients in use plus the PSF-width slopes."""
        return int(self.design.n_regressors) + len(self.param_names)

    def diagnostics(self) -> dict[str, Any]:
        """Regressors, dropped null directions, bins and whether the PSF-width term is on."""
        return {"n_regressors": int(self.n_raw_regressors),
                "n_dropped_directions": int(self.n_dropped_directions),
                "bin_frames": int(self.linear_options.bin_frames),
                "n_fit_points": -(-len(self.data) // int(self.linear_options.bin_frames)),
                "psf_width": bool(self.linear_options.psf_width)}


@dataclass(frozen=True)
class PolyOptions(MethodOptions):
    """Options of ``poly2`` ... ``poly5``."""

    bin_frames: Annotated[int, AtLeast(1)] = 64
    psf_width: bool = False


class _Polynomial(LinearDetectorModel[PolyOptions]):
    """SPCA's 2-D polynomial of total degree ``order`` in the centroid (module docstring)."""

    order: ClassVar[int] = 0
    requires: ClassVar[tuple[str, ...]] = ("x", "y")

    def regressors(self, data: EpochData) -> np.ndarray:
        """Legendre products of the scaled centroids up to total degree ``order``."""
        u, self.x_centre_px, self.x_half_range_px = scaled_coordinate(data.x)
        v, self.y_centre_px, self.y_half_range_px = scaled_coordinate(data.y)
        return legendre_design(u, v, self.order)

    def diagnostics(self) -> dict[str, Any]:
        """The base diagnostics plus the order and the centroid centre and half range (px)."""
        return {**super().diagnostics(), "order": self.order,
                "x_centre_px": self.x_centre_px, "y_centre_px": self.y_centre_px,
                "x_half_range_px": self.x_half_range_px, "y_half_range_px": self.y_half_range_px}


def _poly_doc(order: int) -> str:
    n = len(polynomial_terms(order))
    return (f"SPCA's poly{order}: a 2-D polynomial of total degree {order} in (x, y), {n} "
            f"coefficients (Bell et al. 2021; options :class:`PolyOptions`).")


def _polynomial_method(order: int) -> type[_Polynomial]:
    """The registered class ``poly<order>`` (one class per order, as SPCA names its models)."""
    cls = type(f"Poly{order}", (_Polynomial,), {
        "__doc__": _poly_doc(order), "__module__": __name__, "name": f"poly{order}",
        "order": order,
        "record": MethodRecord(label=f"poly{order}", paper=team_profile("spca"),
                               docs_anchor=SPCA_DOCS_ANCHOR)})
    return register(cls)


Poly2, Poly3, Poly4, Poly5 = (_polynomial_method(order) for order in range(2, 6))
