"""SPCA's ``PLDAper``: pixel-level decorrelation of the aperture flux (Bell et al. 2021).

SPCA (``detec_models.detec_model_PLD``, ``helpers.get_data``) models the flux as
the astrophysical curve times a linear combination of the stamp's pixels, each
divided by the stamp's sum in the same frame (Deming et al. 2015, Eq. 3)::

    flux_t = astro_t * sum_i c_i P_it / sum_j P_jt  [* W_t]

``PLDAper`` is how SPCA combines this with aperture photometry: the *fitted
flux* is the aperture photometry (``foldername_aper``; "strongly recommended
as this gives much cleaner photometry than the sum of the PLD stamp",
``Decorrelation.py``), while the regressors stay the normalised pixels of the
3x3 or 5x5 stamp. The aperture flux is not a regressor. SPCA's plain ``PLD``
fits the sum of the stamp instead and is not built here. ``W_t`` is SPCA's
optional PSF-width term (:mod:`eclipsebench.decorrelate.poly`).

SPCA passes the normalised pixels through a PCA and prepends a constant
(``Decorrelation.py``); since the normalised pixels sum to 1 this spans the
same space, so the least-squares model is unchanged (here the columns are
likewise rotated onto the weighted design's singular vectors, for
conditioning only). As the polynomial models, the whole fit is made on means
of ``bin_frames`` consecutive frames (default 64: SPCA fits 64-frame data
cubes), and the coefficients are applied to every frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from .base import EpochData, register
from .pld import central_stamp, normalised_pixels
from .poly import SPCA_DOCS_ANCHOR, LinearDetectorModel, PolyOptions
from .record import MethodRecord, team_profile

__all__ = ["PldAperOptions", "PldAperture"]


@dataclass(frozen=True)
class PldAperOptions(PolyOptions):
    """Options of ``pld-aper`` (:class:`PldAperture`)."""

    stamp: Literal[3, 5] = 3


@register
class PldAperture(LinearDetectorModel[PldAperOptions]):
    """SPCA's PLDAper: the aperture flux fitted with normalised 3x3 or 5x5 pixels.

    Options (:class:`PldAperOptions`)
    ---------------------------------
    stamp : int, 3 or 5, default 3
        Side of the stamp (a 5x5 table stamp is cut to 3x3 when 3).
    bin_frames : int, default 64
        Fit on means of this many consecutive frames.
    psf_width : bool, default False
        Multiply by SPCA's PSF-width term (needs ``width_x``, ``width_y``).
    """

    name: ClassVar[str] = "pld-aper"
    requires: ClassVar[tuple[str, ...]] = ("pixels",)
    record: ClassVar[MethodRecord] = MethodRecord(label="pld-aper", paper=team_profile("spca"),
                                                  docs_anchor=SPCA_DOCS_ANCHOR)

    def regressors(self, data: EpochData) -> np.ndarray:
        """The normalised pixels ``P_i / sum P`` of the central stamp."""
        return normalised_pixels(central_stamp(data.column("pixels"), int(self.options.stamp)))

    def diagnostics(self) -> dict[str, Any]:
        """The base diagnostics plus the stamp side."""
        return {**super().diagnostics(), "stamp": int(self.options.stamp)}
