"""flctool-demo: a random-search learner and a one-dimensional line world for flctool.

The entries (named by the package's entry points) and the models of the behaviour-file
sections they read; the implementations are imported only when a file names them.
"""

from typing import Literal

from pydantic import Field

from flctool.behaviour.environment import AdapterConfig
from flctool.behaviour.learning import LearningConfig
from flctool.errors import Problem
from flctool.plugins import Plugin


class RandomSearchConfig(LearningConfig):
    """``learning:`` of the random search: the keys every learner reads plus its own."""

    learner: Literal["random_search"] = "random_search"
    keep: int = Field(1, ge=1, description="best controllers kept into the next generation")


class LineConfig(AdapterConfig):
    """``environment:`` of the line world."""

    adapter: Literal["line"]
    max_steps: int = Field(20, ge=1)
    goal: float = Field(9.0, description="x at which an episode succeeds")

    def fit_problems(self, inputs: tuple[str, ...], commands: tuple[str, ...]) -> list[Problem]:
        # The world observes one thing, x: a behaviour must read exactly that.
        if inputs == ("x",):
            return []
        return [Problem(("inputs",), f"the line world observes x only, not {', '.join(inputs)}",
                        "give the behaviour one input, named x")]


LEARNER = Plugin("random_search", "flctool_demo.learner:RandomSearchLearner", RandomSearchConfig)
ENVIRONMENT = Plugin("line", "flctool_demo.env:LineEnv", LineConfig)
