"""The Spitzer pointing model of IRACSIM (paper Appendix A.1, Table ``ptg_params``).

``x(t) = x_j + x_w + x_sd + x_ld`` (and the same for y): jitter (a sine plus
fractional Brownian motion), a skewed-sinusoid wobble whose amplitude and
period wander, a decaying-sinusoid short-term drift and a linear long-term
drift, each projected on its own axis. Offsets are in pixels, relative to the
peak-up position of the AOR.

Time origin
    ``t_s`` counts seconds from the start of the epoch's first AOR (``t0``
    of the paper). Jitter, wobble and the short-term drift are phased from
    ``t0``; the long-term drift restarts at each AOR start (``aor_starts_s``),
    as IRACSIM's ``DRIFT_TIMEZERO`` does.

Fractional Brownian motion
    As in IRACSIM's ``fbm1.pro`` (Stutzki et al. 1998, Section 4): Fourier
    amplitudes ``|f|^(-beta/2)`` with uniformly random phases, transformed
    back to time in independent segments of 2048 samples (2.048 s at 1 ms),
    each with its least-squares line removed. IRACSIM scaled the series of
    each cube so that its peak ``|FBM|`` equals ``A_fbm``; here every block of
    64 segments (131 s, about one 64-frame cube) is scaled so that its peak
    equals ``A_fbm``. Blocks are generated from their own random streams on
    demand, so memory stays bounded and a time gives the same value in any
    chunk. Between model samples the FBM is linearly interpolated.

Wobble amplitude and period
    Bounded random walks: an FBM of index 4 (as IRACSIM) over the epoch on a
    1 s grid, mean removed and scaled so that the largest excursion equals
    ``dA_w_max`` (px) and ``dP_w_max`` (s); linearly interpolated.

Negative short-term-drift decay times
    Table 5 draws ``tau_sd`` uniformly in -1800..1800 s; used literally a
    negative value makes ``exp(-t / tau)`` grow by e^18 over an epoch.
    IRACSIM itself drew the decay in 0.1..3600 s (same width). Here the decay
    time is ``|tau_sd|`` (at least 0.1 s) and a negative ``tau_sd`` reverses
    the sign of the whole term (the drift settles from the other side of its
    axis), so the table's range keeps both its width and its two signs.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np
import scipy.fft

from eclipsebench.errors import InputError

from ..detector.constants import PIXEL_SCALE_ARCSEC

__all__ = ["PointingParams", "ParamRange", "PointingRanges", "draw_pointing_params",
           "PointingModel", "fbm_series", "fbm_scale", "skewed_sine", "frame_windows"]

FBM_SEGMENT = 2048
FBM_BLOCK_SEGMENTS = 64
WALK_STEP_S = 1.0
SMOOTH_STEP_S = 0.05


@dataclass(frozen=True)
class PointingParams:
    """Pointing-model parameters of one epoch (Table 5 names, units in the names)."""

    a_j_px: float = 0.04
    p_j_s: float = 60.0
    phi_j_rad: float = 0.0
    theta_j_deg: float = -45.0
    a_fbm_px: float = 0.4
    beta_fbm: float = 1.0
    a_w_px: float = 0.026
    p_w_s: float = 2000.0
    phi_w_rad: float = 0.0
    s_w: float = 0.25
    da_w_max_px: float = 0.01
    dp_w_max_s: float = 10.0
    theta_w_deg: float = -62.5
    a_sd_px: float = 0.5
    p_sd_s: float = 395.6
    phi_sd_rad: float = 7.0 * np.pi / 4.0
    tau_sd_s: float = 900.0
    theta_sd_deg: float = 100.0
    a_ld_arcsec_per_hr: float = 0.0104
    theta_ld_deg: float = -75.0

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if not np.isfinite(v):
                raise InputError(f"pointing.{f.name}: expected a finite number, got {v}")
        for name in ("p_j_s", "p_w_s", "p_sd_s"):
            if getattr(self, name) <= 0:
                raise InputError(f"pointing.{name}: expected a positive period in s")
        for name in ("a_j_px", "a_fbm_px", "a_w_px", "da_w_max_px", "dp_w_max_s", "a_sd_px",
                     "a_ld_arcsec_per_hr"):
            if getattr(self, name) < 0:
                raise InputError(f"pointing.{name}: expected a non-negative value")
        if not 0.0 < self.s_w < 0.5:
            raise InputError(f"pointing.s_w: expected a skew in (0, 0.5), got {self.s_w}")
        if self.dp_w_max_s >= self.p_w_s:
            raise InputError("pointing.dp_w_max_s: expected less than p_w_s")
        if np.isclose(np.sin(self.phi_sd_rad), 0.0):
            raise InputError("pointing.phi_sd_rad: sin(phi_sd) must not be 0")

    def to_dict(self) -> dict:
        """Plain dict (for truth tables and headers)."""
        return {k: float(v) for k, v in asdict(self).items()}


@dataclass(frozen=True)
class ParamRange:
    """A Table-5 entry: type ``"U"`` (uniform lo..hi), ``"G"`` (Gaussian, lo..hi = mean -+ 1 sigma,
    redrawn outside ``limits``) or ``"C"`` (constant ``lo``)."""

    kind: str
    lo: float
    hi: float | None = None
    limits: tuple[float, float] | None = None

    def __post_init__(self):
        if self.kind not in ("U", "G", "C"):
            raise InputError(f"pointing range type: expected U, G or C, got {self.kind!r}")
        if self.kind != "C" and (self.hi is None or self.hi < self.lo):
            raise InputError(f"pointing range {self.kind} {self.lo}..{self.hi}: expected lo <= hi")

    def draw(self, rng: np.random.Generator) -> float:
        """One value."""
        if self.kind == "C" or self.hi is None:   # (__post_init__ refuses hi = None otherwise)
            return float(self.lo)
        if self.kind == "U":
            return float(rng.uniform(self.lo, self.hi))
        mean, sigma = 0.5 * (self.lo + self.hi), 0.5 * (self.hi - self.lo)
        for _ in range(1000):
            v = float(rng.normal(mean, sigma))
            if self.limits is None or self.limits[0] <= v <= self.limits[1]:
                return v
        raise InputError(f"pointing range G {self.lo}..{self.hi}: limits {self.limits} unreachable")


def _c(v):
    return ParamRange("C", v)


@dataclass(frozen=True)
class PointingRanges:
    """Table 5 of the paper (``ptg_params``) as the default ranges of each parameter.

    The skew ``s_w`` (G, 0.1..0.4) is redrawn outside 0.02..0.48 where the
    skewed sine is defined.
    """

    a_j_px: ParamRange = _c(0.04)
    p_j_s: ParamRange = _c(60.0)
    phi_j_rad: ParamRange = ParamRange("U", 0.0, 2.0 * np.pi)
    theta_j_deg: ParamRange = _c(-45.0)
    a_fbm_px: ParamRange = _c(0.4)
    beta_fbm: ParamRange = _c(1.0)
    a_w_px: ParamRange = ParamRange("U", 0.018, 0.034)
    p_w_s: ParamRange = ParamRange("U", 1200.0, 2800.0)
    phi_w_rad: ParamRange = ParamRange("U", -1.0, 1.0)
    s_w: ParamRange = ParamRange("G", 0.1, 0.4, (0.02, 0.48))
    da_w_max_px: ParamRange = _c(0.01)
    dp_w_max_s: ParamRange = _c(10.0)
    theta_w_deg: ParamRange = ParamRange("G", -80.0, -45.0)
    a_sd_px: ParamRange = ParamRange("U", 0.0, 1.0)
    p_sd_s: ParamRange = _c(395.6)
    phi_sd_rad: ParamRange = _c(7.0 * np.pi / 4.0)
    tau_sd_s: ParamRange = ParamRange("U", -1800.0, 1800.0)
    theta_sd_deg: ParamRange = _c(100.0)
    a_ld_arcsec_per_hr: ParamRange = ParamRange("U", 0.0, 0.0208)
    theta_ld_deg: ParamRange = ParamRange("U", -95.0, -55.0)


def draw_pointing_params(rng: np.random.Generator,
                         ranges: PointingRanges | None = None) -> PointingParams:
    """Draw one epoch's :class:`PointingParams` from ``ranges`` (Table 5 by default).

    Parameters are drawn in the order of the dataclass fields, so the same
    generator state gives the same parameters.
    """
    ranges = PointingRanges() if ranges is None else ranges
    values = {f.name: getattr(ranges, f.name).draw(rng) for f in fields(PointingRanges)}
    return PointingParams(**values)


def fbm_series(rng: np.random.Generator, n: int, beta: float) -> np.ndarray:
    """One FBM segment of ``n`` samples (Stutzki et al. 1998, Sec. 4; IRACSIM fbm1.pro).

    Fourier amplitudes ``|f|^(-beta/2)`` (the mean term 1), uniform random
    phases, real inverse transform, least-squares line removed. Unnormalised.
    """
    return fbm_segments(rng, 1, n, beta)[0]


def fbm_segments(rng: np.random.Generator, m: int, n: int, beta: float) -> np.ndarray:
    """``m`` independent :func:`fbm_series` segments of ``n`` samples, shape (m, n)."""
    freq = np.fft.rfftfreq(n)
    amp = np.ones_like(freq)
    amp[1:] = freq[1:] ** (-beta / 2.0)
    # single precision: trigonometry and memory traffic dominate, noise needs no more digits
    phase = rng.random(size=(m, freq.size), dtype=np.float32) * np.float32(2.0 * np.pi)
    amp32 = amp.astype(np.float32)
    spec = np.empty((m, freq.size), dtype=np.complex64)
    spec.real = amp32 * np.cos(phase)
    spec.imag = amp32 * np.sin(phase)
    spec[:, 0] = 0.0  # the mean, which the detrending removes anyway
    z = scipy.fft.irfft(spec, n=n, axis=-1)
    t = (np.arange(n) - 0.5 * (n - 1)).astype(np.float32)
    slope = (z * t).sum(axis=-1) / np.float32((t.astype(float) ** 2).sum())
    z -= slope[:, None] * t
    return z.astype(float)


def fbm_scale(a_fbm_px: float, peak: np.ndarray) -> np.ndarray:
    """The factor that scales an FBM block whose peak ``|FBM|`` is ``peak`` (per axis) to the
    peak ``a_fbm_px`` (a block of zeros stays zeros)."""
    return a_fbm_px / np.where(peak > 0, peak, 1.0)


def _skew_phase(q, s_w: float):
    """phi_sk(q) of the paper (wobble equation), q in [0, 1)."""
    q = np.asarray(q, float)
    return np.where(
        q < s_w, np.pi * (1.0 / (2.0 * s_w) - 2.0) * q,
        np.where(q < 1.0 - s_w, np.pi * ((q - s_w) / (1.0 - 2.0 * s_w) - 2.0 * q + 0.5),
                 np.pi * (1.0 / (2.0 * s_w) - 2.0) * (q - 1.0)))


def skewed_sine(t_s, period_s, s_w: float, phi_w_rad: float):
    """The unit skewed sinusoid ``sin(2 pi q + phi_sk(q))`` with
    ``q = (t / P + phi_w / 2 pi) mod 1`` (paper Appendix A.1)."""
    q = np.mod(np.asarray(t_s, float) / period_s + phi_w_rad / (2.0 * np.pi), 1.0)
    return np.sin(2.0 * np.pi * q + _skew_phase(q, s_w))


class PointingModel:
    """Pointing offsets of one epoch as a function of time.

    Parameters
    ----------
    params : PointingParams
    duration_s : float
        Length of the epoch from ``t0`` (s); times up to it may be asked for.
    dt_s : float
        Model sample time (1 ms for the subarray, ``Delta t / 10``).
    rng : numpy.random.Generator
        Source of all randomness (one 64-bit seed is drawn from it here, the
        FBM blocks and random walks derive their own streams from it).
    aor_starts_s : sequence of float
        Start of each AOR in seconds since ``t0`` (the first is normally 0);
        the long-term drift restarts at each.

    Examples
    --------
    >>> m = PointingModel(PointingParams(), duration_s=100.0, dt_s=1e-3,
    ...                   rng=np.random.default_rng(3), aor_starts_s=[0.0])
    >>> dx, dy = m.offsets(np.array([0.0, 50.0]))
    >>> dx.shape
    (2,)
    """

    def __init__(self, params: PointingParams, *, duration_s: float, dt_s: float,
                 rng: np.random.Generator, aor_starts_s=(0.0,)):
        if not duration_s > 0:
            raise InputError(f"duration_s: expected a positive duration, got {duration_s}")
        if not dt_s > 0:
            raise InputError(f"dt_s: expected a positive sample time, got {dt_s}")
        starts = np.sort(np.asarray(aor_starts_s, float).ravel())
        if starts.size == 0 or not np.all(np.isfinite(starts)):
            raise InputError("aor_starts_s: expected at least one finite AOR start time")
        self.params = params
        self.duration_s = float(duration_s)
        self.dt_s = float(dt_s)
        self.aor_starts_s = starts
        self._seed = int(rng.integers(0, 2**63 - 1))
        self.n_samples = int(np.ceil(self.duration_s / self.dt_s)) + 2
        self._block_len = FBM_SEGMENT * FBM_BLOCK_SEGMENTS
        self._block_cache: dict[int, np.ndarray] = {}
        self._build_walks()

    def _stream(self, *key: int) -> np.random.Generator:
        return np.random.Generator(np.random.PCG64(np.random.SeedSequence(self._seed,
                                                                          spawn_key=key)))

    def _build_walks(self) -> None:
        p = self.params
        n = int(np.ceil(self.duration_s / WALK_STEP_S)) + 2
        self._walk_t = np.arange(n) * WALK_STEP_S
        walks = []
        for key, excursion in ((1, p.da_w_max_px), (2, p.dp_w_max_s)):
            if n < 3 or excursion == 0:
                walks.append(np.zeros(n))
                continue
            z = fbm_segments(self._stream(key), 1, n, 4.0)[0]
            z = z - z.mean()
            peak = np.max(np.abs(z))
            walks.append(z * (excursion / peak) if peak > 0 else np.zeros(n))
        self._walk_amp, self._walk_per = walks

    # ----- FBM -------------------------------------------------------------
    def fbm_block_unscaled(self, b: int) -> tuple[np.ndarray, np.ndarray]:
        """Block ``b`` of the FBM before its scaling, shape (2, block_len), and each axis's
        peak ``|FBM|``, shape (2, 1): the block is ``z * fbm_scale(a_fbm_px, peak)``, so one
        draw can be scaled to several ``a_fbm_px`` (the twins' calibration, issue 40)."""
        z = fbm_segments(self._stream(0, b), 2 * FBM_BLOCK_SEGMENTS, FBM_SEGMENT,
                         self.params.beta_fbm).reshape(2, self._block_len)
        # max |z| without a temporary |z| (the same value)
        return z, np.maximum(z.max(axis=1, keepdims=True), -z.min(axis=1, keepdims=True))

    def _fbm_block(self, b: int) -> np.ndarray:
        """Block ``b`` of the FBM, shape (2, block_len): x and y."""
        cached = self._block_cache.get(b)
        if cached is not None:
            return cached
        p = self.params
        if p.a_fbm_px > 0:   # scaled in place: the draw is this call's own (no new 2 MB array)
            z, peak = self.fbm_block_unscaled(b)
            out = np.multiply(z, fbm_scale(p.a_fbm_px, peak), out=z)
        else:
            out = np.zeros((2, self._block_len))
        if len(self._block_cache) >= 4:
            self._block_cache.pop(next(iter(self._block_cache)))
        self._block_cache[b] = out
        return out

    def fbm_samples(self, start: int, n: int) -> np.ndarray:
        """FBM at model samples ``start .. start + n - 1``, shape (2, n)."""
        out = np.empty((2, n))
        i = 0
        while i < n:
            k = start + i
            b, off = divmod(k, self._block_len)
            take = min(n - i, self._block_len - off)
            out[:, i:i + take] = self._fbm_block(b)[:, off:off + take]
            i += take
        return out

    def _fbm_at(self, t_s: np.ndarray) -> np.ndarray:
        u = t_s / self.dt_s
        k0 = np.floor(u).astype(np.int64)
        frac = u - k0
        out = np.zeros((2,) + t_s.shape)
        if t_s.size == 0:
            return out
        lo, hi = int(k0.min()), int(k0.max()) + 1
        if hi - lo + 1 <= 4 * self._block_len:
            seg = self.fbm_samples(lo, hi - lo + 1)
            a = seg[:, k0 - lo]
            b = seg[:, k0 - lo + 1]
        else:
            a = np.empty((2,) + t_s.shape)
            b = np.empty((2,) + t_s.shape)
            blocks = k0 // self._block_len
            for blk in np.unique(blocks):
                sel = blocks == blk
                base = int(blk) * self._block_len
                seg = self.fbm_samples(base, self._block_len + 1)
                a[:, sel] = seg[:, k0[sel] - base]
                b[:, sel] = seg[:, k0[sel] - base + 1]
        return a + (b - a) * frac

    # ----- deterministic terms ----------------------------------------------
    def long_term_drift(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """The long-term drift alone; it restarts (jumps) at each AOR start."""
        p = self.params
        t = np.asarray(t_s, float)
        idx = np.searchsorted(self.aor_starts_s, t, side="right") - 1
        t_aor = t - self.aor_starts_s[np.clip(idx, 0, None)]
        ld = p.a_ld_arcsec_per_hr / PIXEL_SCALE_ARCSEC * t_aor / 3600.0
        th_ld = np.deg2rad(p.theta_ld_deg)
        return ld * np.cos(th_ld), ld * np.sin(th_ld)

    def smooth_offsets(self, t_s, *, drift: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Jitter sine + wobble + short-term drift (+ the long-term drift unless
        ``drift=False``): everything but the FBM."""
        p = self.params
        t = np.asarray(t_s, float)
        jit = p.a_j_px * np.sin(2.0 * np.pi * t / p.p_j_s + p.phi_j_rad)
        th_j = np.deg2rad(p.theta_j_deg)
        amp = p.a_w_px + np.interp(t, self._walk_t, self._walk_amp)
        per = p.p_w_s + np.interp(t, self._walk_t, self._walk_per)
        wob = amp * skewed_sine(t, per, p.s_w, p.phi_w_rad)
        th_w = np.deg2rad(p.theta_w_deg)
        tau = max(abs(p.tau_sd_s), 0.1)
        sign = -1.0 if p.tau_sd_s < 0 else 1.0
        sd = (sign * p.a_sd_px / np.sin(p.phi_sd_rad)
              * np.sin(2.0 * np.pi * t / p.p_sd_s + p.phi_sd_rad) * np.exp(-t / tau))
        th_sd = np.deg2rad(p.theta_sd_deg)
        dx = jit * np.cos(th_j) + wob * np.cos(th_w) + sd * np.cos(th_sd)
        dy = jit * np.sin(th_j) + wob * np.sin(th_w) + sd * np.sin(th_sd)
        if drift:
            lx, ly = self.long_term_drift(t)
            dx = dx + lx
            dy = dy + ly
        return dx, dy

    def offsets(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Pointing offsets (dx_px, dy_px) at times ``t_s`` (s since ``t0``), any shape.

        The same time gives the same offset whichever call or chunk asks for it.
        """
        t = np.asarray(t_s, float)
        if t.size and (np.nanmin(t) < 0 or np.nanmax(t) > self.duration_s + self.dt_s):
            raise InputError(f"t_s: expected times within 0..{self.duration_s} s of the epoch")
        dx, dy = self.smooth_offsets(t)
        fbm = self._fbm_at(t)
        return dx + fbm[0], dy + fbm[1]

    def offsets_grid(self, start_index: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Offsets at the model samples ``t = (start_index + i) dt``, ``i = 0 .. n-1``.

        Fast path for regular sampling: the continuous deterministic terms
        (periods of 60 s and more) are evaluated every 50 ms and linearly
        interpolated (error below 1e-6 px); the long-term drift, which jumps
        at AOR starts, and the FBM are taken sample by sample. Identical
        across chunkings for the same indices.
        """
        if start_index < 0 or n < 0 or (start_index + n - 1) * self.dt_s > self.duration_s + self.dt_s:
            raise InputError(f"offsets_grid: samples {start_index}..{start_index + n - 1} "
                             f"outside the epoch of {self.duration_s} s")
        t = (start_index + np.arange(n)) * self.dt_s
        step = SMOOTH_STEP_S
        c0 = int(np.floor(t[0] / step)) if n else 0
        c1 = int(np.floor(t[-1] / step)) + 1 if n else 0
        tc = np.arange(c0, c1 + 1) * step
        # continuous terms on a coarse grid anchored at t = 0, interpolated; the
        # long-term drift (which jumps at AOR starts) and the FBM sample by sample
        sx, sy = self.smooth_offsets(tc, drift=False)
        lx, ly = self.long_term_drift(t)
        fbm = self.fbm_samples(start_index, n)
        return (np.interp(t, tc, sx) + lx + fbm[0], np.interp(t, tc, sy) + ly + fbm[1])


def frame_windows(samples, starts: np.ndarray, n_grid: int) -> tuple[np.ndarray, np.ndarray]:
    """Each frame's ``n_grid`` model samples, cut from one span that covers them all.

    Parameters
    ----------
    samples : callable
        ``samples(start, n)`` gives the x and y offsets at model samples
        ``start .. start + n - 1`` (:meth:`PointingModel.offsets_grid`,
        :meth:`PointingModel.fbm_samples`).
    starts : array of int
        Each frame's first model sample.
    n_grid : int
        Samples per frame.

    Returns
    -------
    dx, dy : ndarray, shape (len(starts), n_grid)

    Examples
    --------
    >>> ramp = lambda start, n: (np.arange(start, start + n) * 1.0, -np.arange(start, start + n))
    >>> dx, dy = frame_windows(ramp, np.array([10, 13]), 3)
    >>> dx.tolist(), dy[1].tolist()
    ([[10.0, 11.0, 12.0], [13.0, 14.0, 15.0]], [-13, -14, -15])
    """
    starts = np.asarray(starts, np.int64)
    first = int(starts.min())
    gx, gy = samples(first, int(starts.max()) - first + n_grid)
    # each frame's samples are one contiguous run: rows of a sliding window, copied
    at = starts - first
    return (np.lib.stride_tricks.sliding_window_view(gx, n_grid)[at],
            np.lib.stride_tricks.sliding_window_view(gy, n_grid)[at])
