"""An experiment's behaviour: one file carrying the learning keys of every compared learner."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from flctool import load_behaviour
from flctool.behaviour import behaviour_to_data, behaviour_to_yaml
from flctool.behaviour.overrides import Override
from flctool.errors import RunDirError, SpecError
from flctool.experiment import (
    ExperimentPlan,
    open_experiment,
    prepare_experiment,
    read_experiment_behaviour,
    share_behaviour,
)
from flctool.runs import resolve_behaviour

from ..conftest import BEHAVIOURS
from .helpers import MIXED_LEARNING, line_of, write_mixed

LEARNERS = ("pitt", "hybrid", "fuzzy_q")
def test_each_learner_keeps_exactly_its_keys(tmp_path: Path) -> None:
    file = write_mixed(tmp_path)
    with pytest.raises(SpecError, match="read by the pitt learner only"):
        load_behaviour(file)  # on its own the file is its learner's: strict as before
    shared = read_experiment_behaviour(file, LEARNERS, {"q.temperature": 0.2})
    pitt, hybrid, fuzzy_q = (shared.of(name).learning for name in LEARNERS)
    assert pitt.learner == "pitt" and pitt.pitt_crossover == "one_point"
    assert not hasattr(pitt, "q") and not hasattr(pitt, "exploration")
    assert hybrid.q.temperature == 0.2 and not hasattr(hybrid, "pitt_crossover")
    assert not hasattr(hybrid, "exploration")
    assert fuzzy_q.q.temperature == 0.2 and fuzzy_q.exploration.epsilon == 0.3
    assert fuzzy_q.exploration.policy == "epsilon_greedy"
    assert {section.population for section in (pitt, hybrid, fuzzy_q)} == {4}
    # kept as one file that reads back to the same behaviours
    kept = tmp_path / "kept.yaml"
    kept.write_text(shared.to_yaml())
    assert read_experiment_behaviour(kept, LEARNERS) == shared


def test_a_file_without_other_learners_keys_is_kept_as_before(tmp_path: Path) -> None:
    """Directories of earlier versions compare as the same plan: same text, same runs."""
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"q.alpha": 0.3, "generations": 2})
    shared = share_behaviour(behaviour, LEARNERS)
    assert shared.to_yaml("header") == behaviour_to_yaml(behaviour, "header")
    for learner in LEARNERS:
        assert shared.of(learner) == resolve_behaviour(behaviour, {"learner": learner})
    read = read_experiment_behaviour(BEHAVIOURS / "ballchase.yaml", LEARNERS,
                                     {"q.alpha": 0.3, "generations": 2})
    assert read == shared


def test_keys_no_compared_learner_reads_are_located_errors(tmp_path: Path) -> None:
    file = write_mixed(tmp_path)
    with pytest.raises(SpecError) as info:
        read_experiment_behaviour(file, ("pitt", "hybrid"))
    [problem] = info.value.problems
    assert problem.path == ("learning", "exploration")
    assert (problem.file, problem.line) == (str(file), line_of(file, "  exploration:"))
    assert "read by the fuzzy_q learner only, which this experiment does not compare" in \
        problem.message
    assert "add fuzzy_q to --learners" in problem.hint

    with pytest.raises(SpecError) as info:
        read_experiment_behaviour(file, ("fuzzy_q",), [
            Override("crossover", 0.5, "command line (--set crossover)"),
            Override("exploration.decay", 0.9, "command line (--set exploration.decay)")])
    [problem] = info.value.problems  # exploration is fuzzy_q's: applied, not refused
    assert problem.file == "command line (--set crossover)"
    assert "read by the pitt and hybrid learners, none of which this experiment compares" \
        in problem.message
    assert "add pitt or hybrid" in problem.hint


def test_the_experiment_decides_learner_and_seed(tmp_path: Path) -> None:
    with pytest.raises(SpecError) as info:
        read_experiment_behaviour(BEHAVIOURS / "ballchase.yaml", LEARNERS,
                                  {"learner": "pitt", "learning.seed": 3})
    assert [(p.path, p.hint) for p in info.value.problems] == [
        (("learning", "learner"), "use --learners"), (("learning", "seed"), "use --seeds")]


def test_bad_values_are_located_once(tmp_path: Path) -> None:
    file = write_mixed(tmp_path, MIXED_LEARNING.replace("one_point", "two").replace(
        "epsilon: 0.3", "epsilon: 3") + "  q:\n    temperature: -1\n  populaton: 3\n")
    with pytest.raises(SpecError) as info:
        read_experiment_behaviour(file, LEARNERS)
    found = [(p.line, p.path[-1]) for p in info.value.problems]
    # q is read by hybrid and fuzzy_q, but its problem is said once; the typo by the file's
    # own learner
    assert found == [(line_of(file, "  pitt_crossover: two"), "pitt_crossover"),
                     (line_of(file, "    epsilon: 3"), "epsilon"),
                     (line_of(file, "    temperature: -1"), "temperature"),
                     (line_of(file, "  populaton: 3"), "populaton")]
    assert "Did you mean 'population'" in info.value.problems[-1].message


def test_the_files_own_learner_keeps_its_keys_when_not_compared(tmp_path: Path) -> None:
    file = write_mixed(tmp_path, "learning:\n  learner: hybrid\n  q:\n    alpha: 0.5\n")
    shared = read_experiment_behaviour(file, ("pitt",))
    assert shared.own.learning.q.alpha == 0.5
    assert "q" not in behaviour_to_data(shared.of("pitt"))["learning"]


def test_changed_keys_of_another_learner_are_another_plan(tmp_path: Path) -> None:
    file = write_mixed(tmp_path)
    plan = ExperimentPlan("ballchase", LEARNERS, 1, heldout_episodes=10)
    first = prepare_experiment(read_experiment_behaviour(file, LEARNERS), plan, tmp_path / "x")
    again = prepare_experiment(read_experiment_behaviour(file, LEARNERS), plan, tmp_path / "x")
    assert again.behaviour == first.behaviour == open_experiment(tmp_path / "x").behaviour
    file.write_text(file.read_text().replace("epsilon: 0.3", "epsilon: 0.4"))
    with pytest.raises(RunDirError, match=r"different plan \(it differs in: the behaviour\)"):
        prepare_experiment(read_experiment_behaviour(file, LEARNERS), plan, tmp_path / "x")


def test_an_experiment_recorded_with_every_key_continues(tmp_path: Path) -> None:
    """Earlier versions wrote every key of every learner into the experiment's
    behaviour.yaml; such a directory is the same plan as the file it came from, and its runs
    keep the other learners' values it recorded."""
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"generations": 2})
    plan = ExperimentPlan("ballchase", ("pitt", "hybrid"), 1, heldout_episodes=10)
    experiment = prepare_experiment(behaviour, plan, tmp_path / "old")
    recorded = yaml.safe_load((experiment.path / "behaviour.yaml").read_text())
    recorded["learning"].update(pitt_crossover="uniform",
                                exploration={"policy": "boltzmann", "epsilon": 0.1,
                                             "decay": 1.0, "minimum": 0.0})
    (experiment.path / "behaviour.yaml").write_text(yaml.safe_dump(recorded, sort_keys=False))
    assert prepare_experiment(behaviour, plan, tmp_path / "old").jobs() == experiment.jobs()
    recorded["learning"]["pitt_crossover"] = "one_point"
    (experiment.path / "behaviour.yaml").write_text(yaml.safe_dump(recorded, sort_keys=False))
    reopened = open_experiment(tmp_path / "old")
    assert reopened.behaviour.of("pitt").learning.pitt_crossover == "one_point"
