"""A method's facts: declared once (type parameter, docstring, record, the teams' table).

Issue 27: a method class says its registry name, the columns it needs and
its record; its options come from its type parameter, its description from
its docstring, its docs anchor from its heading in docs/methods.md, and its
team's pipeline from ``data/paper_teams.toml``.
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated, ClassVar

import numpy as np
import pytest

from eclipsebench.decorrelate import available_methods, get_method
from eclipsebench.decorrelate.base import AtLeast, EpochData, MethodOptions, Systematics
from eclipsebench.decorrelate.record import PaperProfile, heading_anchor, team_profile
from eclipsebench.errors import ConfigError, InputError

METHODS_MD = Path(__file__).resolve().parents[2] / "docs" / "methods.md"
BUILT_IN = [m for m in available_methods()
            if get_method(m).__module__.startswith("eclipsebench.")]


def test_each_built_in_method_s_docs_anchor_is_a_heading_of_methods_md():
    headings = {heading_anchor(line.lstrip("#"))
                for line in METHODS_MD.read_text().splitlines() if line.startswith("## ")}
    for name in BUILT_IN:
        assert get_method(name).record.docs_anchor in headings, name


def test_every_team_of_the_data_file_is_a_built_in_method_s_whole_profile():
    text = resources.files("eclipsebench.data").joinpath("paper_teams.toml").read_text()
    teams = tomllib.loads(text)
    used = [get_method(m).record.paper for m in BUILT_IN]
    required = {f.name for f in dataclasses.fields(PaperProfile)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    for key, entry in teams.items():
        assert required <= set(entry), key
        assert set(entry["why"]) == {"centroid", "phase", "ramp", "fit", "error"}, key
        assert team_profile(key) in used, key
    assert get_method("kr-data").record.paper.method_options == {"k": 50}


@dataclass(frozen=True)
class _ShortOptions(MethodOptions):
    k: Annotated[int, AtLeast(2)] = 3


class _Short(Systematics[_ShortOptions]):
    """A method declared the short way.

    Its second paragraph is not its description.
    """

    name: ClassVar[str] = "short"
    requires: ClassVar[tuple[str, ...]] = ("x",)

    def setup(self, data: EpochData) -> None:
        self.calls = getattr(self, "calls", 0) + 1
        self.mean_x = float(np.mean(data.x)) * self.options.k

    def predict(self, astro, theta=None):
        return astro * np.mean(self.data.flux)


def test_a_method_takes_options_from_its_type_and_description_from_its_docstring():
    assert _Short.Options is _ShortOptions
    assert _Short.description == "A method declared the short way."
    data = EpochData(time_bmjd=np.arange(5.0), flux=np.ones(5), flux_err=np.ones(5),
                     x=np.arange(5.0), y=None)
    built = _Short(data, k=4)
    assert built.calls == 1 and built.mean_x == pytest.approx(8.0)
    with pytest.raises(InputError, match="method 'short' option 'k': expected an integer >= 2"):
        _Short(data, k=1)
    # the bound reaches an option inherited from a parent: kr-pmap's k is KR/Data's
    with pytest.raises(ConfigError, match="'k': expected an integer >= 1"):
        get_method("kr-pmap").Options(k=0)
