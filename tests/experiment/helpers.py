"""A tiny experiment on the shipped ballchase behaviour, shared by the experiment tests."""

from __future__ import annotations

from pathlib import Path

from flctool import load_behaviour
from flctool.experiment import Experiment, ExperimentPlan, prepare_experiment
from flctool.runs import resolve_behaviour

from ..conftest import BEHAVIOURS

TINY = {"generations": 3, "population": 4}
LEARNERS = ("pitt", "hybrid", "fuzzy_q")
#: A learning: section for an experiment: keys of pitt (pitt_crossover) and of fuzzy_q
#: (exploration) beside the hybrid's own.
MIXED_LEARNING = """\
learning:
  learner: hybrid
  seed: 0
  population: 4
  generations: 2
  pitt_crossover: one_point
  exploration:
    policy: epsilon_greedy
    epsilon: 0.3
"""


def write_mixed(tmp_path: Path, learning: str = MIXED_LEARNING) -> Path:
    """ballchase.yaml with ``learning`` as its section: a file for an experiment."""
    text = (BEHAVIOURS / "ballchase.yaml").read_text()
    start = text.index("learning:\n")
    end = text.index("environment:\n")
    path = tmp_path / "mixed.yaml"
    path.write_text(text[:start] + learning + text[end:])
    return path


def line_of(path: Path, text: str) -> int:
    """The line (from 1) of ``path`` that reads ``text``."""
    return path.read_text().splitlines().index(text) + 1


def tiny_experiment(path: Path, seeds: int = 2, learners: tuple[str, ...] = LEARNERS,
                    ) -> Experiment:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"), TINY)
    plan = ExperimentPlan(behaviour.name, learners, seeds, heldout_episodes=20,
                          overrides=dict(TINY))
    return prepare_experiment(behaviour, plan, path)
