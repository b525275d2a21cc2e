"""The interface every systematics model implements, and the registry.

A method models the instrument's correlated noise; one astrophysical model
(eclipse, phase curve, ramp; :mod:`eclipsebench.fit`) is shared by all of
them. The joint model of the measured flux is::

    model = systematics.predict(astro, theta_sys)

where ``astro`` is the astrophysical light curve (1 = the star alone) and
``theta_sys`` the method's own nonlinear parameters (empty for most). Linear
or non-parametric pieces (PLD coefficients, BLISS knots, kernel-regression
averages, ICA component weights) are solved *inside* ``predict`` for the
given ``astro``, as the original methods do.

Work that does not depend on fitted parameters (knot assignment, neighbour
lists, design matrices, kernel factorisations) happens once in ``__init__``,
as batman's ``TransitModel`` does; ``predict`` is the cheap call a fitter
repeats thousands of times.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ..errors import InputError

__all__ = ["EpochData", "Systematics", "register", "get_method", "available_methods"]


@dataclass(frozen=True)
class EpochData:
    """The good frames of one epoch, as arrays (no flagged frames).

    Attributes
    ----------
    time_bmjd : ndarray, shape (n,)
        Mid-exposure times, BMJD_TDB.
    flux, flux_err : ndarray, shape (n,)
        Aperture flux and its uncertainty, electrons.
    x, y : ndarray, shape (n,)
        Centroids, 0-based pixel coordinates (centre of the first pixel at 0).
    noise_pixels : ndarray, shape (n,)
        Noise pixels beta (paper Eq. ``noise_pixels``).
    pixels : ndarray, shape (n, p) or None
        Background-subtracted pixel values of a stamp (3x3 -> p = 9), for PLD
        and ICA.
    aorkey : ndarray, shape (n,)
        AOR of each frame.
    meta : dict
        Provenance (input files, simulation folder, options).
    """

    time_bmjd: np.ndarray
    flux: np.ndarray
    flux_err: np.ndarray
    x: np.ndarray
    y: np.ndarray
    noise_pixels: np.ndarray | None = None
    pixels: np.ndarray | None = None
    aorkey: np.ndarray | None = None
    meta: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.time_bmjd)
        for name in ("flux", "flux_err", "x", "y", "noise_pixels", "aorkey"):
            arr = getattr(self, name)
            if arr is not None and len(arr) != n:
                raise InputError(f"column '{name}': expected {n} values, got {len(arr)}")
        if self.pixels is not None and self.pixels.shape[0] != n:
            raise InputError(f"pixel stamps: expected {n} rows, got {self.pixels.shape[0]}")
        if n == 0:
            raise InputError("no good frames to fit")

    def __len__(self) -> int:
        return len(self.time_bmjd)

    def subset(self, index: np.ndarray) -> EpochData:
        """A new EpochData with only the frames selected by ``index``."""
        def take(a):
            return None if a is None else np.asarray(a)[index]
        return EpochData(time_bmjd=take(self.time_bmjd), flux=take(self.flux),
                         flux_err=take(self.flux_err), x=take(self.x), y=take(self.y),
                         noise_pixels=take(self.noise_pixels), pixels=take(self.pixels),
                         aorkey=take(self.aorkey), meta=dict(self.meta))


class Systematics(ABC):
    """Base class of a systematics model.

    Subclasses set ``name`` (the registry name), ``requires`` (the EpochData
    attributes that must not be None) and implement :meth:`predict`. They do
    all parameter-independent work in ``__init__``.

    Parameters
    ----------
    data : EpochData
        The frames to model. Never modified.
    **options
        Method-specific, keyword-only options (documented per method).
    """

    name: ClassVar[str] = ""
    requires: ClassVar[tuple[str, ...]] = ()
    #: Names of the method's own nonlinear parameters, fitted with the astrophysical ones.
    param_names: ClassVar[tuple[str, ...]] = ()
    #: Whether predict() returns the full flux model (True) or the method is a
    #: pre-processing detrend whose output the fitter models directly.
    description: ClassVar[str] = ""
    #: The emcee move the fitter uses for this method's MCMC: "stretch" (the
    #: affine-invariant default) or "de" (differential evolution, the DE-MC of
    #: the BLISS team; ter Braak 2006).
    preferred_move: ClassVar[str] = "stretch"
    #: The eclipse shape the fitter uses when ``[reduce] eclipse_shape = "auto"``:
    #: "physical" (the orbit's) or "box" (the faithful default of SP(K2)).
    default_eclipse_shape: ClassVar[str] = "physical"
    #: Whether the fitter's prayer-bead error applies to this method. A method
    #: whose model follows the correlated noise itself (a GP's conditional
    #: mean) leaves residuals that are not the noise the bead should shift,
    #: and may set this to False (its errors then come from the Jacobian and MCMC).
    use_prayer_bead: ClassVar[bool] = True

    def __init__(self, data: EpochData, **options: Any) -> None:
        missing = [c for c in self.requires if getattr(data, c, None) is None]
        if missing:
            raise InputError(f"method '{self.name}' needs the column(s) {', '.join(missing)} "
                             "in the photometry table")
        self.data = data
        self.options = dict(options)

    def initial_params(self) -> np.ndarray:
        """Starting values of the method's own parameters (default: none)."""
        return np.zeros(len(self.param_names))

    def param_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the method's own parameters."""
        n = len(self.param_names)
        return np.full(n, -np.inf), np.full(n, np.inf)

    @abstractmethod
    def predict(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """The model of ``data.flux`` (electrons) for the astrophysical curve ``astro``.

        Parameters
        ----------
        astro : ndarray, shape (n,)
            Astrophysical light curve, normalised so that 1 is the star alone.
        theta : ndarray or None
            The method's own parameters (``param_names``), or None.
        """

    def log_likelihood(self, astro: np.ndarray, theta: np.ndarray | None = None,
                       noise_scale: float = 1.0) -> float:
        """Gaussian log-likelihood of the data given ``astro`` (default: white noise).

        Methods with correlated-noise likelihoods (GP) override this.
        """
        model = self.predict(astro, theta)
        sigma = self.data.flux_err * noise_scale
        r = (self.data.flux - model) / sigma
        return float(-0.5 * np.dot(r, r) - np.sum(np.log(sigma)) - 0.5 * len(r) * np.log(2 * np.pi))

    def residuals(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Normalised residuals ``(flux - model) / flux_err`` (for least squares)."""
        return (self.data.flux - self.predict(astro, theta)) / self.data.flux_err

    def correct(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """The decorrelated light curve: ``flux / (model / astro)``, in units of the star."""
        systematic = self.predict(astro, theta) / astro
        return self.data.flux / systematic

    def with_flux(self, flux: np.ndarray) -> Systematics:
        """The same method (same options) rebuilt on ``data`` with ``flux`` replaced.

        Used by the prayer bead, which refits the model plus shifted residuals.
        ``flux`` has the length of ``self.data``. Methods whose ``__init__``
        transforms the data (binning, say) override this so that the new
        fluxes are not transformed twice.
        """
        from dataclasses import replace
        return type(self)(replace(self.data, flux=np.asarray(flux, dtype=float)), **self.options)

    def optimise_hyperparameters(self, astro: np.ndarray) -> dict[str, Any] | None:
        """Re-set parameters that the method fixes by maximum likelihood for a given ``astro``.

        The fitter alternates this with the least-squares fit of the joint
        parameters (coordinate ascent) for methods that override it (GP: kernel
        and white-noise parameters). The default does nothing and returns None.
        """
        return None

    def extra_depth_variance(self, astro: np.ndarray, dastro_ddepth: np.ndarray) -> float:
        """A variance of the depth (fraction squared) that the fit cannot see, default 0.

        The fitter adds it to the depth variance (ICA: the component-separation
        error). ``dastro_ddepth`` is the derivative of ``astro`` with respect to
        the depth at the solution.
        """
        return 0.0

    def n_effective_params(self) -> int:
        """Free parameters that the systematics model adds, for BIC and AIC."""
        return len(self.param_names)


_REGISTRY: dict[str, type[Systematics]] = {}


def register(cls: type[Systematics]) -> type[Systematics]:
    """Class decorator: add a Systematics subclass to the registry under ``cls.name``."""
    if not cls.name:
        raise TypeError(f"{cls.__name__} has no registry name")
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise TypeError(f"method name '{cls.name}' is registered twice")
    _REGISTRY[cls.name] = cls
    return cls


def get_method(name: str) -> type[Systematics]:
    """The registered class called ``name``; InputError listing the known names otherwise."""
    try:
        return _REGISTRY[name]
    except KeyError:
        known = ", ".join(available_methods()) or "none"
        raise InputError(f"--method {name!r}: unknown method (known: {known})") from None


def available_methods() -> tuple[str, ...]:
    """Registered method names in the paper's order where it has one."""
    order = ["bliss", "gp", "ica", "kr-data", "kr-pmap", "pld", "segpoly"]
    names = sorted(_REGISTRY, key=lambda n: (order.index(n) if n in order else len(order), n))
    return tuple(names)
