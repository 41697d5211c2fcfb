"""A tiny experiment on the shipped ballchase behaviour, shared by the experiment tests."""

from __future__ import annotations

from pathlib import Path

from flctool import load_behaviour
from flctool.experiment import Experiment, ExperimentPlan, prepare_experiment
from flctool.runs import resolve_behaviour

from ..conftest import BEHAVIOURS

TINY = {"generations": 3, "population": 4}
LEARNERS = ("pitt", "hybrid", "fuzzy_q")


def tiny_experiment(path: Path, seeds: int = 2, learners: tuple[str, ...] = LEARNERS,
                    ) -> Experiment:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"), TINY)
    plan = ExperimentPlan(behaviour.name, learners, seeds, heldout_episodes=20,
                          overrides=dict(TINY))
    return prepare_experiment(behaviour, plan, path)
