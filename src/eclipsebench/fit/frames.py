"""Which frames of an epoch a fit uses: the settling AOR rule.

The paper's challenge observed each epoch as a 30-minute Pre AOR followed by
the 7.8-hour Main AOR (Section 2.1); the Pre AOR exists "to allow short term
pointing drift to settle", and the paper's frame count N = 14,912 = 233 x 64
is the Main AOR alone. So by default the reducer leaves out the frames of an
epoch's first AOR when it is short beside the others (:func:`settling_aor`),
and says how many; ``[reduce] settling_aor = "keep"`` fits them.

A whole phase curve spans several AORs; :func:`per_aor_systematics` builds a
method on each of them (``[reduce] systematics_per_aor``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ..decorrelate.base import EpochData, Systematics
from ..decorrelate.record import FitterPolicy
from ..errors import InputError

__all__ = ["settling_aor", "SETTLING_MAX_FRACTION", "PerAorSystematics", "per_aor_systematics"]

#: The first AOR is a settling AOR when its time span is at most this fraction of
#: the longest AOR's. The challenge's Pre AOR spans 0.06 of its Main AOR (11 of
#: 244 cubes); real Spitzer staring programmes used 20-30 min pre-AORs before
#: AORs of several hours, so any fraction between about 0.1 and 0.5 separates them.
SETTLING_MAX_FRACTION = 0.25


def settling_aor(time_bmjd: np.ndarray, aorkey: np.ndarray | None,
                 max_fraction: float = SETTLING_MAX_FRACTION) -> np.ndarray:
    """Mask of the frames of the epoch's settling AOR (all False when there is none).

    Parameters
    ----------
    time_bmjd : ndarray, shape (n,)
        Frame times.
    aorkey : ndarray, shape (n,) or None
        The AOR of each frame; None (a table without AORs) means one AOR.
    max_fraction : float
        The first AOR (by start time) is the settling AOR when the epoch has at
        least two AORs and its span is at most this fraction of the longest.

    Returns
    -------
    ndarray of bool, shape (n,)

    Examples
    --------
    >>> t = np.concatenate([np.linspace(0, 0.02, 10), np.linspace(0.03, 0.35, 100)])
    >>> aor = np.repeat([1, 2], [10, 100])
    >>> int(settling_aor(t, aor).sum())
    10
    >>> int(settling_aor(t, None).sum())
    0
    """
    time = np.asarray(time_bmjd, dtype=float)
    mask = np.zeros(len(time), dtype=bool)
    if aorkey is None:
        return mask
    aor = np.asarray(aorkey)
    keys = np.unique(aor)
    if len(keys) < 2:
        return mask
    starts = {k: time[aor == k].min() for k in keys}
    spans = {k: np.ptp(time[aor == k]) for k in keys}
    first = min(keys, key=lambda k: starts[k])
    if spans[first] <= max_fraction * max(spans.values()):
        mask = aor == first
    return mask


class PerAorSystematics(Systematics):
    """One method built on each AOR of a long series, seen by the fitter as one method.

    A whole phase curve spans several AORs, each after a repointing; a
    map-based method (BLISS) may map each AOR's pixel phase on its own
    (``[reduce] systematics_per_aor``). The parts are built in the order of
    their AORs' first frames and concatenated: ``predict``, ``residuals``,
    ``correct`` join the parts' arrays, the log-likelihoods add, the method's
    own parameters are the parts' (``aor<k>_<name>``). Each part fits its own
    flux level, so the astrophysical model then has no AOR offsets.

    Parameters
    ----------
    parts : sequence of Systematics
        The method built on each AOR's frames (the same class and options),
        in time order.

    Examples
    --------
    >>> from eclipsebench.decorrelate import get_method
    >>> t = np.arange(200) / 1440.0
    >>> d = EpochData(time_bmjd=t, flux=np.full(200, 1e5), flux_err=np.full(200, 300.0),
    ...               x=15 + 0.01 * np.sin(t * 50), y=np.full(200, 15.0),
    ...               aorkey=np.repeat([7, 8], 100))
    >>> both = per_aor_systematics(d, lambda part: get_method("poly2")(part, bin_frames=1))
    >>> len(both.parts), both.n_frames, both.predict(np.ones(200)).shape
    (2, 200, (200,))
    """

    def __init__(self, parts: Sequence[Systematics]) -> None:
        parts = tuple(parts)
        if not parts:
            raise InputError("per-AOR systematics: no AOR to fit")
        first = parts[0]
        cls = type(first)
        if cls.extra_depth_variance is not Systematics.extra_depth_variance:
            raise InputError(f"method '{first.name}': its depth-separation error cannot be "
                             "combined over AORs; set [reduce] systematics_per_aor = false")
        self.parts = parts
        self.name = first.name  # type: ignore[misc]  # the wrapper answers to its parts' registry name
        self.options = first.options
        self.context = first.context
        self.param_names = tuple(f"aor{k}_{n}" for k, p in enumerate(parts)
                                 for n in p.param_names)
        sizes = [len(p.data) for p in parts]
        bounds = np.concatenate([[0], np.cumsum(sizes)])
        self._rows = [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]
        counts = np.concatenate([[0], np.cumsum([len(p.param_names) for p in parts])])
        self._cols = [slice(int(a), int(b)) for a, b in zip(counts[:-1], counts[1:], strict=True)]

        def joined(name):
            arrays = [getattr(p.data, name) for p in parts]
            return None if any(a is None for a in arrays) else np.concatenate(arrays)

        self.data = EpochData(
            time_bmjd=joined("time_bmjd"), flux=joined("flux"), flux_err=joined("flux_err"),
            x=joined("x"), y=joined("y"), noise_pixels=joined("noise_pixels"),
            pixels=joined("pixels"), aorkey=joined("aorkey"), meta=dict(first.data.meta),
            width_x=joined("width_x"), width_y=joined("width_y"))
        if np.any(np.diff(self.data.time_bmjd) < 0):
            raise InputError("per-AOR systematics: the AORs overlap in time; set [reduce] "
                             "systematics_per_aor = false")

    @property
    def policy(self) -> FitterPolicy:
        """The parts' fitter policy (their method's record), ``with_flux_rebuilds`` included."""
        return self.parts[0].policy

    def _theta(self, theta, k: int):
        if not len(self.param_names) or theta is None:
            return None
        return np.asarray(theta)[..., self._cols[k]]

    def predict(self, astro, theta=None):
        return np.concatenate([p.predict(astro[s], self._theta(theta, k))
                               for k, (p, s) in enumerate(zip(self.parts, self._rows,
                                                              strict=True))])

    def residuals(self, astro, theta=None):
        return np.concatenate([p.residuals(astro[s], self._theta(theta, k))
                               for k, (p, s) in enumerate(zip(self.parts, self._rows,
                                                              strict=True))])

    def correct(self, astro, theta=None):
        return np.concatenate([p.correct(astro[s], self._theta(theta, k))
                               for k, (p, s) in enumerate(zip(self.parts, self._rows,
                                                              strict=True))])

    def log_likelihood(self, astro, theta=None, noise_scale: float = 1.0) -> float:
        return float(sum(p.log_likelihood(astro[s], self._theta(theta, k),
                                          noise_scale=noise_scale)
                         for k, (p, s) in enumerate(zip(self.parts, self._rows, strict=True))))

    def log_likelihood_batch(self, astro, theta=None, noise_scale: float = 1.0):
        astro = np.atleast_2d(np.asarray(astro, dtype=float))
        return sum(p.log_likelihood_batch(astro[:, s], self._theta(theta, k),
                                          noise_scale=noise_scale)
                   for k, (p, s) in enumerate(zip(self.parts, self._rows, strict=True)))

    def with_flux(self, flux):
        flux = self._checked_flux(flux)
        return PerAorSystematics([p.with_flux(flux[s])
                                  for p, s in zip(self.parts, self._rows, strict=True)])

    def initial_params(self):
        return np.concatenate([[]] + [np.asarray(p.initial_params(), dtype=float)
                                      for p in self.parts])

    def param_bounds(self):
        lo, hi = zip(*(p.param_bounds() for p in self.parts), strict=True)
        return (np.concatenate([[]] + [np.asarray(v, dtype=float) for v in lo]),
                np.concatenate([[]] + [np.asarray(v, dtype=float) for v in hi]))

    def n_effective_params(self) -> int:
        return int(sum(p.n_effective_params() for p in self.parts))

    def optimise_hyperparameters(self, astro):
        changed = [p.optimise_hyperparameters(astro[s])
                   for p, s in zip(self.parts, self._rows, strict=True)]
        if all(c is None for c in changed):
            return None
        return {f"aor{k}": c for k, c in enumerate(changed) if c is not None}

    def dropped_frames(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for p in self.parts:
            for key, value in p.dropped_frames().items():
                out[key] = out.get(key, 0) + int(value)
        return out

    def diagnostics(self) -> dict:
        return {"systematics_per_aor": [
            {"aorkey": p.data.aorkey[0].item() if p.data.aorkey is not None else k,
             "n_frames": len(p.data), **p.diagnostics()} for k, p in enumerate(self.parts)]}


def per_aor_systematics(data: EpochData, build: Callable[[EpochData], Systematics],
                        ) -> Systematics:
    """``build`` on each AOR of ``data`` (in time order), joined; ``build(data)`` for one AOR.

    Raises
    ------
    InputError
        The table has no ``aorkey`` column.
    """
    if data.aorkey is None:
        raise InputError("[reduce] systematics_per_aor: the table has no aorkey column")
    keys = np.unique(np.asarray(data.aorkey))
    if len(keys) < 2:
        return build(data)
    starts = {k: data.time_bmjd[data.aorkey == k].min() for k in keys}
    return PerAorSystematics([build(data.subset(np.asarray(data.aorkey) == k))
                              for k in sorted(keys, key=lambda k: starts[k])])
