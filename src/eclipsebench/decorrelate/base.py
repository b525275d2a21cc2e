"""The interface every systematics model implements, its options and context, and the registry.

A method models the instrument's correlated noise; one astrophysical model
(eclipse, phase curve, ramp; :mod:`eclipsebench.fit`) is shared by all of
them. The joint model of the measured flux is::

    model = systematics.predict(astro, theta_sys)

where ``astro`` is the astrophysical light curve (1 = the star alone) and
``theta_sys`` the method's own nonlinear parameters (empty for most). Linear
or non-parametric pieces (PLD coefficients, BLISS knots, kernel-regression
averages, ICA component weights) are solved *inside* ``predict`` for the
given ``astro``, as the original methods do.

A method is built from three things (``docs/architecture.md``, "the method seam"):

* the epoch's data (:class:`EpochData`, arrays only);
* its options, a frozen dataclass (``cls.Options``, a :class:`MethodOptions`)
  validated at the edge: an unknown or ill-typed option is one
  :class:`~eclipsebench.errors.InputError` naming it;
* a :class:`MethodContext`: the random streams of this run, epoch and method,
  and the resources the caller already loaded (a calibration set, as arrays).

Work that does not depend on fitted parameters (knot assignment, neighbour
lists, design matrices, kernel factorisations) happens once in ``__init__``,
as batman's ``TransitModel`` does; ``predict`` is the cheap call a fitter
repeats thousands of times. :meth:`Systematics.diagnostics` reports what the
build found (sparse knots, low occupancy, separation errors) so that it
reaches the result file, as lightkurve's correctors keep theirs.

Methods register by name with :func:`register`; other packages add theirs
through the entry-point group ``eclipsebench.methods`` (name = method name,
value = ``module:Class``), loaded the first time the registry is read.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import warnings
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any, ClassVar, Generic, Self, TypeVar, cast, get_type_hints

import numpy as np

from ..config.base import check, coerce
from ..errors import ConfigError, InputError
from ..io.paths import SAFE_NAME, is_safe_name
from ..seeding import rng, spawn_ints
from .record import FitterPolicy, MethodRecord, PaperProfile, heading_anchor

__all__ = ["EpochData", "AtLeast", "MethodOptions", "MethodContext", "Systematics", "MethodRecord",
           "FitterPolicy", "PaperProfile", "register",
           "get_method", "method_class", "available_methods", "unknown_methods",
           "parse_method_options", "ENTRY_POINT_GROUP"]

#: The entry-point group through which other packages register methods.
ENTRY_POINT_GROUP = "eclipsebench.methods"


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
        Provenance (input files, simulation folder, options); ``meta["table_columns"]``
        may name the photometry-table column behind an attribute (``{"pixels":
        "stamp3 pixels (or p0..p8)"}``), for messages (:meth:`table_column`).
    width_x, width_y : ndarray, shape (n,) or None
        PSF widths (px) when the table has them (SPCA's PSF-width term). Not
        checked for finite values here: a method that uses them checks them.
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
    width_x: np.ndarray | None = None
    width_y: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = len(self.time_bmjd)
        for name in ("flux", "flux_err", "x", "y", "noise_pixels", "aorkey", "width_x",
                     "width_y"):
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
                         aorkey=take(self.aorkey), meta=dict(self.meta),
                         width_x=take(self.width_x), width_y=take(self.width_y))

    def column(self, name: str) -> np.ndarray:
        """The optional column ``name`` (``"pixels"``, ``"noise_pixels"``, ...), which must be there.

        A method lists the columns it needs in ``requires`` and the base class
        refuses data without them; this returns one with its type narrowed.
        """
        value = getattr(self, name)
        if value is None:
            raise InputError(f"no column {self.table_column(name)} in the photometry table")
        return value

    def table_column(self, name: str) -> str:
        """The photometry-table column behind the attribute ``name``, for messages.

        Examples
        --------
        >>> d = EpochData(time_bmjd=np.zeros(1), flux=np.ones(1), flux_err=np.ones(1),
        ...               x=np.zeros(1), y=np.zeros(1))
        >>> d.table_column("pixels"), d.table_column("noise_pixels")
        ('stamp3 pixels (or p0..p8)', 'noise_pixels')
        """
        labels = {"pixels": "stamp3 pixels (or p0..p8)", **dict(self.meta.get("table_columns") or {})}
        return str(labels.get(name, name))


@dataclass(frozen=True)
class AtLeast:
    """An integer option's lower bound, declared with its type: ``k: Annotated[int, AtLeast(1)]``.

    :class:`MethodOptions` checks it when an instance is made, before ``validate``.
    """

    minimum: int


@dataclass(frozen=True)
class MethodOptions:
    """Base of every method's options: a frozen dataclass, one field per option.

    A subclass declares typed fields with defaults (an integer's lower
    bound with its type: ``Annotated[int, AtLeast(1)]``) and may add other checks
    in ``validate`` (raise :class:`~eclipsebench.errors.ConfigError` naming
    the field, with :func:`eclipsebench.config.check`). An instance is
    checked when it is made (``__post_init__``): each value given is taken
    as its field's type (a list as a tuple, an integer as a float where a
    number is declared), then ``validate`` runs; so an options object is
    valid from the moment it exists, and a method trusts the one it gets.
    Build one from names and values with :func:`parse_method_options`, which
    also refuses unknown names.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class KnnOptions(MethodOptions):
    ...     k: int = 50
    >>> KnnOptions().to_dict()
    {'k': 50}
    """

    def __post_init__(self) -> None:
        # A subclass that defines its own __post_init__ calls this one.
        types, declared = get_type_hints(type(self)), get_type_hints(type(self),
                                                                     include_extras=True)
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is not f.default:   # the class's own default is as it declared it
                value = coerce(value, types[f.name], f.name)
                object.__setattr__(self, f.name, value)
            for bound in getattr(declared[f.name], "__metadata__", ()):
                if isinstance(bound, AtLeast):
                    check(value >= bound.minimum, f.name, f"an integer >= {bound.minimum}")
        self.validate()

    def validate(self) -> None:
        """Range checks beyond the field types (default: none)."""

    def to_dict(self) -> dict[str, Any]:
        """The options as a JSON-able dict (tuples become lists)."""
        def plain(v):
            return [plain(x) for x in v] if isinstance(v, tuple) else v
        return {f.name: plain(getattr(self, f.name)) for f in dataclasses.fields(self)}


#: The options dataclass of a method (``Systematics[BlissOptions]``).
OptionsT = TypeVar("OptionsT", bound=MethodOptions)


def parse_method_options(cls: type[Systematics[OptionsT]], options: Any = None, *,
                         prefix: str | None = None,
                         base: OptionsT | None = None) -> OptionsT:
    """``cls.Options`` from None, a mapping or an options instance: the one place options
    are parsed.

    An instance of ``cls.Options`` is returned as it is (it was checked when
    it was made); a mapping is checked once, names and values, into a new
    instance.

    Parameters
    ----------
    cls : type
        The method class (its ``Options`` and ``name`` are used).
    options : None, Mapping or MethodOptions
        The options to check; None gives ``base`` (default: the defaults).
    prefix : str, optional
        A configuration path (``"reduce.options.bliss"``): errors are then
        :class:`~eclipsebench.errors.ConfigError` naming the dotted key.
        Without it, errors name the method and the option.
    base : MethodOptions, optional
        An instance of ``cls.Options`` whose values a mapping overrides, name
        by name (e.g. a configuration's table under the command line's
        ``--option`` values); default the class's defaults.

    Raises
    ------
    InputError
        An unknown option, a value of the wrong type or out of range.

    Examples
    --------
    >>> from eclipsebench.decorrelate import get_method
    >>> parse_method_options(get_method("kr-data"), {"k": 30}).k
    30
    >>> parse_method_options(get_method("kr-data"), {"kk": 30})
    Traceback (most recent call last):
    ...
    eclipsebench.errors.InputError: method 'kr-data' option 'kk': unknown option (known: k, use_noise_pixels)
    >>> kr = parse_method_options(get_method("kr-data"), {"k": 30})
    >>> parse_method_options(get_method("kr-data"), {"use_noise_pixels": True}, base=kr)
    KrDataOptions(k=30, use_noise_pixels=True)
    """
    opts_cls = cls.Options
    if isinstance(options, opts_cls):
        return cast(OptionsT, options)
    if isinstance(options, MethodOptions):
        raise InputError(f"method '{cls.name}' options: expected {opts_cls.__name__}, "
                         f"got {type(options).__name__}")
    if options is None:
        mapping: dict[str, Any] = {}
    elif isinstance(options, Mapping):
        mapping = {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in options.items()}
    else:
        raise InputError(f"method '{cls.name}' options: expected a mapping of option names "
                         f"to values, got {type(options).__name__}")
    try:
        known = sorted(f.name for f in dataclasses.fields(opts_cls))
        for key in mapping:
            if key not in known:
                raise ConfigError(key, "unknown key (known: " + ", ".join(known) + ")")
        if base is None:
            return cast(OptionsT, opts_cls(**mapping))
        return dataclasses.replace(base, **mapping) if mapping else base
    except ConfigError as exc:
        if prefix is not None:
            raise ConfigError(f"{prefix}.{exc.key}", exc.problem) from None
        problem = exc.problem.replace("unknown key", "unknown option")
        raise InputError(f"method '{cls.name}' option '{exc.key}': {problem}") from None


@dataclass(frozen=True)
class MethodContext:
    """What a method gets from its caller besides data and options.

    Attributes
    ----------
    seed : int
        The run seed.
    epoch : int
        The epoch number (0 when unknown).
    method : str
        The method's registry name: part of every random stream's key.
    resources : Mapping
        Inputs the caller already loaded, by name (``"pmap"``: a calibration
        set or gridded pixel map, as arrays). A method lists the names it
        needs in ``Systematics.resources`` and loads them from paths in its
        ``load_resources`` classmethod, which the caller runs.

    Notes
    -----
    The random streams are ``rng(seed, "reduce", epoch, method, *key)``
    (:mod:`eclipsebench.seeding`): a method asks for one per purpose with
    :meth:`stream`, so rebuilding the method (the prayer bead's refits) gives
    the same numbers and no stream depends on what ran before it.

    Examples
    --------
    >>> ctx = MethodContext(seed=1, epoch=3, method="ica")
    >>> a = ctx.stream("bootstrap").normal()
    >>> a == MethodContext(seed=1, epoch=3, method="ica").stream("bootstrap").normal()
    True
    """

    seed: int = 0
    epoch: int = 0
    method: str = ""
    resources: Mapping[str, Any] = field(default_factory=dict)

    @property
    def rng(self) -> np.random.Generator:
        """The method's own stream, ``rng(seed, "reduce", epoch, method)``."""
        return rng(self.seed, "reduce", self.epoch, self.method)

    def stream(self, *key: object) -> np.random.Generator:
        """An independent Generator for the purpose ``key`` (e.g. ``"bootstrap"``)."""
        return rng(self.seed, "reduce", self.epoch, self.method, *key)

    def stream_ints(self, *key: object, n: int = 1) -> list[int]:
        """``n`` 32-bit integer seeds for libraries that take an int (scikit-learn)."""
        return spawn_ints(self.seed, "reduce", self.epoch, self.method, *key, n=n)

    def resource(self, name: str) -> Any:
        """The loaded resource ``name``; InputError naming the method if absent."""
        try:
            return self.resources[name]
        except KeyError:
            raise InputError(f"method '{self.method}': needs the resource '{name}', "
                             "which was not given") from None


class Systematics(ABC, Generic[OptionsT]):
    """Base class of a systematics model.

    Subclasses set ``name`` (the registry name), ``requires`` (the EpochData
    attributes that must not be None), their options as the class's type
    parameter (``class Bliss(Systematics[BlissOptions])``: a
    :class:`MethodOptions` dataclass, which becomes ``Options`` and types
    ``self.options``) and implement :meth:`predict`. They do all
    parameter-independent work in :meth:`setup`, reading their settings from
    ``self.options`` and their random streams and resources from
    ``self.context``.

    Parameters
    ----------
    data : EpochData
        The frames to model. Never modified.
    options : MethodOptions, optional
        The method's options: an instance of ``cls.Options``, taken as it is
        (the caller's edge resolved it once: :func:`parse_method_options`,
        ``eclipsebench.fit.prepare.resolve_method_options``); a mapping is
        refused (TypeError). Default: the class's defaults.
    context : MethodContext, optional
        Random streams and loaded resources (default: seed 0, epoch 0).
    **kwargs
        Options given as keywords (a notebook's ``Bliss(data, knot_spacing_px=0.1)``),
        checked and merged over ``options``.
    """

    name: ClassVar[str] = ""
    requires: ClassVar[tuple[str, ...]] = ()
    #: The options dataclass; a method without options keeps the empty base.
    Options: ClassVar[type[MethodOptions]] = MethodOptions
    #: Names of the context resources the method needs (see ``load_resources``).
    resources: ClassVar[tuple[str, ...]] = ()
    #: Names of the method's own nonlinear parameters, fitted with the astrophysical ones
    #: (an instance may set its own when its options add parameters: GP, SPCA's PSF width).
    param_names: tuple[str, ...] = ()
    description: ClassVar[str] = ""
    #: The method's facts beside its code: label, fitter policy, paper profile, docs
    #: anchor (:class:`~eclipsebench.decorrelate.record.MethodRecord`). :func:`register`
    #: gives a class that sets none its own default record (its parent's policy, no
    #: paper profile: it runs in the paper profile as in the controlled one).
    record: ClassVar[MethodRecord] = MethodRecord()
    #: The method's options: an instance of ``type(self).Options``.
    options: OptionsT

    def __init__(self, data: EpochData, options: MethodOptions | None = None,
                 *, context: MethodContext | None = None, **kwargs: Any) -> None:
        cls = type(self)
        if options is not None and not isinstance(options, MethodOptions):
            # options are resolved once, at the edge (eb.reduce, the commands, the planners):
            # a raw mapping here would be a second resolution
            raise TypeError(f"method '{cls.name}': options must be its {cls.Options.__name__} "
                            "(eclipsebench.fit.prepare.resolve_method_options) or keywords, "
                            f"not {type(options).__name__}")
        self.options = parse_method_options(cls, options)
        if kwargs:
            self.options = parse_method_options(cls, kwargs, base=self.options)
        missing = [data.table_column(c) for c in self.requires if getattr(data, c, None) is None]
        if missing:
            raise InputError(f"method '{self.name}' needs the column(s) {', '.join(missing)} "
                             "in the photometry table")
        self.data = data
        self.context = context if context is not None else MethodContext(method=self.name)
        self.setup(data)

    def __init_subclass__(cls, **kwargs: Any) -> None:
        """What a subclass does not set itself: ``Options`` from its type parameter
        (``Systematics[BlissOptions]``), ``description`` from its docstring's summary."""
        super().__init_subclass__(**kwargs)
        if "description" not in cls.__dict__ and cls.__doc__:
            cls.description = " ".join(cls.__doc__.strip().split("\n\n")[0].split())
        if "Options" in cls.__dict__:
            return
        for base in cls.__dict__.get("__orig_bases__", ()):
            for arg in getattr(base, "__args__", ()):
                if isinstance(arg, type) and issubclass(arg, MethodOptions):
                    cls.Options = arg
                    return

    def setup(self, data: EpochData) -> None:
        """The method's parameter-independent work, once, when it is built.

        Called at the end of ``__init__`` with its options parsed
        (``self.options``) and its streams and resources in ``self.context``.
        The default does nothing.
        """

    @classmethod
    def build(cls, data: EpochData, options: MethodOptions | None = None,
              *, seed: int = 0, epoch: int = 0,
              resources: Mapping[str, Any] | None = None, **kwargs: Any) -> Self:
        """Build the method as the reducer does: resources loaded, streams from ``seed``.

        Parameters
        ----------
        data : EpochData
            The frames.
        options : MethodOptions, optional
            The method's options (an instance of ``cls.Options``, resolved at the
            edge); ``kwargs`` override them by name, checked as the constructor's.
        seed, epoch : int
            Run seed and epoch number of the random streams.
        resources : Mapping, optional
            Paths or loaded objects for the names in ``cls.resources``.
        """
        context = MethodContext(seed=int(seed), epoch=int(epoch), method=cls.name,
                                resources=cls.load_resources(data, dict(resources or {})))
        return cls(data, options, context=context, **kwargs)

    @classmethod
    def load_resources(cls, data: EpochData, sources: Mapping[str, Any]) -> dict[str, Any]:
        """Turn the caller's resource arguments (paths or loaded objects) into arrays.

        The caller runs this before building the method and puts the result in
        :attr:`MethodContext.resources`. The default takes ``sources`` as they are.
        """
        return {k: v for k, v in sources.items() if k in cls.resources and v is not None}

    @property
    def policy(self) -> FitterPolicy:
        """How the shared fitter treats this method (``record.policy``)."""
        return self.record.policy

    def diagnostics(self) -> dict[str, Any]:
        """What the build found, JSON-able (written under ``diagnostics`` in results)."""
        return {}

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

    def log_likelihood_batch(self, astro: np.ndarray, theta: np.ndarray | None = None,
                             noise_scale: float = 1.0) -> np.ndarray:
        """:meth:`log_likelihood` of ``m`` astrophysical curves at once (the MCMC's call).

        The MCMC evaluates every walker of a step in one call (emcee's
        ``vectorize=True``). The default loops over :meth:`log_likelihood`, so
        it is right for any method; a method overrides it where its linear
        pieces can be solved for all curves together (batched normal
        equations, one sparse product for all walkers), returning the same
        values to rounding (the contract test compares the two).

        Parameters
        ----------
        astro : ndarray, shape (m, n)
            One astrophysical curve per row, at ``data.time_bmjd``.
        theta : ndarray, shape (m, k), or None
            The method's own parameters of each curve (``param_names``), or None.
        noise_scale : float
            As for :meth:`log_likelihood`.

        Returns
        -------
        ndarray, shape (m,)

        Examples
        --------
        >>> from eclipsebench.decorrelate import get_method
        >>> n = 200
        >>> d = EpochData(time_bmjd=np.arange(n) / 1440, flux=np.full(n, 1e5),
        ...               flux_err=np.full(n, 300.0), x=np.linspace(14.9, 15.1, n),
        ...               y=np.full(n, 15.0))
        >>> m = get_method("poly2")(d, bin_frames=1)
        >>> astro = np.vstack([np.ones(n), np.full(n, 1.001)])
        >>> batch = m.log_likelihood_batch(astro)
        >>> bool(np.allclose(batch, [m.log_likelihood(a) for a in astro], rtol=1e-12))
        True
        """
        astro = np.atleast_2d(np.asarray(astro, dtype=float))
        out = np.empty(len(astro))
        for i, row in enumerate(astro):
            out[i] = self.log_likelihood(row, None if theta is None else theta[i],
                                         noise_scale=noise_scale)
        return out

    def _batch_is_exact(self, owner: type) -> bool:
        """Whether ``owner``'s vectorised likelihood describes this instance.

        True unless a class below ``owner`` redefined :meth:`predict`,
        :meth:`residuals` or :meth:`log_likelihood` (a plugin subclassing a
        built-in method): its overrides of :meth:`log_likelihood_batch` then
        fall back to the loop.
        """
        cls = type(self)
        return all(getattr(cls, name) is getattr(owner, name)
                   for name in ("predict", "residuals", "log_likelihood"))

    def _white_log_likelihood_batch(self, model: np.ndarray, noise_scale: float) -> np.ndarray:
        """The default white-noise :meth:`log_likelihood` of each row of ``model`` (electrons)."""
        sigma = self.data.flux_err * noise_scale
        r = (self.data.flux - model) / sigma
        return (-0.5 * np.einsum("ij,ij->i", r, r) - np.sum(np.log(sigma))
                - 0.5 * r.shape[1] * np.log(2 * np.pi))

    def residuals(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """Normalised residuals ``(flux - model) / flux_err`` (for least squares)."""
        return (self.data.flux - self.predict(astro, theta)) / self.data.flux_err

    def residuals_batch(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """:meth:`residuals` of ``m`` astrophysical curves at once (a Jacobian's columns).

        The default loops over :meth:`residuals`; a method overrides it where
        all curves share one pass (KR/Data), returning the same values, so
        that a fit is the same whichever is called.

        Parameters
        ----------
        astro : ndarray, shape (m, n)
            One astrophysical curve per row, at ``data.time_bmjd``.
        theta : ndarray, shape (m, k), or None
            The method's own parameters of each curve (``param_names``), or None.

        Returns
        -------
        ndarray, shape (m, len(residuals))
        """
        return np.stack([self.residuals(a, None if theta is None else theta[i])
                         for i, a in enumerate(np.atleast_2d(astro))])

    def correct(self, astro: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """The decorrelated light curve: ``flux / (model / astro)``, in units of the star."""
        systematic = self.predict(astro, theta) / astro
        return self.data.flux / systematic

    def with_flux(self, flux: np.ndarray) -> Self:
        """The same method (same options and context) rebuilt on ``data`` with ``flux`` replaced.

        Used by the prayer bead, which refits the model plus shifted residuals.
        ``flux`` has the length of ``self.data``. Methods whose ``__init__``
        transforms the data (binning, say) override this so that the new
        fluxes are not transformed twice; the contract tests check that the
        result equals a fresh build.
        """
        flux = self._checked_flux(flux)
        return type(self)(dataclasses.replace(self.data, flux=flux), self.options,
                          context=self.context)

    def _checked_flux(self, flux: np.ndarray) -> np.ndarray:
        """``flux`` as floats, one per point of ``self.data``; InputError otherwise."""
        flux = np.asarray(flux, dtype=float)
        if flux.shape != self.data.flux.shape:
            raise InputError(f"method '{self.name}' with_flux: expected "
                             f"{self.data.flux.shape[0]} fluxes, got {flux.shape}")
        return flux

    def _copy_with_flux(self, flux: np.ndarray) -> Self:
        """A shallow copy whose ``data.flux`` is ``flux`` (checked), for ``with_flux``
        overrides that reuse the flux-independent work and redo only what the flux enters."""
        flux = self._checked_flux(flux)
        new = copy.copy(self)
        new.data = dataclasses.replace(self.data, flux=flux)
        return new

    def optimise_hyperparameters(self, astro: np.ndarray) -> dict[str, Any] | None:
        """Re-set parameters that the method fixes by maximum likelihood for a given ``astro``.

        The fitter alternates this with the least-squares fit of the joint
        parameters (coordinate ascent) for methods that override it (GP: kernel
        and white-noise parameters; PLD: the bin size). Return None when nothing
        changed (the fitter then stops alternating), else what was set. The
        default does nothing and returns None.
        """
        return None

    def extra_depth_variance(self, astro: np.ndarray, dastro_ddepth: np.ndarray) -> float:
        """A variance of the depth (fraction squared) that the fit cannot see, default 0.

        The fitter adds it to the depth variance (ICA: the component-separation
        error). ``dastro_ddepth`` is the derivative of ``astro`` with respect to
        the depth at the solution.
        """
        return 0.0

    @property
    def n_frames(self) -> int:
        """Frames the model fits (a method that bins: the frames behind its bins)."""
        return len(self.data)

    def dropped_frames(self) -> dict[str, int]:
        """Frames of the input that the method left out of ``self.data``, by reason.

        A method that drops frames (BLISS's sparse knots, KR/Pmap's low
        occupancy) builds ``self.data`` as the subset it keeps and counts the
        rest here; the result file adds them to ``n_frames_dropped``.
        """
        return {}

    def depth_error_estimates(self, astro: np.ndarray, dastro_ddepth: np.ndarray,
                              theta: np.ndarray | None = None) -> dict[str, float]:
        """The method's own estimates of the depth error (fractions), by name; default none.

        Called once at the best fit. Each estimate is written to the result as
        ``depth_err_<name>_ppm``; the one named by ``reported_error`` is
        reported under ``[reduce] error_rule = "method"``.
        """
        return {}

    def n_effective_params(self) -> int:
        """Free parameters that the systematics model adds, for BIC and AIC."""
        return len(self.param_names)


_REGISTRY: dict[str, type[Systematics]] = {}
_S = TypeVar("_S", bound=Systematics)
_PLUGINS_LOADED = False
#: The paper's seven first, in its order; then every other method by name.
_PAPER_ORDER = ("bliss", "gp", "ica", "kr-data", "kr-pmap", "pld", "segpoly")


def register(cls: type[_S]) -> type[_S]:
    """Class decorator: add a Systematics subclass to the registry under ``cls.name``."""
    if not (isinstance(cls, type) and issubclass(cls, Systematics)):
        raise TypeError(f"{cls!r} is not a subclass of eclipsebench.Systematics")
    if not cls.name:
        raise TypeError(f"{cls.__name__} has no registry name")
    if not is_safe_name(cls.name):  # it becomes a folder of every run (results/<name>/)
        raise TypeError(f"{cls.__name__}'s name {cls.name!r} is not a safe file name "
                        f"({SAFE_NAME.pattern})")
    if not (isinstance(cls.Options, type) and issubclass(cls.Options, MethodOptions)
            and dataclasses.is_dataclass(cls.Options)):
        raise TypeError(f"{cls.__name__}.Options is not a MethodOptions dataclass")
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise TypeError(f"method name '{cls.name}' is registered twice")
    own = cls.__dict__.get("record")
    if not isinstance(own, MethodRecord):
        # a class with no record of its own (a plugin subclassing a built-in method):
        # its parent's policy (the code it runs), no team's profile, no docs section
        cls.record = MethodRecord(policy=cls.record.policy)
    elif not own.docs_anchor:
        heading = f"{own.label or cls.name} (`{cls.name}`)"
        cls.record = dataclasses.replace(own, docs_anchor=heading_anchor(heading))
    _REGISTRY[cls.name] = cls
    return cls


def load_plugins(*, refresh: bool = False) -> None:
    """Register the methods of the entry-point group ``eclipsebench.methods``.

    Called the first time the registry is read. A plugin that fails to load
    (raises, or calls ``sys.exit``, while imported), whose entry-point name is
    not a safe file name (:data:`eclipsebench.io.paths.SAFE_NAME`: it becomes
    a folder of every run), is not a Systematics subclass, or whose class
    names itself differently from its entry point is left out with a warning
    naming it, so that one broken package does not take the built-in methods
    down with it. A class that does not set ``name`` itself (a subclass of a
    built-in method) takes its entry point's name.
    """
    global _PLUGINS_LOADED
    if _PLUGINS_LOADED and not refresh:
        return
    _PLUGINS_LOADED = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in _REGISTRY and not refresh:
            continue
        try:
            if not is_safe_name(ep.name):  # checked before the plugin's code is imported
                raise TypeError(f"the name is not a safe file name ({SAFE_NAME.pattern}); "
                                "it would become a folder of every run")
            cls = ep.load()
            if not (isinstance(cls, type) and issubclass(cls, Systematics)):
                raise TypeError(f"{ep.value} is not a subclass of eclipsebench.Systematics")
            own = cls.__dict__.get("name")   # a name inherited from a parent does not count
            if own and own != ep.name:
                raise TypeError(f"{ep.value} is named '{own}', not '{ep.name}'")
            cls.name = ep.name   # the entry point names the method
            if _REGISTRY.get(ep.name) not in (None, cls):
                raise TypeError(f"method name '{ep.name}' is already registered")
            register(cls)
        except (Exception, SystemExit) as exc:  # any error of a third-party package, a
            # sys.exit() while it is imported included: skip it, say why in one line
            reason = (f"it called sys.exit({exc.code!r}) while imported"
                      if isinstance(exc, SystemExit) else " ".join(str(exc).split()))
            warnings.warn(f"method plugin {ep.name!r} ({ep.value}) not loaded: {reason}",
                          RuntimeWarning, stacklevel=2)


def get_method(name: str) -> type[Systematics]:
    """The registered class called ``name``; InputError listing the known names otherwise.

    Examples
    --------
    >>> get_method("bliss").__name__
    'Bliss'
    """
    load_plugins()
    try:
        return _REGISTRY[name]
    except KeyError:
        raise InputError(f"method: {unknown_methods([name])}") from None


def unknown_methods(names) -> str | None:
    """The problem with ``names`` that are no registered method, or None when all are.

    One phrase for every caller's one line (``reduce --method``, ``trust
    --methods``, ``run.methods``, ``[reduce.options]``): each unknown name
    with the registered names closest to it (:func:`difflib.get_close_matches`)
    and the whole list, e.g. ``unknown method 'pdl' (did you mean pld?); known: bliss,
    ...`` (``tests/trust/test_refusals.py``).
    """
    known = available_methods()
    unknown = [str(n) for n in dict.fromkeys(names) if n not in known]
    if not unknown:
        return None
    parts = []
    for name in unknown:
        close = difflib.get_close_matches(name, known, n=3, cutoff=0.6)
        parts.append(f"{name!r}" + (f" (did you mean {' or '.join(close)}?)" if close else ""))
    return (f"unknown method{'s' if len(parts) > 1 else ''} {', '.join(parts)}; known: "
            f"{', '.join(known) or 'none'}")


#: The public name of :func:`get_method` (``eb.method_class``).
method_class = get_method


def available_methods() -> tuple[str, ...]:
    """Registered method names: the paper's seven in its order, then the others by name."""
    load_plugins()
    rank = {n: i for i, n in enumerate(_PAPER_ORDER)}
    return tuple(sorted(_REGISTRY, key=lambda n: (rank.get(n, len(rank)), n)))
