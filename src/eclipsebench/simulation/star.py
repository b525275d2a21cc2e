"""The star's image for the simulator: a PRF choice plus the flux scale.

``simulation.prf`` selects the PRF:

``"builtin"``
    :class:`eclipsebench.instrument.prf.BuiltinPRF` of ``observation.channel``
    (the package's own optics times a fitted intra-pixel response);
    ``simulation.flat_gain = true`` switches the intra-pixel response off.
``"irsa:<folder>"``
    :class:`eclipsebench.instrument.prf.IrsaPRF` from a folder of IRSA/IRACSIM
    PRF files (e.g. ``../shared/data/irac/prf/warm_2015_ch2``), the file of
    the array position nearest the peak-up target (subarray or full array).
    Their intra-pixel structure is part of the files, so ``flat_gain`` cannot
    switch it off (a configuration error says so); files named for the other
    channel are refused.

The flux scale makes a star at the peak-up target ``(x0_px, y0_px)`` give
``flux_aperture_e`` electrons per exposure in the ``aperture_radius_px``
aperture (paper Appendix A.2: the PRF rescaled to an input aperture flux).

The sky under the star (:meth:`StarImager.sky_e_per_px`) is what makes the
3-7 px annulus show the configured level. For ``noise_model = "iracsim2015"``
that level is the 2015 frames' own: the challenge put ``background_e_per_px``
(the paper's 881 e per aperture, 55.4 e/px) in as a uniform sky *under* the
star, so its annulus also holds the wings of the PRFs it used
(:data:`IRACSIM2015_ANNULUS_WING_PER_E` of the aperture flux per pixel,
55.0 e/px): 110.4 e/px, against 111 e/px measured on the public 2015 cube.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..config import Config
from ..errors import ConfigError, InputError
from ..instrument.prf import PRF, BuiltinPRF, IrsaPRF
from ..photometry.estimators import annulus_background, aperture_flux
from .render import N_MOMENTS

__all__ = ["StarImager", "make_star_imager", "make_prf", "prf_label",
           "IRACSIM2015_ANNULUS_WING_PER_E"]

_PRF_CACHE: dict[tuple, PRF] = {}

#: Mean star light per pixel in the 3-7 px annulus per electron in the
#: r = 2.25 px aperture, for the PRFs the 2015 challenge used
#: (``../shared/data/irac/prf/warm_2015_ch2``) with the star at the peak-up
#: target (15.15, 15.20): 7.51e-4, i.e. 55.0 e/px for 73,173 e (7.51e-4 to
#: 7.85e-4 within 0.25 px of it; the builtin PRF's wings give 4.30e-4).
#: Measured by test ``test_iracsim2015_wing_constant_is_the_2015_prfs``.
IRACSIM2015_ANNULUS_WING_PER_E = 7.51e-4
def prf_label(name: str) -> str:
    """``simulation.prf`` without folders (headers carry no absolute paths)."""
    name = name.strip()
    if name.startswith("irsa:"):
        return "irsa:" + Path(name[5:].rstrip("/")).name
    return name


def make_prf(name: str, *, flat_gain: bool = False, channel: int = 2,
             array_position: tuple[float, float] | None = None, subarray: bool = True) -> PRF:
    """The PRF that ``simulation.prf = name`` selects (cached per process).

    ``channel`` picks the builtin PRF's band and gain map (and must match the
    IRSA files'); ``array_position`` (0-based, on the subarray or the full
    array) picks the IRSA file (default the subarray sweet spot).
    """
    position = None if array_position is None else (round(float(array_position[0])),
                                                    round(float(array_position[1])))
    key = (name, flat_gain, int(channel), position if name.startswith("irsa:") else None,
           bool(subarray))
    cached = _PRF_CACHE.get(key)
    if cached is not None:
        return cached
    if name == "builtin":
        prf: PRF = BuiltinPRF(gain=not flat_gain, channel=channel)
    elif name.startswith("irsa:"):
        folder = Path(name[5:]).expanduser()
        if flat_gain:
            raise ConfigError("simulation.flat_gain", "true needs prf = 'builtin' (IRSA PRF "
                                                      "files carry their intra-pixel response)")
        if not folder.is_dir():
            raise ConfigError("simulation.prf", f"{str(folder)!r} is not a folder of IRSA PRF "
                                                "files")
        try:
            prf = IrsaPRF.from_files(folder, array_position=position, subarray=subarray,
                                     channel=channel)
        except InputError as exc:
            raise ConfigError("simulation.prf", str(exc)) from None
    else:
        raise ConfigError("simulation.prf", f"expected 'builtin' or 'irsa:<folder>', got {name!r}")
    _PRF_CACHE[key] = prf
    return prf


class StarImager:
    """Noiseless images of the star and their Taylor expansion in position.

    Parameters
    ----------
    prf : PRF
        Unit-normalised PRF.
    x_ref_px, y_ref_px : float
        Where ``flux_aperture_e`` is defined (the peak-up target).
    radius_px : float
        Aperture radius of the flux definition.
    annulus_px : (float, float)
        The background annulus photometry uses (``[photometry] annulus_px``):
        the star's wings in it set the ``"annulus"`` background reference.
    annulus_extra_per_e : float
        Star light per annulus pixel and aperture electron that the
        ``"annulus"`` level holds on top of the configured background: 0 when
        the configured value is what photometry measures (physical model),
        :data:`IRACSIM2015_ANNULUS_WING_PER_E` when it is the sky the 2015
        simulation put under its PRFs (``iracsim2015``).
    """

    def __init__(self, prf: PRF, *, x_ref_px: float, y_ref_px: float, radius_px: float,
                 annulus_px: tuple[float, float] = (3.0, 7.0),
                 annulus_extra_per_e: float = 0.0):
        self.prf = prf
        self.annulus_extra_per_e = float(annulus_extra_per_e)
        # measured on a 32 x 32 window with the star on its pixel (15, 15) at the same
        # sub-pixel phase (the PRF, gain included, depends on the phase only)
        x_loc = x_ref_px - (round(x_ref_px) - 15)
        y_loc = y_ref_px - (round(y_ref_px) - 15)
        im = prf.render(np.array([x_loc]), np.array([y_loc]), shape=(32, 32))
        self.aperture_per_unit = float(aperture_flux(im, x_loc, y_loc, radius_px)[0])
        self.annulus_per_unit = float(
            annulus_background(im, x_loc, y_loc, annulus_px)["mean_e"][0])

    def electrons_per_unit(self, flux_aperture_e: float) -> float:
        """Electrons per exposure per PRF unit for an aperture flux ``flux_aperture_e``."""
        return flux_aperture_e / self.aperture_per_unit

    def sky_e_per_px(self, background_e_per_px: float, flux_aperture_e: float,
                     reference: str) -> float:
        """Sky per pixel and exposure giving ``background_e_per_px`` as ``reference`` defines it.

        ``"annulus"``: the mean of the 3-7 px annulus around the peak-up target
        including the star's wings (what photometry measures) is
        ``background_e_per_px + annulus_extra_per_e * flux_aperture_e``; the
        sky is that minus this PRF's own wings, floored at 0. ``"sky"``: the
        value itself.

        Examples
        --------
        >>> from eclipsebench.instrument.prf import BuiltinPRF
        >>> star = StarImager(BuiltinPRF(), x_ref_px=15.15, y_ref_px=15.2, radius_px=2.25)
        >>> round(star.sky_e_per_px(55.4, 73246.0, "annulus"), 1)
        23.9
        >>> star.sky_e_per_px(55.4, 73246.0, "sky")
        55.4
        """
        if reference == "sky":
            return background_e_per_px
        wing = self.annulus_per_unit * self.electrons_per_unit(flux_aperture_e)
        level = background_e_per_px + self.annulus_extra_per_e * flux_aperture_e
        return max(level - wing, 0.0)

    def image(self, x_px: float, y_px: float, shape: tuple[int, int]) -> np.ndarray:
        """The star at ``(x, y)`` over an array of ``shape`` (PRF units)."""
        return self.prf.render(np.array([x_px]), np.array([y_px]), shape=shape)[0]

    def stamps(self, x_px: np.ndarray, y_px: np.ndarray, sx0: int, sy0: int, size: int
               ) -> np.ndarray:
        """Values on the common stamp at ``(sx0, sy0)``, shape (n, size, size)."""
        return self._common(x_px, y_px, sx0, sy0, size, order=0)[:, 0]

    def taylor_basis(self, x_px: np.ndarray, y_px: np.ndarray, sx0: int, sy0: int, size: int
                     ) -> np.ndarray:
        """``[V, Gx, Gy, Hxx/2, Hxy, Hyy/2]`` on the common stamp, shape (n, 6, size*size)."""
        t = self._common(x_px, y_px, sx0, sy0, size, order=2)
        n = t.shape[0]
        basis = t.reshape(n, N_MOMENTS, size * size).copy()
        basis[:, 3] *= 0.5
        basis[:, 5] *= 0.5
        return basis

    def _common(self, x_px, y_px, sx0: int, sy0: int, size: int, order: int) -> np.ndarray:
        """Evaluate on stamps centred on each star, then crop all to the common stamp."""
        x = np.atleast_1d(np.asarray(x_px, float))
        y = np.atleast_1d(np.asarray(y_px, float))
        half = size // 2
        cx, cy = sx0 + half, sy0 + half
        margin = int(max(np.abs(np.rint(x) - cx).max(), np.abs(np.rint(y) - cy).max()))
        h = half + margin
        if order == 0:
            vals, x0, y0 = self.prf.render_stamp(x, y, half=h)
            full = vals[:, None]
        else:
            ts = self.prf.render_taylor(x, y, half=h)
            full = np.stack([ts.value, ts.dx, ts.dy, ts.dxx, ts.dxy, ts.dyy], axis=1)
            x0, y0 = ts.x0, ts.y0
        ox = sx0 - x0
        oy = sy0 - y0
        a = oy[:, None] + np.arange(size)[None, :]          # (n, size) rows
        b = ox[:, None] + np.arange(size)[None, :]          # (n, size) cols
        idx_n = np.arange(x.size)[:, None, None]
        return full.transpose(0, 2, 3, 1)[idx_n, a[:, :, None], b[:, None, :]].transpose(0, 3, 1, 2)


def make_star_imager(cfg: Config) -> StarImager:
    """The :class:`StarImager` of a configuration.

    With ``simulation.noise_model = "iracsim2015"`` the ``"annulus"``
    background level is the 2015 frames' (``background_e_per_px`` of sky plus
    the wings of the 2015 PRFs, :data:`IRACSIM2015_ANNULUS_WING_PER_E`).
    """
    obs = cfg.observation
    prf = make_prf(cfg.simulation.prf.strip(), flat_gain=cfg.simulation.flat_gain,
                   channel=obs.channel, array_position=(obs.x0_px, obs.y0_px),
                   subarray=obs.readout_mode().subarray)
    extra = IRACSIM2015_ANNULUS_WING_PER_E if cfg.simulation.noise_model == "iracsim2015" else 0.0
    return StarImager(prf, x_ref_px=cfg.observation.x0_px, y_ref_px=cfg.observation.y0_px,
                      radius_px=cfg.simulation.aperture_radius_px,
                      annulus_px=(cfg.photometry.annulus_px[0], cfg.photometry.annulus_px[1]),
                      annulus_extra_per_e=extra)
