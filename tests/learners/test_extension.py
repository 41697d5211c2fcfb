"""How long a run learns: its generations, and past them while it improves (learning.extend)."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from flctool import load_behaviour
from flctool.behaviour.learning import ExtendConfig
from flctool.errors import LearnError, SpecError
from flctool.learners import Callback, GenerationMetrics, make_learner, train
from flctool.learners.extension import Extension, held_most, most_generations
from flctool.runs import resolve_behaviour
from flctool.training import resume_run, start_run
from tests.conftest import BEHAVIOURS
from tests.learners.line_env import LineEnv, cut_and_resumed, line_behaviour


def extended(**learning: object) -> object:
    """The line behaviour with an extension (its file gives generations: so it has none)."""
    return line_behaviour(**{"extend": {"patience": 3, "most": 20}, **learning})


def test_a_file_without_a_budget_is_extended_and_one_with_a_budget_is_exact() -> None:
    assert load_behaviour(BEHAVIOURS / "ballchase.yaml").learning.extend == ExtendConfig()
    assert line_behaviour().learning.extend is None  # its file gives generations: 6
    paper = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                              {"protocol": "paper"})
    assert paper.learning.extend is None and paper.learning.generations == 30
    with pytest.raises(SpecError, match="leave one of them out"):
        line_behaviour(protocol="paper", extend={"patience": 2})


def test_an_extended_run_goes_on_while_it_improves_and_ends_after_its_patience() -> None:
    # fuzzy_q cannot start afresh: one attempt, extended while it improves
    learner = make_learner(extended(generations=2, learner="fuzzy_q"), LineEnv())
    history = train(learner)
    extension = learner.extension
    assert extension.enabled and extension.starts == [0]
    last = history[-1].generation
    # it ended `patience` generations after the last improvement (at least at 2), or at most
    assert last + 1 == min(20, max(2, extension.improved_at + 1 + 3))
    assert learner.planned_generations() == last + 1


@pytest.mark.parametrize("name", ["pitt", "hybrid"])
def test_the_room_left_goes_to_fresh_attempts(name: str) -> None:
    learner = make_learner(extended(generations=3, learner=name), LineEnv())
    seen: dict[int, list[list[int]]] = {}

    class Watch(Callback):
        def on_generation(self, metrics: GenerationMetrics) -> bool:
            assert self.learner is not None
            seen[metrics.generation] = self.learner.population.tolist()
            return True

    history = train(learner, [Watch()])
    starts = learner.extension.starts
    assert len(starts) >= 2 and starts[0] == 0
    last = history[-1].generation
    # the run ends when no fresh attempt of 3 generations fits in most (20), or at most
    assert last + 1 == 20 or last + 1 + 3 > 20
    assert all(b - a >= 3 for a, b in itertools.pairwise(starts))
    # an attempt's first generation is drawn afresh: no elite carried over from before
    first = starts[1]
    before = {tuple(row) for row in seen[first - 1]}
    assert not {tuple(row) for row in seen[first]} <= before
    record = learner.selection_record()["extension"]
    assert record == {"attempts": starts, "most": 20, "patience": 3}


def test_an_extended_run_never_passes_its_most() -> None:
    learner = make_learner(extended(generations=2, extend={"patience": 50, "most": 5}),
                           LineEnv())
    assert len(train(learner)) == 5


def test_a_learner_that_starts_afresh_begins_an_attempt_only_where_one_fits() -> None:
    extension = Extension(ExtendConfig(patience=3, most=40), least=30, most=40)
    extension.begin_attempt(5)
    assert extension.starts == [0, 5] and extension.planned() == 35
    extension.begin_attempt(5)  # the same attempt again: nothing new
    extension.begin_attempt(11)  # 11 + 30 > 40: no room for a whole attempt
    assert extension.starts == [0, 5]
    exact = Extension(None, least=30, most=60)
    exact.begin_attempt(5)  # without extend a run has exactly its generations
    assert exact.starts == [0] and exact.planned() == 30


def test_a_learner_that_begins_to_start_afresh_part_way_gets_room_for_its_attempts() -> None:
    # fuzzy_q once it holds its draws: three attempts of 30 from generation 5
    extension = Extension(ExtendConfig(patience=3), least=30, most=60)
    assert not extension.attempts
    extension.open_attempts(5, 3)
    assert extension.attempts and extension.most == 95
    # the latest they open is where one attempt still fits: the plan's bound
    latest = Extension(ExtendConfig(patience=3), least=30, most=60)
    latest.open_attempts(30, 3)
    assert latest.most == held_most(60, 30, 3) == 120
    late = Extension(ExtendConfig(patience=3), least=30, most=60)
    late.open_attempts(31, 3)  # 31 + 30 > 60: not one fresh attempt fits
    assert not late.attempts and late.most == 60
    given = Extension(ExtendConfig(patience=3, most=70), least=30, most=70)
    given.open_attempts(5, 3)  # extend.most bounds the run: attempts within it
    assert given.attempts and given.most == 70
    exact = Extension(None, least=30, most=60)
    exact.open_attempts(5, 3)  # without extend a run has exactly its generations
    assert not exact.attempts and exact.planned() == 30


@given(st.integers(1, 50), st.integers(0, 100), st.integers(0, 150), st.integers(1, 5))
def test_attempts_opened_part_way_stay_within_the_plans_bound(least: int, extra: int,
                                                              start: int, attempts: int) -> None:
    most = least + extra
    extension = Extension(ExtendConfig(patience=3), least=least, most=most)
    extension.open_attempts(start, attempts)
    assert most <= extension.most <= held_most(most, least, attempts)


def test_without_extend_a_run_has_exactly_its_generations() -> None:
    learner = make_learner(line_behaviour(generations=4), LineEnv())
    assert len(train(learner)) == 4 and not learner.extension.enabled


def test_an_extended_run_resumes_bit_for_bit() -> None:
    behaviour = extended(generations=2)
    whole = make_learner(behaviour, LineEnv())
    train(whole)
    state = json.loads(json.dumps(whole.state_dict()))
    second, _ = cut_and_resumed(behaviour, after=3)
    assert second.state_dict() == {**state, "elapsed": second.state_dict()["elapsed"]}


def test_a_damaged_extension_record_is_a_clear_error() -> None:
    learner = make_learner(extended(generations=2), LineEnv())
    train(learner)
    state = json.loads(json.dumps(learner.state_dict()))
    state["selection"]["extension"]["improved_at"] = -7
    with pytest.raises(LearnError, match="extension record is damaged"):
        make_learner(extended(generations=2), LineEnv()).load_state_dict(state)
    del state["selection"]["extension"]["best_seen"]
    with pytest.raises(LearnError, match="selection record is damaged"):
        make_learner(extended(generations=2), LineEnv()).load_state_dict(state)


def test_a_checkpoint_without_an_extension_continues_without_one() -> None:
    # a run of a version without extensions ends at its generations, as it would have
    learner = make_learner(extended(generations=2), LineEnv())
    train(learner)
    state = json.loads(json.dumps(learner.state_dict()))
    del state["selection"]["extension"]
    again = make_learner(extended(generations=2), LineEnv())
    again.load_state_dict(state)
    assert not again.extension.enabled and again.planned_generations() == 2


@given(rules=st.integers(0, 500), commands=st.integers(1, 20), least=st.integers(1, 200))
def test_the_bound_from_the_problem_grows_with_it_and_leaves_room(rules: int, commands: int,
                                                                   least: int) -> None:
    most = most_generations(rules, commands, least)
    assert most >= 2 * least and (most % 30 == 0 or most == 2 * least)
    assert most_generations(rules + 30, commands, least) >= most


@given(least=st.integers(1, 50), most=st.integers(1, 80), patience=st.integers(1, 20),
       improved=st.integers(-1, 100))
def test_the_planned_generations_stay_within_least_and_most(least: int, most: int,
                                                            patience: int,
                                                            improved: int) -> None:
    extension = Extension(ExtendConfig(patience=patience), least, most)
    extension.improved_at = improved
    assert least <= extension.planned() <= max(least, most)


def test_resuming_a_run_directory_keeps_its_extension(tmp_path: Path) -> None:
    tiny = {"population": 4, "selection.candidates": 2, "selection.episodes": 3,
            "selection.confirmation": 0, "extend.most": 4}
    path = BEHAVIOURS / "ballchase.yaml"
    training = start_run(path, tiny, tmp_path / "run")
    summary = training.train()
    assert summary.generations == 30  # a most below generations: exactly generations
    recorded = training.run.behaviour.learning.extend
    assert recorded is not None and recorded.most == 4
    # the same file and options resume the same run; the budget is the run's own
    resumed = resume_run(tmp_path / "run", path, tiny)
    try:
        assert resumed.run.behaviour.learning.extend == recorded
    finally:
        resumed.close()


def test_a_budget_given_is_exact_even_on_a_file_flctool_wrote_out(tmp_path: Path) -> None:
    from flctool.behaviour import behaviour_to_yaml

    written = tmp_path / "copy.yaml"  # every key written out, extend's defaults included
    written.write_text(behaviour_to_yaml(load_behaviour(BEHAVIOURS / "ballchase.yaml")))
    assert load_behaviour(written).learning.extend == ExtendConfig()
    assert resolve_behaviour(load_behaviour(written), {"generations": 2}).learning.extend \
        is None
    # an extend of the file's own stays
    own = resolve_behaviour(load_behaviour(written), {"extend.most": 90})
    assert resolve_behaviour(own, {"generations": 40}).learning.extend == ExtendConfig(most=90)


def test_resuming_with_more_generations_keeps_the_run_extending(tmp_path: Path) -> None:
    tiny = {"population": 4, "selection.candidates": 2, "selection.episodes": 3,
            "selection.confirmation": 0, "extend.patience": 1}
    start_run(BEHAVIOURS / "ballchase.yaml", tiny, tmp_path / "run").train()
    resumed = resume_run(tmp_path / "run", generations=70)
    try:
        learning = resumed.run.behaviour.learning
        assert learning.generations == 70 and learning.extend is not None
        assert learning.extend.patience == 1
    finally:
        resumed.close()
