"""A plugin package as a third party would write it: one learner and one environment.

Its dist-info folder beside it is what ``pip install`` leaves, so putting this folder on the
path installs it as far as importlib.metadata (and so flctool) can tell.
"""

from typing import Literal

from pydantic import Field

from flctool.plugins import Plugin
from flctool.spec.environment import AdapterConfig
from flctool.spec.learning import LearningConfig


class RandomSearchConfig(LearningConfig):
    """``learning:`` of the random search: the keys every learner reads plus its own."""

    learner: Literal["random_search"] = "random_search"
    keep: int = Field(1, ge=1, description="best controllers kept into the next generation")


class LineConfig(AdapterConfig):
    """``environment:`` of the line world."""

    adapter: Literal["line"]
    max_steps: int = Field(20, ge=1)
    goal: float = Field(9.0, description="x at which an episode succeeds")


LEARNER = Plugin("random_search", "flctool_demo.learner:RandomSearchLearner", RandomSearchConfig)
ENVIRONMENT = Plugin("line", "flctool_demo.env:LineEnv", LineConfig)
