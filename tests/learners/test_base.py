"""Contract tests run over every registered learner: the template loop, determinism, resume."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flctool.errors import LearnError
from flctool.learners import (
    LEARNERS,
    TRAIN_SEED_LOW,
    Callback,
    GenerationMetrics,
    Learner,
    StopAtFitness,
    make_learner,
    train,
)
from flctool.plugins import names, plugins
from flctool.registry import UnknownNameError
from tests.learners.line_env import LineEnv, cut_and_resumed, line_behaviour


class Recorder(Callback):
    def __init__(self, stop_after: int | None = None) -> None:
        self.events: list[str] = []
        self.stop_after = stop_after

    def on_start(self, learner: Learner) -> None:
        super().on_start(learner)
        self.events.append("start")

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        self.events.append(f"gen{metrics.generation}")
        return self.stop_after is None or metrics.generation < self.stop_after

    def on_end(self) -> None:
        self.events.append("end")


def test_registry_holds_exactly_the_configurable_learners() -> None:
    assert set(LEARNERS.names()) == set(names("learner"))
    with pytest.raises(UnknownNameError, match="Did you mean 'hybrid'"):
        LEARNERS.get("hybird")


@pytest.mark.parametrize("name", names("learner"))
def test_training_runs_every_generation_through_the_callbacks(name: str) -> None:
    recorder = Recorder()
    learner = make_learner(line_behaviour(learner=name), LineEnv())
    history = train(learner, [recorder])
    assert recorder.events == ["start", *(f"gen{g}" for g in range(6)), "end"]
    assert [m.generation for m in history] == list(range(6))
    assert learner.generation == 5
    assert all(m.min <= m.mean <= m.best and m.steps >= m.episodes for m in history)
    assert learner.population.shape[1] == 3
    _, consequents, fitness = learner.best()
    assert fitness == learner.fitness.max() and consequents.shape == (3,)
    assert (learner.strengths() is not None) == learner.uses_strengths


@pytest.mark.parametrize("name", names("learner"))
def test_a_callback_can_stop_training_early(name: str) -> None:
    recorder = Recorder(stop_after=2)
    history = train(make_learner(line_behaviour(learner=name), LineEnv()), [recorder])
    assert len(history) == 3 and recorder.events[-1] == "end"
    assert len(train(make_learner(line_behaviour(learner=name), LineEnv()),
                     [StopAtFitness(-10.0)])) == 1


@pytest.mark.parametrize("name", names("learner"))
@pytest.mark.slow
def test_the_same_seed_gives_the_same_run(name: str) -> None:
    runs = []
    for _ in range(2):
        learner = make_learner(line_behaviour(learner=name), LineEnv())
        history = train(learner)
        runs.append(([(m.mean, m.best, m.steps) for m in history], learner.state_dict()))
    for run in runs:
        run[1].pop("elapsed")
    assert runs[0] == runs[1]
    other = make_learner(line_behaviour(learner=name, seed=4), LineEnv())
    train(other)
    assert other.state_dict()["rng"] != runs[0][1]["rng"]


@pytest.mark.parametrize("name", names("learner"))
@pytest.mark.slow
def test_resuming_from_a_json_checkpoint_ends_where_an_uninterrupted_run_ends(
        name: str) -> None:
    behaviour = line_behaviour(learner=name, generations=7)
    whole = make_learner(behaviour, LineEnv())
    whole_history = train(whole)
    second, rest = cut_and_resumed(behaviour, after=3)
    assert [m.generation for m in rest] == [4, 5, 6]
    strip = lambda ms: [(m.mean, m.std, m.best, m.min, m.steps) for m in ms]  # noqa: E731
    assert strip(rest) == strip(whole_history[4:])
    a, b = second.state_dict(), whole.state_dict()
    a.pop("elapsed"), b.pop("elapsed")
    assert a == b


def test_training_seeds_stay_clear_of_evaluation_seeds() -> None:
    learner = make_learner(line_behaviour(learner="pitt"), LineEnv())
    seeds = learner.episode_seeds(5, 3, common=False)
    assert seeds.shape == (5, 3) and seeds.min() >= TRAIN_SEED_LOW
    assert len(np.unique(seeds)) == 15
    common = learner.episode_seeds(5, 3, common=True)
    assert (common == common[0]).all() and len(np.unique(common[0])) == 3


def test_a_checkpoint_of_another_learner_is_refused() -> None:
    pitt = make_learner(line_behaviour(learner="pitt"), LineEnv())
    hybrid = make_learner(line_behaviour(learner="hybrid"), LineEnv())
    with pytest.raises(Exception, match="learner 'pitt', not 'hybrid'"):
        hybrid.load_state_dict(pitt.state_dict())


@pytest.mark.parametrize("name", names("learner"))
def test_a_learner_reads_only_its_own_learning_section(name: str) -> None:
    learner = LEARNERS.get(name)
    other = "pitt" if name != "pitt" else "fuzzy_q"
    with pytest.raises(LearnError, match=f"the {name} learner cannot learn a behaviour whose "
                       f"learning section is the {other} learner's"):
        learner(line_behaviour(learner=other), LineEnv())
    model = next(p.config_model() for p in plugins("learner") if p.name == name)
    assert type(learner(line_behaviour(learner=name), LineEnv()).config) is model


class Crash(Recorder):
    """Raises ``error`` from on_generation at ``generation``."""

    def __init__(self, generation: int, error: BaseException) -> None:
        super().__init__()
        self.generation, self.error = generation, error

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        super().on_generation(metrics)
        if metrics.generation == self.generation:
            raise self.error
        return True


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_on_end_runs_when_training_fails_or_is_interrupted(error: BaseException) -> None:
    crash, after = Crash(1, error), Recorder()
    learner = make_learner(line_behaviour(learner="pitt"), LineEnv())
    with pytest.raises(type(error)):
        train(learner, [crash, after])
    assert crash.events == ["start", "gen0", "gen1", "end"]
    assert after.events == ["start", "gen0", "end"]  # its on_generation never ran for gen 1
    assert learner.generation == 1


def damage(state: dict[str, object], **changes: object) -> dict[str, object]:
    damaged = json.loads(json.dumps(state))
    damaged.update(changes)
    return {k: v for k, v in damaged.items() if v is not None}


@pytest.mark.parametrize(("changes", "message"), [
    ({"population": [[0, 1, 3]] * 6}, r"population holds command indices 0\.\.3, outside "
                                      r"0\.\.2"),
    ({"population": [[0, -1, 2]] * 6}, r"command indices -1\.\.2"),
    ({"population": [0, 1, 2]}, r"population has shape \(3,\)"),
    ({"population": [[0, 1]] * 6}, "controllers have 2 rules, the behaviour 3"),
    ({"population": [[0, 1], [2]]}, "its 'population' is not a table of whole numbers"),
    ({"fitness": [0.5]}, r"fitness has shape \(1,\), not \(6,\)"),
    ({"q": [[0.0] * 3] * 2}, r"'q' table has shape \(2, 3\), not \(rules, commands\) = "
                            r"\(3, 3\)"),
    ({"traces": None}, r"has no 'traces' table of shape \(rules, commands\) = \(3, 3\)"),
    ({"rng": {"ga": {}}}, "no state of the random generator.*env, explore"),
    ({"rng": {"ga": {}, "env": {}, "explore": {}}}, "random generator states cannot be "
                                                  "restored"),
    ({"generation": None}, "has no 'generation'"),
    ({"generation": "1"}, "its 'generation' is not a generation number"),
    ({"population": [[0.5, 1, 2]] * 6}, "not a table of whole numbers"),
    ({"fitness": [float("nan")] * 6}, "its 'fitness' holds NaN or infinity"),
    ({"elapsed": "soon"}, "its 'elapsed' is not a finite number"),
    ({"learner": "pitt"}, "is of learner 'pitt', not 'hybrid'"),
    ({"rng": {"ga": {"x": 2**200}, "env": {}, "explore": {}}}, r"outside \[0, 2\^128\)"),
])
def test_a_damaged_checkpoint_is_refused_and_leaves_the_learner_as_it_was(
        changes: dict[str, object], message: str) -> None:
    trained = make_learner(line_behaviour(learner="hybrid"), LineEnv())
    train(trained)
    fresh = make_learner(line_behaviour(learner="hybrid"), LineEnv())
    before = fresh.state_dict()
    with pytest.raises(LearnError, match=message):
        fresh.load_state_dict(damage(trained.state_dict(), **changes))
    assert fresh.state_dict() == before


def test_a_checkpoint_that_is_not_an_object_is_refused() -> None:
    learner = make_learner(line_behaviour(learner="pitt"), LineEnv())
    with pytest.raises(LearnError, match="the checkpoint holds a JSON list, not an object"):
        learner.load_state_dict([1, 2])  # type: ignore[arg-type]


@pytest.mark.parametrize("name", names("learner"))
def test_rules_the_file_gives_stay_fixed(name: str) -> None:
    # 'up' is best in every rule, so a learner free to change rule 1 ('mid') would
    ga = {"mutation": 0.5} if name in ("pitt", "hybrid") else {}
    behaviour = line_behaviour(learner=name, generations=8, **ga)
    given = behaviour.model_validate({**behaviour.model_dump(by_alias=True),
                                      "rules": [{"if": {"x": "mid"}, "then": "stay"}]})
    learner = make_learner(given, LineEnv())
    assert learner.fixed_rules.tolist() == [1] and learner.fixed_commands.tolist() == [1]
    seen: list[np.ndarray] = []

    class Watch(Callback):
        def on_generation(self, metrics: GenerationMetrics) -> bool:
            seen.append(learner.population.copy())
            return True

    q_before = learner.strengths()
    train(learner, [Watch()])
    assert all((population[:, 1] == 1).all() for population in seen)
    assert learner.selected()[2][1] == 1
    assert all(c["consequents"][1] == 1 for c in learner.selection.state_dict()["hall"])
    # the other rules did learn: not every controller kept its start
    assert any((population[:, [0, 2]] == 2).any() for population in seen)
    if name == "fuzzy_q":  # never explored: only the given command's strength moved
        assert q_before is not None
        moved = learner.strengths() != q_before  # type: ignore[operator]
        assert moved[1].tolist() == [False, True, False]
