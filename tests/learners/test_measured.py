"""The measured tasks ``flctool show`` cites: each row is of the file it names."""

from __future__ import annotations

import pytest

from flctool import load_behaviour
from flctool.learners.extension import most_generations
from flctool.learners.measured import MEASURED, SEEDS, similar_tasks
from tests.conftest import BEHAVIOURS, ROOT


@pytest.mark.parametrize("task", MEASURED, ids=lambda t: t.name)
def test_a_row_has_its_file_s_size_learner_and_training_budget(task: object) -> None:
    from flctool.learners.measured import MeasuredTask

    assert isinstance(task, MeasuredTask)
    path = BEHAVIOURS / f"{task.name}.yaml"
    if not path.exists():
        path = ROOT / "benchmarks" / "tasks" / f"{task.name}.yaml"
    behaviour = load_behaviour(path)
    learning = behaviour.learning
    assert task.rules == len(behaviour.missing_rules())
    assert task.commands == len(behaviour.output.commands)
    assert task.learner == learning.learner
    per_generation = learning.population * learning.trials
    if learning.extend is None:
        assert task.training == learning.generations * per_generation
    else:  # the median of what the runs used, between the run's least and most
        most = learning.extend.most or most_generations(task.rules, task.commands,
                                                        learning.generations)
        assert learning.generations * per_generation <= task.training <= most * per_generation


def test_similar_tasks_are_the_nearest_in_size() -> None:
    assert [t.name for t in similar_tasks(25, 5)][:1] == ["dribble"]
    assert {t.name for t in similar_tasks(5, 3, count=2)} == {"face-goal", "face-goal-fine"}
    assert len(similar_tasks(1000, 9)) == 3


def test_the_rows_seeds_are_the_suite_s_in_the_docs() -> None:
    """flctool show names the seeds the rows were measured on: those of the docs' table."""
    text = (ROOT / "docs" / "learning.md").read_text(encoding="utf-8")
    assert f"on training seeds {SEEDS}, which took no part in any choice" in " ".join(
        text.split())
