"""``[reduce]``: the shared astrophysical model and the fitter."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from ..astro.events import event_for
from ..limits import MAX_MCMC_WALKER_STEPS, MAX_MCMC_WALKERS, check_size
from .base import check

#: The phase-curve models of a single eclipse (``[reduce] phase``).
PhaseModel = Literal["flat", "linear", "quadratic", "sinusoid"]
#: The ramp models (``[reduce] ramp``).
RampModel = Literal["none", "linear", "exponential"]


@dataclass(frozen=True)
class ReduceSection:
    """Options shared by every decorrelation method.

    One astrophysical model (eclipse, phase curve, optional ramp) is shared by
    all methods so that they differ only in their systematics model. See
    ``docs/fitting.md`` for the equations and for how the depth error is chosen.

    Attributes
    ----------
    phase : {"flat", "linear", "quadratic", "sinusoid"}
        Out-of-eclipse phase-curve model (paper Section 4.2).
    ramp : {"none", "linear", "exponential"}
        Multiplicative detector ramp.
    eclipse_shape : {"physical", "box"}
        The orbit's physical shape (default) or a box of the half-depth
        duration. Shared by every method in the controlled profile; the paper
        profile takes each team's (the box for ``segpoly``, paper App. B.6).
    sampler : {"auto", "mcmc", "leastsq"}
        Least squares followed by emcee (``mcmc``), or least squares only
        (``leastsq``, for speed). ``auto`` (the default) samples the posterior
        where it costs seconds: an eclipse or a transit (1-9 s for 15,000
        frames with the DE move, BENCHMARKS.md "mcmc"); a whole phase curve is
        least squares (its MCMC evaluates the model walker by walker, about
        100 s for 2,000 steps on 1,000 rows). :meth:`resolved_sampler` says
        which.
    mcmc_walkers, mcmc_steps, mcmc_block_steps, mcmc_tau_factor
        Ensemble size, step cap, steps between autocorrelation checks, and the
        chain length (in autocorrelation times) that counts as converged.
        Checks every 100 steps, as the emcee documentation's convergence
        example does: with 250 the challenge's chains ran 14 % past the
        step at which they had converged (167,000 steps against about
        143,000 over the 220 chains of ``make run``); the first check, at
        100 steps, would need tau below 2 steps (it is 9-19 here).
        16 walkers: ter Braak (2006) runs DE-MC with N >= 2d chains; the
        autocorrelation time is 10-19 steps against 11-14 with 32, so half
        the walkers cost about half (BENCHMARKS.md "mcmc"); the sampler
        raises it to 2 d + 2 for a model of more parameters.
    prayer_bead_shifts : int
        Cyclic residual shifts refitted for the prayer-bead error (0: none),
        spread evenly over the series, each refit capped at 50 evaluations
        (``prayer_bead_mode = "spread"``). The bead is computed where a rule
        can report it: not beside a sampled posterior that the default
        ``error_rule = "posterior"`` reports.
    prayer_bead_mode : {"spread", "all"}
        ``spread``: ``prayer_bead_shifts`` shifts (a quick estimate).
        ``all``: every cyclic shift in steps of ``prayer_bead_stride`` points,
        each refitted to convergence (Wong et al. 2014; the paper profile's
        choice for the teams that reported a prayer bead).
    prayer_bead_stride : int
        Step of the full cycle in fitted points (64: one subarray cube of
        frames, so that each cube's correlated residuals move together).
    beta_bin_minutes : [float, float]
        Range of bin widths over which the red-noise factor is averaged.
    radius_px : float
        Aperture radius whose flux column is fitted; 0 uses the table's
        ``flux`` (the photometry default, 2.25 px).
    stamp : {"stamp3", "stamp5"}
        Pixel stamp handed to pixel-level methods (PLD, ICA).
    max_nfev : int
        Cap on function evaluations of one least-squares fit.
    settling_aor : {"drop", "keep"}
        Leave out of the fit the frames of an epoch's first AOR when it is short
        beside the others (the 30-minute Pre AOR that lets the pointing settle;
        :mod:`eclipsebench.fit.frames`), or fit every frame.
    profile : {"controlled", "paper"}
        ``controlled``: these settings for every method. ``paper``: each
        method's team's centroid, phase and ramp models, eclipse shape,
        sampler, options and reported error (``eclipsebench.fit.profiles``;
        ``docs/methods.md``, "The paper profile"), which override ``phase``,
        ``ramp``, ``eclipse_shape``, ``sampler`` and ``error_rule``.
    error_rule : {"posterior", "largest", "method"}
        The reported depth error, for every method alike: ``posterior`` (the
        default) the MCMC posterior's 16-84 % half-width when the sampler ran,
        else the larger of the Jacobian error times ``max(1, beta_red)`` and
        the prayer bead; ``largest`` the largest of those three; ``method``
        the estimate each method's authors reported (its record's paper profile,
        ``reported_error``, e.g. PLD's time-averaging extrapolation; the largest
        of the three for a method without one).
    options : dict
        Per-method options, ``[reduce.options.<method>]`` tables (the keys of
        each method's ``Options``; ``docs/methods.md``). Checked against the
        method's options when the reduce stage builds the method.
    event : {"eclipse", "transit", "phase-curve"}
        The event fitted: the secondary eclipse (depth), the transit
        (Rp/R*, batman's quadratic limb darkening; ``docs/fitting.md``,
        "Transits"), or a whole phase curve (eclipses, transits and the
        harmonic phase variation over several AORs; "Whole phase curves").
    phase_curve_model : {"bic", "harmonic1", "harmonic2"}
        A whole phase curve's phase model (``phase`` is the eclipse's and
        transit's): the first harmonic, or the first and second (SPCA;
        Bell et al. 2021), or ``"bic"`` (the default): both are fitted and the
        one of least BIC is reported (``phase_curve_bic`` in the result).
    nonnegative_planet : bool
        A whole phase curve's prior that the planet's flux is non-negative
        over the orbit (least squares: a penalty residual; MCMC: log-prior
        -inf). Off: the result only flags a negative minimum.
    systematics_per_aor : bool
        A whole phase curve: build the method once per AOR (its own map,
        regression, ...) instead of one systematics model over the whole
        series; the AOR flux offsets are then left out (each AOR's
        systematics fits its own flux level).
    aor_offsets : bool
        A whole phase curve with one systematics model: a flux offset for
        each AOR after the first (SPCA). False leaves them out (a map-based
        method whose AORs sit on different knots is degenerate with them).
    exposure_s : float
        A whole phase curve's integration time of one table row in s; 0: the
        table's median cadence (a binned row spans its cube). Rows longer
        than 10 s are averaged over sub-exposures.
    transit_free : list of {"a_rs", "b", "q1", "q2"}
        The transit's parameters fitted besides Rp/R* and the mid-transit
        time; the others stay at the catalogue's values (``b``: the impact
        parameter; ``q1``, ``q2``: Kipping's 2013 limb-darkening parameters).
    transit_priors : dict
        ``[reduce.transit_priors]`` ``name = [mean, sigma]``: a Gaussian prior
        on a free transit parameter (a free one without has a uniform prior
        within its bounds).
    limb_darkening_q : [q1, q2]
        Kipping's q1, q2, fixed (or the start of free ones); empty: those of
        the catalogue's quadratic coefficients.
    """

    phase: PhaseModel = "quadratic"
    ramp: RampModel = "none"
    eclipse_shape: Literal["physical", "box"] = "physical"
    sampler: Literal["auto", "mcmc", "leastsq"] = "auto"
    mcmc_walkers: int = 16
    mcmc_steps: int = 5000
    mcmc_block_steps: int = 100
    mcmc_tau_factor: float = 50.0
    prayer_bead_shifts: int = 16
    prayer_bead_mode: Literal["spread", "all"] = "spread"
    prayer_bead_stride: int = 64
    beta_bin_minutes: tuple[float, ...] = (10.0, 30.0)
    radius_px: float = 0.0
    stamp: Literal["stamp3", "stamp5"] = "stamp3"
    max_nfev: int = 200
    settling_aor: Literal["drop", "keep"] = "drop"
    error_rule: Literal["posterior", "largest", "method"] = "posterior"
    profile: Literal["controlled", "paper"] = "controlled"
    options: dict[str, dict[str, Any]] = field(default_factory=dict)
    event: Literal["eclipse", "transit", "phase-curve"] = "eclipse"
    phase_curve_model: Literal["bic", "harmonic1", "harmonic2"] = "bic"
    nonnegative_planet: bool = False
    systematics_per_aor: bool = False
    aor_offsets: bool = True
    exposure_s: float = 0.0
    transit_free: tuple[str, ...] = ()
    transit_priors: dict[str, tuple[float, ...]] = field(default_factory=dict)
    limb_darkening_q: tuple[float, ...] = ()

    def resolved_sampler(self) -> str:
        """``"mcmc"`` or ``"leastsq"``: the sampler ``auto`` stands for with this event.

        Examples
        --------
        >>> ReduceSection().resolved_sampler(), ReduceSection(event="phase-curve").resolved_sampler()
        ('mcmc', 'leastsq')
        """
        if self.sampler != "auto":
            return self.sampler
        return event_for(self.event).default_sampler

    def _check_chain_size(self) -> None:
        """Walkers, and walkers x steps (the chain kept in memory), within the stated limits."""
        check_size("mcmc_walkers", self.mcmc_walkers, MAX_MCMC_WALKERS, "walkers", config=True)
        for key in ("mcmc_steps", "mcmc_block_steps"):
            steps = getattr(self, key)
            check_size(key, self.mcmc_walkers * steps, MAX_MCMC_WALKER_STEPS,
                       f"walker-steps ({self.mcmc_walkers} walkers x {steps})", config=True)

    def validate(self) -> None:
        check(self.mcmc_walkers >= 4 and self.mcmc_walkers % 2 == 0, "mcmc_walkers",
              "an even number of walkers >= 4")
        check(self.mcmc_steps >= 100, "mcmc_steps", "at least 100 steps")
        check(self.mcmc_block_steps >= 10, "mcmc_block_steps", "at least 10 steps")
        self._check_chain_size()
        check(self.mcmc_tau_factor > 0, "mcmc_tau_factor", "a positive number")
        check(0 <= self.prayer_bead_shifts <= 10000, "prayer_bead_shifts",
              "an integer between 0 (no prayer bead) and 10000")
        check(self.prayer_bead_stride >= 1, "prayer_bead_stride", "at least 1 point")
        check(len(self.beta_bin_minutes) == 2 and 0 < self.beta_bin_minutes[0]
              <= self.beta_bin_minutes[1], "beta_bin_minutes",
              "[shortest, longest] bin width in minutes, 0 < shortest <= longest")
        check(self.radius_px == 0 or 0.5 <= self.radius_px <= 10.0, "radius_px",
              "0 (the table's flux column) or an aperture radius in 0.5-10 px")
        check(self.max_nfev >= 10, "max_nfev", "at least 10 evaluations")
        check(0.0 <= self.exposure_s <= 3600.0, "exposure_s",
              "0 (the table's cadence) or an exposure of at most 3600 s")
        for key in ("systematics_per_aor", "nonnegative_planet"):
            check(not getattr(self, key) or key in event_for(self.event).own_settings, key,
                  "true only with event = 'phase-curve'")
        free = ("a_rs", "b", "q1", "q2")   # eclipsebench.fit.model.TRANSIT_FREE
        check(all(n in free for n in self.transit_free)
              and len(set(self.transit_free)) == len(self.transit_free), "transit_free",
              "distinct names among " + ", ".join(free))
        for name, pair in self.transit_priors.items():
            check(name in self.transit_free, f"transit_priors.{name}",
                  "a prior on a parameter named in transit_free")
            check(len(pair) == 2 and pair[1] > 0, f"transit_priors.{name}", "[mean, sigma > 0]")
        check(len(self.limb_darkening_q) in (0, 2)
              and all(0.0 <= q <= 1.0 for q in self.limb_darkening_q), "limb_darkening_q",
              "[] (the catalogue's) or [q1, q2], each in [0, 1]")
