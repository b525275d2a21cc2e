"""The events carry the facts callers branch on (issue 39): one class each, asked, not compared."""

from __future__ import annotations

import re
import typing
from pathlib import Path

import numpy as np
import pytest

from eclipsebench.astro.catalogue import get_system
from eclipsebench.astro.events import EVENT_CLASSES, event_for
from eclipsebench.astro.orbit import eclipse_time_bmjd, transit_time_bmjd
from eclipsebench.config.reduce import ReduceSection
from eclipsebench.config.simulation import ObservationSection
from eclipsebench.errors import InputError
from eclipsebench.fit.model import AstroModel
from eclipsebench.fit.names import EVENTS
from eclipsebench.fit.prepare import predicted_event_bmjd

SRC = Path(__file__).resolve().parents[2] / "src" / "eclipsebench"
XO3 = get_system("XO-3b (2015 challenge)")

_NAME = r"""['"](?:eclipse|transit|phase-curve)['"]"""
#: A comparison of an event's name: ``x == "transit"``, ``"eclipse" != x``, ``x in ("transit",
#: ...)``, ``x == {"transit"}``, or a dict keyed by event names (``{"eclipse": (...``).
BRANCH = re.compile(rf"(?:==|!=)\s*[{{(\[]?\s*{_NAME}|{_NAME}\s*(?:==|!=)|\bin\s*[(\[{{]\s*{_NAME}"
                    rf"|[{{,]\s*{_NAME}\s*:\s*[(\[{{]")
#: Where comparing the names is the point: the event classes themselves.
EVENT_CLASS_MODULES = {"astro/events.py"}


def test_the_branch_pattern_catches_what_it_counts():
    caught = ['if options.event == "eclipse":', 'if event != "phase-curve":',
              'x = a if self.event_detail.get("event") == "transit" else b',
              'if obs.event in ("transit", "phase-curve") and system is None:',
              'or events == {"transit"}:', 'events = {"eclipse": (("eclipse", f),),',
              """f"the {'transit' if r['event'] == 'transit' else 'eclipse'}" """]
    assert all(BRANCH.search(line) for line in caught)
    assert not BRANCH.search('event: Literal["eclipse", "transit", "phase-curve"] = "eclipse"')


def test_at_most_three_event_name_comparisons_outside_the_event_classes():
    found = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel in EVENT_CLASS_MODULES:
            continue
        lines = path.read_text().splitlines()
        for n, line in enumerate(lines, start=1):
            if BRANCH.search(line.split("#")[0]):
                found.append(f"{rel}:{n}: {line.strip()}")
                # each says why, on its line or in the comment just above it
                above = lines[n - 2].strip() if n > 1 else ""
                assert "#" in line or above.startswith("#"), found[-1]
    assert len(found) <= 3, "\n".join(found)


def test_every_event_has_one_class_and_the_names_agree():
    assert tuple(EVENT_CLASSES) == EVENTS
    for section in (ReduceSection, ObservationSection):
        hints = typing.get_type_hints(section, include_extras=True)
        assert typing.get_args(hints["event"]) == EVENTS
    assert event_for(None) is event_for("eclipse")
    with pytest.raises(InputError, match=r"event 'occultation': expected one of eclipse, "
                                         r"transit, phase-curve"):
        event_for("occultation")


@pytest.mark.parametrize("name", EVENTS)
def test_the_fitted_model_and_its_event_share_the_facts(name):
    t = eclipse_time_bmjd(XO3, 57234.5) if name != "transit" else transit_time_bmjd(XO3, 57234.5)
    phase = "harmonic1" if name == "phase-curve" else "flat"
    model = AstroModel.build(t + np.linspace(-0.1, 0.1, 50), XO3, phase=phase, event=name)
    facts = event_for(name)
    assert type(model).facts is facts and model.whole_orbit == facts.whole_orbit
    assert model.names[1] == facts.time_key
    # the size of a depth is the inverse of the model's depth of its size
    assert model.depth_ppm(facts.size_from_depth(6400.0)) == pytest.approx(6400.0, rel=1e-12)
    assert AstroModel.event_class(name).phase_models == model.phase_models


def test_facts_of_each_event():
    eclipse, transit, phase = (event_for(n) for n in EVENTS)
    assert [e.time_prefix for e in (eclipse, transit, phase)] == ["t_ecl", "t_transit", "t_ecl"]
    assert [e.mid_label for e in (eclipse, transit, phase)] == [
        "mid-eclipse", "mid-transit", "mid-eclipse"]
    assert transit.replaced_time_keys == ("t_ecl_bmjd", "t_ecl_err_d", "t_ecl_predicted_bmjd")
    assert eclipse.replaced_time_keys == phase.replaced_time_keys == ()
    assert [e.default_sampler for e in (eclipse, transit, phase)] == ["mcmc", "mcmc", "leastsq"]
    assert [ReduceSection(event=n).resolved_sampler() for n in EVENTS] == [
        "mcmc", "mcmc", "leastsq"]
    assert (eclipse.joint_fit, transit.joint_fit, phase.joint_fit) == (True, False, False)
    assert [e.observed for e in (eclipse, transit, phase)] == [
        ("eclipse",), ("transit",), ("eclipse", "transit")]
    assert transit.size_from_depth(8208.36) == pytest.approx(0.0906, rel=1e-5)


def test_the_predicted_time_is_the_events_conjunction():
    time = transit_time_bmjd(XO3, 57234.5) + np.linspace(-0.1, 0.1, 20)
    assert predicted_event_bmjd(XO3, time, event="transit") == transit_time_bmjd(XO3, 57234.5)
    with pytest.raises(InputError, match="eclipse nearest the data"):
        predicted_event_bmjd(XO3, time, event="eclipse")


def test_detail_lines_of_a_printout():
    result = {"rp_rs": 0.09, "rp_rs_err": 0.001}
    assert event_for("transit").detail_lines(result) == [
        "rp_rs         0.09000 +- 0.00100 (depth = rp_rs^2)"]
    assert event_for("eclipse").detail_lines(result) == []
