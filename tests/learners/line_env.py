"""A tiny deterministic environment for learner tests (like stable-baselines3's identity env).

One input ``x`` in [0, 10]; the crisp output ``a`` moves x by ``a``. Reaching x >= 9 ends the
episode in success (+1), x <= 1 in failure (-1), ``max_steps`` steps truncate it. The start
is drawn from the episode's seed. The best controller says ``up`` in every rule.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from flctool import parse_behaviour
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.runs import resolve_behaviour

if TYPE_CHECKING:
    from flctool.learners import GenerationMetrics, Learner

LINE_BEHAVIOUR = """\
flctool: 1
name: line
inputs:
  x:
    range: [0, 10]
    sets:
      low: [0, 0, 2, 6]
      mid: [2, 5, 5, 8]
      high: [4, 8, 10, 10]
output:
  name: u
  commands: {down: -1, stay: 0, up: 1}
learning:
  seed: 3
  generations: 6
  population: 6
"""


def line_behaviour(**learning: Any) -> Behaviour:
    """The line behaviour with ``learning`` fields overridden (validated, as ``--set``)."""
    return resolve_behaviour(parse_behaviour(LINE_BEHAVIOUR, "line.yaml"), learning)


class LineEnv(BatchEnv):
    observation_names = ("x",)

    def __init__(self, max_steps: int = 20) -> None:
        self.max_steps = max_steps
        self.x = np.zeros(1)
        self.t = np.zeros(1, dtype=np.int64)
        self.done = np.zeros(1, dtype=np.bool_)
        self.reached = np.zeros(1, dtype=np.bool_)
        self.resets = 0

    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        self.resets += 1
        self.x = np.array([2.0 + 6.0 * np.random.default_rng(int(s)).random() for s in seeds])
        self.t = np.zeros(len(seeds), dtype=np.int64)
        self.done = np.zeros(len(seeds), dtype=np.bool_)
        self.reached = np.zeros(len(seeds), dtype=np.bool_)
        self.terminated = np.zeros(len(seeds), dtype=np.bool_)
        self.truncated = np.zeros(len(seeds), dtype=np.bool_)
        return self.x[:, None].copy(), {}

    def step(self, actions: FloatArray) -> Step:
        live = ~self.done
        self.x = np.where(live, self.x + actions, self.x)
        self.t = self.t + live
        success = live & (self.x >= 9.0)
        failure = live & (self.x <= 1.0)
        truncated = live & ~success & ~failure & (self.t >= self.max_steps)
        rewards = np.where(success, 1.0, np.where(failure, -1.0, 0.0))
        self.reached |= success
        self.terminated = self.terminated | success | failure
        self.truncated = self.truncated | truncated
        self.done |= self.terminated | self.truncated
        # flags stay set once an episode has ended, as the adapter protocol asks
        return Step(self.x[:, None].copy(), rewards, self.terminated.copy(),
                    self.truncated.copy())

    def success(self) -> BoolArray:
        return self.reached.copy()


def cut_and_resumed(behaviour: Behaviour, after: int) -> tuple[Learner, list[GenerationMetrics]]:
    """A run of ``behaviour`` on :class:`LineEnv` cut after generation ``after``, its
    checkpoint passed through JSON as a file would hold it, and resumed to its end: the
    resumed learner and the generations it ran."""
    from flctool.learners import Callback, make_learner, train

    class StopAfter(Callback):
        def on_generation(self, metrics: GenerationMetrics) -> bool:
            return metrics.generation < after

    first = make_learner(behaviour, LineEnv())
    train(first, [StopAfter()])
    second = make_learner(behaviour, LineEnv())
    second.load_state_dict(json.loads(json.dumps(first.state_dict())))
    return second, train(second)
