"""Model selection, budgets and stopping: seeds, the hall of fame, what a run returns."""

from __future__ import annotations

import csv
import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from flctool import load_behaviour
from flctool.behaviour import Behaviour
from flctool.behaviour.learning import SelectionConfig, StopConfig
from flctool.errors import LearnError
from flctool.learners import Callback, GenerationMetrics, make_learner, train
from flctool.learners.base import TRAIN_SEED_HIGH, TRAIN_SEED_LOW
from flctool.learners.confirmation import confirmation_seeds
from flctool.learners.metrics import Usage
from flctool.learners.selection import (
    RACE_FACTOR,
    VALIDATION_SEED_LOW,
    ModelSelection,
    race_cost,
    validation_seeds,
)
from flctool.learners.trial import run_trial
from flctool.plugins import names
from flctool.rollout import CONFIRMATION_SEED_LOW, evaluation_seeds
from flctool.runs import (
    BEST_FILE,
    ENDED,
    METRICS_FILE,
    create_run,
    open_run,
    resolve_behaviour,
)
from tests.conftest import BEHAVIOURS
from tests.learners.line_env import LineEnv, line_behaviour


class SeedRecordingEnv(LineEnv):
    """The line environment, recording the seeds of every reset: (batch size, seeds)."""

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[tuple[int, list[int]]] = []

    def reset(self, seeds: Any) -> Any:
        self.seen.append((len(seeds), [int(s) for s in seeds]))
        return super().reset(seeds)


def test_validation_seeds_are_fixed_distinct_and_in_their_own_range() -> None:
    seeds = validation_seeds(7, 500)
    assert seeds.shape == (500,) and len(set(seeds.tolist())) == 500
    assert seeds.min() >= VALIDATION_SEED_LOW and seeds.min() >= TRAIN_SEED_HIGH
    np.testing.assert_array_equal(seeds, validation_seeds(7, 500))
    assert not set(seeds.tolist()) & set(validation_seeds(8, 500).tolist())
    # a prefix: more validation episodes add seeds, they do not change the first ones
    np.testing.assert_array_equal(validation_seeds(7, 20), seeds[:20])


@pytest.mark.parametrize("name", names("learner"))
def test_selection_seeds_are_disjoint_from_training_and_evaluation(name: str) -> None:
    env = SeedRecordingEnv()
    behaviour = line_behaviour(learner=name, selection=SelectionConfig(candidates=3,
                                                                       episodes=7, race=0))
    learner = make_learner(behaviour, env)
    train(learner)
    # validation and confirmation run their episodes one after another, like training, on
    # seeds of their own (races: test_a_race_...)
    seen = [seed for _, seeds in env.seen for seed in seeds]
    training = [seed for seed in seen if TRAIN_SEED_LOW <= seed < TRAIN_SEED_HIGH]
    flat = [seed for seed in seen if seed >= TRAIN_SEED_HIGH]
    confirmation = [seed for seed in seen if seed < TRAIN_SEED_LOW]
    validation = [flat[i : i + 7] for i in range(0, len(flat), 7)]
    assert validation and training and confirmation
    assert all(seeds == validation_seeds(3, 7).tolist() for seeds in validation)
    # the confirmation, then the baselines on the same episodes (paired comparisons)
    assert confirmation[:50] == confirmation_seeds(3, 50).tolist()
    assert set(confirmation) == set(confirmation[:50])
    assert all(CONFIRMATION_SEED_LOW <= seed < TRAIN_SEED_LOW for seed in confirmation)
    evaluation = set(evaluation_seeds(0, 1000).tolist()) | set(range(1000))
    assert max(evaluation) < CONFIRMATION_SEED_LOW
    assert not set(validation[0]) & (set(training) | evaluation | set(confirmation))
    assert not set(confirmation) & (set(training) | evaluation)
    assert learner.usage.selection_episodes == 7 * len(validation)
    assert learner.usage.confirmation_episodes == 50


@pytest.mark.parametrize("name", names("learner"))
def test_the_returned_controller_is_the_best_validated_candidate(name: str) -> None:
    learner = make_learner(line_behaviour(learner=name), LineEnv())
    history = train(learner)
    selection = learner.selection
    values = [c["validation"]["value"] for c in selection.validated]
    assert selection.finalized and len(values) >= 1
    generation, individual, consequents, _, candidate = learner.selected()
    assert candidate is selection.best and candidate is not None
    assert candidate.validation is not None
    assert candidate.validation.value == max(values)
    assert history[-1].validated == max(values)
    assert sum(m.selection_episodes for m in history) == learner.usage.selection_episodes
    assert sum(m.episodes for m in history) == learner.usage.training_episodes
    assert 0 <= individual < learner.config.population and generation <= learner.generation
    assert consequents.shape == (3,)


def racing_line(learner: str, **learning: Any) -> Behaviour:
    return line_behaviour(learner=learner, generations=8, **learning, selection=SelectionConfig(
        candidates=6, episodes=4, race=36, confirmation=0))


# fuzzy_q's greedy controller settles on the line at once: one candidate, nothing to race
# (test_a_lone_candidate_does_not_race)
@pytest.mark.parametrize("name", ["pitt", "hybrid"])
def test_a_race_takes_the_best_third_on_to_three_times_the_episodes(name: str) -> None:
    env = SeedRecordingEnv()
    learner = make_learner(racing_line(name), env)
    train(learner)
    selection = learner.selection
    assert selection.racing and selection.finalized
    entrants = [c for c in selection.hall.values() if c.validation is not None]
    rounds = selection.rounds
    assert [r["episodes"] for r in rounds] == [12, 36]
    # each round keeps the best third (at least two) of the one before, ranked on the
    # episodes all of them met
    sizes = [len(entrants)] + [len(r["candidates"]) for r in rounds]
    assert sizes[0] >= 3
    for before, after in itertools.pairwise(sizes):
        assert after == max(2, -(-before // RACE_FACTOR))
    first = sorted(entrants, key=lambda c: -c.mean_of(4))
    went_on = [c for c in entrants if len(c.episode_fitness) >= 12]
    assert len(went_on) == sizes[1]
    assert min(c.mean_of(4) for c in went_on) >= first[sizes[1]].mean_of(4)
    finalists = [c for c in entrants if len(c.episode_fitness) == 36]
    best = selection.best
    assert best is not None and best.validation is not None
    assert any(best is c for c in finalists)
    assert best.validation.n == 36 and best.mean_of(36) == max(c.mean_of(36)
                                                               for c in finalists)
    assert learner.selected()[4] is best
    # every episode a race runs is a validation episode, in seed order, and counted
    seeds = validation_seeds(3, 36).tolist()
    validating = [seed for _, run in env.seen for seed in run if seed >= VALIDATION_SEED_LOW]
    assert len(validating) == learner.usage.selection_episodes == sum(
        len(c.episode_fitness) for c in entrants)
    assert set(validating) == set(seeds)
    spent_racing = sum(len(c.episode_fitness) - 4 for c in entrants)
    assert 0 < spent_racing <= race_cost(sizes[0], 4, 36)


def test_a_lone_candidate_does_not_race() -> None:
    learner = make_learner(racing_line("fuzzy_q"), LineEnv())
    train(learner)
    selection = learner.selection
    assert len(selection.hall) == 1 and selection.rounds == []
    assert learner.usage.selection_episodes == 4


def test_race_cost_is_what_the_rounds_spend_at_most() -> None:
    assert race_cost(30, 20, 180) == 10 * 40 + 4 * 120
    assert race_cost(2, 20, 60) == 2 * 40
    assert race_cost(1, 20, 180) == race_cost(30, 20, 20) == 0


@pytest.mark.parametrize("name", ["pitt", "hybrid"])
def test_a_raced_run_resumes_bit_for_bit(name: str) -> None:
    whole = make_learner(racing_line(name), LineEnv())
    train(whole)
    part = make_learner(racing_line(name), LineEnv())
    train(part, [StopAfter(3)])
    state = json.loads(json.dumps(part.state_dict()))  # through a checkpoint file's JSON
    resumed = make_learner(racing_line(name), LineEnv())
    resumed.load_state_dict(state)
    train(resumed)
    assert resumed.selection.rounds and resumed.selection.rounds == whole.selection.rounds
    assert resumed.selection_record() == whole.selection_record()
    assert resumed.selected()[2].tolist() == whole.selected()[2].tolist()
    assert resumed.usage == whole.usage
    after = json.loads(json.dumps(resumed.state_dict()))
    expected = json.loads(json.dumps(whole.state_dict()))
    after.pop("elapsed"), expected.pop("elapsed")
    assert after == expected


def test_a_run_of_a_version_without_races_resumes_without_one() -> None:
    part = make_learner(racing_line("pitt"), LineEnv())
    train(part, [StopAfter(3)])
    state = json.loads(json.dumps(part.state_dict()))
    for key in ("racing", "race"):
        del state["selection"][key]
    for candidate in state["selection"]["hall"]:
        candidate.pop("episodes", None)
    resumed = make_learner(racing_line("pitt"), LineEnv())
    resumed.load_state_dict(state)
    train(resumed)
    assert not resumed.selection.racing and resumed.selection.rounds == []
    assert resumed.selection_record()["race"] == {"episodes": 0, "rounds": []}


def test_the_hall_of_fame_ranks_by_mean_training_fitness_and_keeps_the_best() -> None:
    selection = ModelSelection(SelectionConfig(candidates=2, episodes=3), 0, Usage())
    a, b, c = np.array([0, 0]), np.array([1, 1]), np.array([2, 2])
    selection.offer(np.stack([a, b, c]), np.array([1.0, 3.0, 2.0]), 0)
    assert [x.consequents.tolist() for x in selection.ranked()] == [[1, 1], [2, 2]]
    selection.offer(np.stack([b, a]), np.array([0.0, 5.0]), 1)  # b's mean falls to 1.5
    assert [(x.consequents.tolist(), x.fitness) for x in selection.ranked()] == [
        ([0, 0], 5.0), ([2, 2], 2.0)]
    recency = ModelSelection(SelectionConfig(candidates=2), 0, Usage(), rank_by="recency")
    for generation, genes in enumerate((a, b, c)):
        recency.offer(genes[None, :], np.array([9.0 - generation]), generation)
    assert [x.consequents.tolist() for x in recency.ranked()] == [[2, 2], [1, 1]]


def test_no_selection_returns_the_last_generation_s_best_and_runs_no_validation() -> None:
    env = SeedRecordingEnv()
    learner = make_learner(line_behaviour(selection=SelectionConfig(candidates=0)), env)
    train(learner)
    assert all(size == 1 for size, _ in env.seen)
    _, individual, consequents, fitness, candidate = learner.selected()
    assert candidate is None and fitness == learner.fitness.max()
    assert consequents.tolist() == learner.population[individual].tolist()


@pytest.mark.parametrize("name", names("learner"))
def test_an_episode_budget_counts_selection_and_is_never_exceeded(name: str) -> None:
    stop = StopConfig(episodes=80)
    behaviour = line_behaviour(learner=name, generations=50, stop=stop,
                               selection=SelectionConfig(candidates=2, episodes=5,
                                                         confirmation=0))
    learner = make_learner(behaviour, LineEnv())
    history = train(learner)
    usage = learner.usage
    assert learner.stop_reason == "episodes" and learner.finished
    assert usage.episodes <= 80 and usage.selection_episodes > 0
    assert usage.episodes == sum(m.episodes + m.selection_episodes + m.confirmation_episodes
                                 for m in history)
    assert learner.generation < 49  # without the budget it would have gone on


def test_a_step_budget_and_a_time_budget_stop_the_run() -> None:
    steps = make_learner(line_behaviour(generations=50, stop=StopConfig(steps=300)),
                         LineEnv())
    train(steps)
    assert steps.stop_reason == "steps" and steps.generation < 49
    seconds = make_learner(line_behaviour(generations=50, stop=StopConfig(seconds=1e-9)),
                           LineEnv())
    assert len(train(seconds)) == 1 and seconds.stop_reason == "seconds"


def test_a_target_stops_the_run_once_a_validated_controller_reaches_it() -> None:
    learner = make_learner(line_behaviour(generations=40, stop=StopConfig(target=0.5)),
                           LineEnv())
    history = train(learner)
    best = learner.selection.best
    assert learner.stop_reason == "target"
    assert best is not None and best.validation is not None
    assert best.validation.value >= 0.5 and history[-1].validated == best.validation.value
    assert len(history) < 40


class StopAfter(Callback):
    def __init__(self, generation: int) -> None:
        self.generation = generation

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        return metrics.generation < self.generation


def ballchase(**learning: object) -> Behaviour:
    return resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                             {"population": 6, **learning})


def metrics_rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8") as handle:
        return [{k: v for k, v in row.items() if k != "wall_time"}
                for row in csv.DictReader(handle)]


@pytest.mark.parametrize("learner", names("learner"))
@pytest.mark.parametrize("stop", [{"stop.episodes": 300}, {"stop.steps": 5000},
                                  {"stop.target": 1.9}])
@pytest.mark.slow
def test_resume_is_bit_identical_with_selection_budgets_and_stopping(
        tmp_path: Path, learner: str, stop: dict[str, object]) -> None:
    behaviour = ballchase(learner=learner, seed=5, generations=12, **stop,
                          **{"selection.candidates": 3, "selection.episodes": 8,
                             "selection.race": 24,
                             "selection.confirmation": 8})
    whole = create_run(behaviour, tmp_path / "a")
    whole_summary = whole.train()
    part = create_run(behaviour, tmp_path / "b")
    assert part.train([StopAfter(1)]).status == "stopped"
    resumed = open_run(part.path).train()
    assert resumed.status == whole_summary.status in ENDED
    assert resumed.generations == whole_summary.generations
    assert metrics_rows(part.path / METRICS_FILE) == metrics_rows(whole.path / METRICS_FILE)
    assert (part.path / BEST_FILE).read_text().split("\n", 1)[1] == (
        whole.path / BEST_FILE).read_text().split("\n", 1)[1]
    last = whole.checkpoint_generations()[-1]
    a, b = part.checkpoint(last), whole.checkpoint(last)
    for state in (a, b):
        state.pop("elapsed"), state["metrics"].pop("wall_time")
    assert a == b
    info = json.loads((whole.path / "run.json").read_text())
    assert info["selection"] == json.loads((part.path / "run.json").read_text())["selection"]
    assert resumed.usage == whole_summary.usage
    assert resumed.usage is not None and resumed.usage.selection_episodes > 0
    # the candidates raced, unless a target ended the run (then none is validated after)
    assert info["selection"]["race"]["episodes"] == 24
    assert bool(info["selection"]["race"]["rounds"]) == (
        info["selection"]["stop_reason"] != "target")


@pytest.mark.parametrize("learner", names("learner"))
@pytest.mark.slow
def test_reusing_known_validation_episodes_changes_nothing(
        learner: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A candidate that commands alike every rule that fired where an earlier one acted in a
    validation episode gets that episode's outcome without running it: the run is the same
    as one that runs every episode, with fewer episodes run."""
    from flctool.learners import selection as selection_module

    ran: list[int] = []

    def counted(*args: Any, **kwargs: Any) -> Any:
        ran.append(args[2])
        return run_trial(*args, **kwargs)

    monkeypatch.setattr(selection_module, "run_trial", counted)
    behaviour = ballchase(learner=learner, seed=2, generations=8)
    runs = []
    for replayable in (False, True):
        ran.clear()
        learned = make_learner(behaviour)
        assert learned.env.replayable  # the simulator is
        learned.env.replayable = replayable
        history = [{k: v for k, v in m.row().items() if k != "wall_time"}
                   for m in train(learned)]
        runs.append((history, learned.selection_record(), learned.selected()[2].tolist(),
                     len(ran)))
    (history, record, best, every), (history_, record_, best_, fewer) = runs
    assert (history_, record_, best_) == (history, record, best)
    assert every == record["usage"]["selection_episodes"] > fewer


@pytest.mark.parametrize("race", [0, 180])
def test_run_json_records_every_validated_candidate_and_the_usage(tmp_path: Path,
                                                                  race: int) -> None:
    run = create_run(ballchase(generations=4, **{"selection.race": race}), tmp_path / "run")
    summary = run.train()
    selection = json.loads((run.path / "run.json").read_text())["selection"]
    assert selection["candidates"] == 10 and selection["episodes"] == 20
    rounds = selection["race"]["rounds"]
    assert selection["race"]["episodes"] == race and [r["episodes"] for r in rounds] == (
        [60, 180] if race else [])
    for candidate in selection["validated"]:
        interval = candidate["validation"]
        assert interval["n"] in (20, 60, 180)
        assert interval["low"] <= interval["value"] <= interval["high"]
    usage = selection["usage"]
    assert summary.usage is not None
    assert usage == summary.usage.to_dict() == summary.to_dict()["usage"]
    assert usage["training_episodes"] == 4 * 6
    first = [c for c in selection["validated"] if c["validation"]["n"] == 20]
    # every round runs its candidates on the episodes they have not met yet
    raced = sum(len(r["candidates"]) * (r["episodes"] - before)
                for r, before in zip(rounds, [20, 60], strict=False))
    assert usage["selection_episodes"] == 20 * len(first) + raced
    assert len(selection["validated"]) == len(first) + sum(len(r["candidates"])
                                                           for r in rounds)
    assert summary.best is not None and summary.best.validation is not None
    assert summary.best.validation.to_dict() == selection["best"]["validation"]
    assert summary.best.validation.n == (180 if race else 20)


def test_a_damaged_selection_record_is_refused() -> None:
    learner = make_learner(line_behaviour(), LineEnv())
    train(learner)
    state = learner.state_dict()
    state["selection"]["hall"][0]["consequents"] = [0, 9, 0]
    fresh = make_learner(line_behaviour(), LineEnv())
    with pytest.raises(LearnError, match="not one of this behaviour"):
        fresh.load_state_dict(state)
    state["selection"] = {"hall": "?"}
    with pytest.raises(LearnError, match="selection record is damaged"):
        fresh.load_state_dict(state)
