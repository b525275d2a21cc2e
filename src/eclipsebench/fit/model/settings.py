"""Each event's own settings: one small frozen object per event, handed to its model.

:class:`~eclipsebench.fit.model.AstroModel` takes the keywords every event
reads (``phase``, ``ramp``, ``eclipse_shape``, ``shape``, ``period_d``,
``box_duration_d``) and one ``settings`` object of its event's class:
:class:`EclipseSettings` (none of its own), :class:`TransitSettings` (the
free transit parameters, their priors, the limb darkening) or
:class:`PhaseCurveSettings` (the limb darkening, the AOR offsets, the
exposure, the non-negative planet). ``from_options`` builds one from the
``[reduce]`` section, once, where the options are read
(:meth:`eclipsebench.fit.prepare.PreparedEpoch.astro_model`). A model given
another event's settings refuses them (one line), so a setting cannot be
silently ignored.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ...config.reduce import ReduceSection

__all__ = ["EclipseSettings", "TransitSettings", "PhaseCurveSettings", "OwnSettings"]


@dataclass(frozen=True)
class EclipseSettings:
    """The eclipse's own settings: none (its shape, period and box are every event's
    keywords)."""

    @classmethod
    def from_options(cls, options: ReduceSection, aorkey: Any = None) -> EclipseSettings:
        """The eclipse's settings of a ``[reduce]`` section (there are none)."""
        return cls()


@dataclass(frozen=True)
class TransitSettings:
    """The transit's own settings.

    Parameters
    ----------
    free : sequence of {"a_rs", "b", "q1", "q2"}
        The transit's parameters fitted besides ``rp_rs`` and
        ``t_transit_bmjd``; the others stay at the catalogue's ``a_rs``, impact
        parameter and limb darkening (or ``limb_darkening_q``).
    priors : mapping, optional
        ``{name: (mean, sigma)}``: a Gaussian prior on a free transit
        parameter (added to the least-squares residuals and the MCMC's
        log-probability); a free parameter without one has a uniform prior
        within its bounds.
    limb_darkening_q : (float, float), optional
        Kipping's q1, q2 (fixed values, or the start of free ones); default
        those of the catalogue's quadratic coefficients
        (:func:`~eclipsebench.fit.model.q_from_u`).
    """

    free: Sequence[str] = ()
    priors: Mapping[str, Sequence[float]] | None = None
    limb_darkening_q: Sequence[float] | None = None

    @classmethod
    def from_options(cls, options: ReduceSection, aorkey: Any = None) -> TransitSettings:
        """``[reduce]`` ``transit_free``, ``transit_priors`` and ``limb_darkening_q``."""
        return cls(free=options.transit_free, priors=options.transit_priors,
                   limb_darkening_q=options.limb_darkening_q)


@dataclass(frozen=True)
class PhaseCurveSettings:
    """A whole phase curve's own settings.

    Parameters
    ----------
    limb_darkening_q : (float, float), optional
        Kipping's q1, q2 of its transits (fixed); default the catalogue's.
    aorkey : array_like, shape (n,), optional
        The AOR of each frame: every AOR after the first gets a flux offset
        ``aor_offset_<k>``.
    exposure_s : float, optional
        The integration time of one row (default: the median cadence); rows
        longer than 10 s are averaged over sub-exposures
        (:func:`~eclipsebench.fit.model.integration_offsets_d`).
    nonnegative_planet : bool
        The prior ``p(t) >= 0`` over the orbit (a penalty residual for least
        squares, ``-inf`` log-prior for the MCMC).
    """

    limb_darkening_q: Sequence[float] | None = None
    aorkey: Any = None
    exposure_s: float | None = None
    nonnegative_planet: bool = False

    @classmethod
    def from_options(cls, options: ReduceSection, aorkey: Any = None) -> PhaseCurveSettings:
        """``[reduce]`` ``limb_darkening_q``, ``exposure_s`` (0: the cadence) and
        ``nonnegative_planet``; ``aorkey`` (the frames' AORs) gives an offset per AOR
        when ``aor_offsets`` is on and each AOR does not have its own systematics."""
        offsets = options.aor_offsets and not options.systematics_per_aor
        return cls(limb_darkening_q=options.limb_darkening_q,
                   aorkey=aorkey if offsets else None,
                   exposure_s=options.exposure_s or None,
                   nonnegative_planet=options.nonnegative_planet)


#: The settings object of any event.
OwnSettings = EclipseSettings | TransitSettings | PhaseCurveSettings
