"""The text ``eclipsebench reduce`` prints: one result file's content, a line per quantity."""

from __future__ import annotations

from ..astro.events import event_for

__all__ = ["format_text"]


def _num(value, digits: int = 2) -> str:
    """A number for the text summary; "n/a" for null (e.g. beta_red of too few points)."""
    return "n/a" if value is None else f"{value:.{digits}f}"


def format_text(result: dict) -> str:
    if result.get("joint"):
        lines = [f"method        {result['method']}, joint fit of {len(result['epochs'])} "
                 f"epochs ({result['phase']} phase)",
                 f"depth         {result['depth_ppm']:.1f} +- {result['depth_err_ppm']:.1f} ppm "
                 "(one depth for every epoch)",
                 f"combined      {result['depth_combined_ppm']:.1f} +- "
                 f"{result['depth_combined_err_ppm']:.1f} ppm (the epochs fitted alone, "
                 "inverse-variance mean)"]
        lines.append(f"BIC / AIC     {_num(result['bic'], 1)} / {_num(result['aic'], 1)} "
                     f"(k = {result['k']}, on {result['bic_data']}: comparable only with fits "
                     "of the same points)")
        for e in result["per_epoch"]:
            lines.append(f"  epoch {e['epoch']}: alone {e['depth_alone_ppm']:7.1f} +- "
                         f"{e['depth_alone_err_ppm']:5.1f} ppm, beta_red {_num(e['beta_red'])}")
        lines.append(f"wrote         {result['result_file']}")
        return "\n".join(lines)
    event = event_for(result.get("event"))
    when = event.time_prefix
    lines = [f"method        {result['method']} (epoch {result['epoch']}, phase {result['phase']}, "
             f"{result['sampler']}, {result.get('profile', 'controlled')} profile)",
             f"depth         {result['depth_ppm']:.1f} +- {result['depth_err_ppm']:.1f} ppm "
             f"(error from {result['depth_err_method']})",
             f"{when:<14}{result[when + '_bmjd']:.5f} +- {result[when + '_err_d'] * 86400:.0f} s "
             "BMJD_TDB",
             f"rms           {result['rms_ppm']:.0f} ppm, beta_red {_num(result['beta_red'])}, "
             f"chi2_red {result['chi2_red']:.3f}",
             f"BIC / AIC     {_num(result['bic'], 1)} / {_num(result['aic'], 1)} (k = {result['k']}, "
             f"on {result.get('bic_data', 'points not recorded')}: comparable only with fits "
             "of the same points)"]
    lines[2:2] = event.detail_lines(result)   # Rp/R*, or a phase curve's summary
    models = result.get("phase_models")
    if models:
        lines.append("phase models  (BIC picks " + models["best_bic"] + ", AIC picks "
                     + models["best_aic"] + ")")
        for row in models["models"]:
            lines.append(f"  {row['phase']:<10} depth {row['depth_ppm']:7.1f} +- "
                         f"{row['depth_err_ppm']:5.1f} ppm  dBIC {row['delta_bic']:7.1f}  "
                         f"dAIC {row['delta_aic']:7.1f}")
    if result.get("mcmc_steps"):
        lines.insert(2, f"posterior     median {result['mcmc_depth_median_ppm']:.1f} "
                        f"-{result['mcmc_depth_err_lo_ppm']:.1f} / "
                        f"+{result['mcmc_depth_err_hi_ppm']:.1f} ppm ({result['mcmc_move']}, "
                        f"{result['mcmc_walkers']} walkers x {result['mcmc_steps']} steps, "
                        f"N/tau {result.get('mcmc_n_over_tau') or float('nan'):.0f})")
    if result.get("time_conversion"):
        lines.append(f"times         {result['time_conversion']}")
    wrote = [result["result_file"], result["lightcurve_file"]] + [
        result[k] for k in ("chain_file", "plot_file", "corner_file") if result.get(k)]
    lines.append("wrote         " + ", ".join(wrote))
    return "\n".join(lines)
