"""A trust folder's reductions read back: the real fits and the twins' depths, errors,
``beta_red``, mid-event times and phase-curve quantities per method, with the methods skipped
and the twins failed."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..astro.events import event_for
from .layout import TrustLayout
from .score import PHASE_QUANTITIES

__all__ = ["collect"]


def _load(path: Path) -> dict[str, Any]:
    return json.loads(Path(path).read_text())


#: A phase-curve result's keys that the twins' phase statistics read (value and error).
_PHASE_KEYS = tuple(k for name, unit, _ in PHASE_QUANTITIES
                    for k in (f"{name}_{unit}", f"{name}_err_{unit}"))


def collect(root: Path, methods: Sequence[str], n_twins: int, event: str = "eclipse"
            ) -> tuple[dict, dict, dict[str, str], dict[str, int]]:
    """Real results, twin ``(depths, errors, beta_red, twin numbers, mid-event times, their
    errors, phase quantities)`` per method (times in BMJD_TDB and days; the phase
    quantities ``{key: values}`` with the keys of :data:`~eclipsebench.trust.score.
    PHASE_QUANTITIES` and their errors, NaN where a result has none), skipped methods,
    failed twins."""
    when = event_for(event).time_prefix
    layout = TrustLayout(Path(root))
    real: dict = {}
    twins: dict = {}
    skipped: dict[str, str] = {}
    failed: dict[str, int] = {}
    for m in methods:
        data = _load(layout.real(m))
        if data.get("failed"):
            skipped[m] = data["error"]
            continue
        real[m] = data
        d, e, b, n, t, te = [], [], [], [], [], []
        phase: dict[str, list[float]] = {k: [] for k in _PHASE_KEYS}
        for i in range(1, n_twins + 1):
            res = _load(layout.twin_result(m, i))
            if res.get("failed") or not np.isfinite(res.get("depth_err_ppm") or np.nan):
                failed[m] = failed.get(m, 0) + 1
                continue
            d.append(res["depth_ppm"])
            e.append(res["depth_err_ppm"])
            b.append(np.nan if res.get("beta_red") is None else res["beta_red"])
            n.append(i)
            t.append(np.nan if res.get(f"{when}_bmjd") is None else res[f"{when}_bmjd"])
            te.append(np.nan if res.get(f"{when}_err_d") is None else res[f"{when}_err_d"])
            for key in _PHASE_KEYS:
                phase[key].append(np.nan if res.get(key) is None else res[key])
        if len(d) < 2:
            skipped[m] = f"{len(d)} of {n_twins} twins reduced: too few to score"
            del real[m]
            continue
        twins[m] = (d, e, b, n, t, te, phase)
    return real, twins, skipped, failed
