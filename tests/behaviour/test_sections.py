"""The sections a plugin reads: a plugin whose model cannot read its section is named when a
file names it, and reads no key for the others."""

from __future__ import annotations

import pytest

from flctool.behaviour import parse_behaviour
from flctool.behaviour import sections as sections_module
from flctool.behaviour.learning import DEFAULT_LEARNER, PittConfig
from flctool.behaviour.sections import readers_of
from flctool.errors import PluginError
from flctool.plugins import Plugin, plugin, plugins
from tests.behaviour.test_load import GOOD

#: An installed learner whose model is Pitt's: it does not declare learner: Literal['mine'].
MINE = Plugin("mine", "flctool_mine:MineLearner", PittConfig)


@pytest.fixture
def mine_installed(monkeypatch: pytest.MonkeyPatch) -> None:
    def found(kind: str, name: str) -> Plugin | None:
        return MINE if (kind, name) == ("learner", "mine") else plugin(kind, name)

    monkeypatch.setattr(sections_module, "plugin", found)
    monkeypatch.setattr(sections_module, "plugins",
                        lambda kind: (*plugins(kind), *((MINE,) if kind == "learner" else ())))


@pytest.mark.usefixtures("mine_installed")
def test_a_file_naming_a_plugin_whose_model_cannot_read_the_section_names_the_plugin() -> None:
    with pytest.raises(PluginError) as info:
        parse_behaviour(GOOD + "learning:\n  learner: mine\n", "mine.yaml")
    message = str(info.value)
    assert "the learner plugin 'mine' (flctool_mine:MineLearner) cannot read 'learning:'" in (
        message)
    assert "its config must declare learner: Literal['mine']" in message
    assert "report it to the authors of its package (flctool_mine)" in message


@pytest.mark.usefixtures("mine_installed")
def test_a_plugin_whose_model_cannot_be_used_reads_no_key() -> None:
    assert readers_of("pitt_crossover") == ("pitt",)
    assert "mine" not in readers_of("seed")
    assert parse_behaviour(GOOD, "good.yaml").learning.learner == DEFAULT_LEARNER
