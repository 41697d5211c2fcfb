"""Learning the sets with the consequents: every built-in learner, resumed bit for bit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flctool import load_behaviour
from flctool.behaviour import Behaviour
from flctool.errors import LearnError
from flctool.learners import Callback, GenerationMetrics, make_learner, train
from flctool.learners.set_genes import SetOperators, initial_set_genes
from flctool.plugins import names
from flctool.runs import BEST_FILE, create_run, open_run, resolve_behaviour
from tests.conftest import BEHAVIOURS


class StopAfter(Callback):
    def __init__(self, generation: int) -> None:
        self.generation = generation

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        return metrics.generation < self.generation


def ballchase(learner: str, sets: dict[str, object], **learning: object) -> Behaviour:
    return resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"), {
        "learner": learner, "population": 4, "generations": 4, "seed": 3,
        "selection.candidates": 2, "selection.episodes": 4, "sets": sets, **learning})


SETS = [{"mode": "partition"},
        {"mode": "lateral", "inputs": {"pan": {"fixed": ["ahead"]}}, "floor": 0.3}]


#: Learners that learn consequents only: the credit learner (learning.sets is an error
#: there, tests/learners/test_credit.py).
CONSEQUENTS_ONLY = {"credit"}


@pytest.mark.parametrize("learner", [n for n in names("learner") if n not in CONSEQUENTS_ONLY])
@pytest.mark.parametrize("sets", SETS, ids=["partition", "lateral"])
@pytest.mark.slow
def test_every_learner_learns_the_sets_and_resumes_bit_for_bit(
        tmp_path: Path, learner: str, sets: dict[str, object]) -> None:
    behaviour = ballchase(learner, sets)
    whole = create_run(behaviour, tmp_path / "a")
    summary = whole.train()
    part = create_run(behaviour, tmp_path / "b")
    assert part.train([StopAfter(1)]).status == "stopped"
    resumed = open_run(part.path).train()
    assert resumed.usage == summary.usage
    assert (part.path / BEST_FILE).read_text().split("\n", 1)[1] == (
        whole.path / BEST_FILE).read_text().split("\n", 1)[1]
    last = whole.checkpoint_generations()[-1]
    a, b = part.checkpoint(last), whole.checkpoint(last)
    for state in (a, b):
        state.pop("elapsed"), state["metrics"].pop("wall_time")
    assert a == b
    best = load_behaviour(whole.path / BEST_FILE)  # a normal behaviour file
    assert best.is_deployable and list(best.inputs) == list(behaviour.inputs)
    for name, variable in best.inputs.items():
        assert list(variable.sets) == list(behaviour.inputs[name].sets)
        assert variable.range == behaviour.inputs[name].range
    if sets["mode"] == "lateral":
        assert best.inputs["pan"].sets["ahead"] == behaviour.inputs["pan"].sets["ahead"]
    # the population's sets moved: a learner that learns sets tries others than the file's
    assert np.abs(np.array(a["set_genes"])).max() > 0


def test_without_learning_sets_a_run_holds_no_set_genes(tmp_path: Path) -> None:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"population": 4, "generations": 2})
    run = create_run(behaviour, tmp_path / "r")
    run.train()
    assert "set_genes" not in run.checkpoint(1)


def test_a_checkpoint_with_set_genes_outside_the_genome_is_refused() -> None:
    behaviour = ballchase("hybrid", SETS[0])
    learner = make_learner(behaviour)
    train(learner, [StopAfter(0)])
    state = learner.state_dict()
    state["set_genes"][0][0] = 2.0
    with pytest.raises(LearnError, match=r"outside \[-1, 1\]"):
        make_learner(behaviour).load_state_dict(state)
    state["set_genes"] = [row[:-1] for row in state["set_genes"]]
    with pytest.raises(LearnError, match="set genes have shape"):
        make_learner(behaviour).load_state_dict(state)


def test_set_operators_keep_genes_in_range_and_inherit_inputs_whole() -> None:
    rng = np.random.default_rng(0)
    genes = initial_set_genes(rng, 5, 6, 0.5)
    assert (genes[0] == 0).all() and np.abs(genes).max() <= 1.0
    operators = SetOperators([(0, 2), (2, 6)], rate=1.0, sigma=5.0)
    a, b = np.full(6, 0.25), np.full(6, -0.25)
    for _ in range(20):
        child = operators.crossover(rng, a, b)
        assert set(child[:2]) in ({0.25}, {-0.25}) and set(child[2:]) in ({0.25}, {-0.25})
        mutated = operators.mutation(rng, child)
        assert np.abs(mutated).max() <= 1.0
