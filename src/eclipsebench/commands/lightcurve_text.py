"""The text ``eclipsebench lightcurve`` prints: L(t)'s summary, or the phase-model biases."""

from __future__ import annotations

__all__ = ["format_text"]


def format_text(result: dict) -> str:
    if "phase_bias_ppm" in result:
        return _format_phase_bias(result)
    lines = [
        f"system                {result['system']}",
        f"eclipse depth         {result['eclipse_depth_ppm']:.1f} ppm"
        + (" (fixed)" if result["depth_fixed"] else ""),
        f"model depth           {result['model_depth_ppm']:.1f} ppm "
        f"(tau_rad = {result['options']['tau_rad_days']:g} d); "
        f"instantaneous re-radiation {result['model_depth_instantaneous_ppm']:.1f} ppm",
        f"transit / eclipse     BJD {result['t_transit_bjd']:.5f} / {result['t_eclipse_bjd']:.5f}",
        f"samples               {result['n_samples']} from BMJD {result['start_bmjd']:.5f} "
        f"to {result['stop_bmjd']:.5f}",
    ]
    if "out_file" in result:
        lines.append(f"written               {result['out_file']}")
    if "plot_file" in result:
        lines.append(f"plot                  {result['plot_file']}")
    return "\n".join(lines)


def _format_phase_bias(result: dict) -> str:
    lines = [f"{result['system']}, challenge epoch {result['epoch']}: {result['n_frames']} frames "
             f"from BMJD {result['start_bmjd']:.4f}, mid-eclipse "
             f"{result['eclipse_after_start_hours']:.2f} h after the start, depth "
             f"{result['depth_ppm']:.1f} ppm",
             "phase model   depth bias (ppm, fitted - true; Section 4.2)"]
    lines += [f"{name:<13} {value:+8.1f}" for name, value in result["phase_bias_ppm"].items()]
    return "\n".join(lines)
