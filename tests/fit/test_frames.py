"""Which frames a fit uses: the settling AOR rule and the frame counts of the result."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from eclipsebench.config.reduce import ReduceSection
from eclipsebench.fit.frames import settling_aor
from eclipsebench.fit.reduce import reduce_epoch


def _two_aor_table(xo3_epoch, pre_fraction=0.06):
    t = xo3_epoch["table"](seed=3)[::3]
    n_pre = int(pre_fraction * len(t))
    aor = np.asarray(t["aorkey"]).copy()
    aor[:n_pre] = 20150000
    t["aorkey"] = aor
    t["flag"][n_pre + 5] = 1   # one flagged frame of the Main AOR
    return t, n_pre


def test_short_first_aor_is_the_settling_aor():
    t = np.arange(1000) * 2.0 / 86400
    aor = np.where(np.arange(1000) < 60, 1, 2)
    assert settling_aor(t, aor).sum() == 60
    long_first = np.where(np.arange(1000) < 500, 1, 2)
    assert not settling_aor(t, long_first).any()
    late_short = np.where(np.arange(1000) < 940, 1, 2)   # a short AOR last is not settling
    assert not settling_aor(t, late_short).any()


def test_reduce_fits_the_main_aor_and_counts_what_it_left_out(xo3_epoch, polygain):
    table, n_pre = _two_aor_table(xo3_epoch)
    options = ReduceSection(prayer_bead_shifts=0)
    dropped = reduce_epoch(table, polygain.name, options=options).to_dict()
    assert dropped["n_frames"] == len(table) - n_pre - 1
    assert dropped["n_frames_dropped"] == {"flagged": 1, "nonfinite": 0, "settling_aor": n_pre}
    kept = reduce_epoch(table, polygain.name,
                        options=replace(options, settling_aor="keep")).to_dict()
    assert kept["n_frames"] == len(table) - 1
    assert kept["n_frames_dropped"]["settling_aor"] == 0
    assert dropped["depth_ppm"] != kept["depth_ppm"]
