"""Evaluation summaries from Python: the statistics ``flctool evaluate`` shows, chunking that
changes no outcome, and seeds given as lists or drawn."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour, with_rules
from flctool.envs import make_env
from flctool.evaluation import (
    episode_seeds,
    evaluate_behaviour,
    evaluate_in_chunks,
    parse_seeds,
)
from flctool.rollout import evaluate, evaluation_seeds
from flctool.runs import resolve_behaviour

from .conftest import BEHAVIOURS

HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"


def test_seeds_lists_and_ranges() -> None:
    assert parse_seeds("1,2,5-9") == [1, 2, 5, 6, 7, 8, 9]
    assert parse_seeds(" 3 - 4 ,0") == [3, 4, 0]
    for bad, message in (("1,x", "'x' is not a seed"), ("9-5", "is empty"),
                         ("1,1-2", "named twice"), ("-1", "is not a seed")):
        with pytest.raises(ValueError, match=message):
            parse_seeds(bad)


def test_episode_seeds_are_listed_or_drawn() -> None:
    assert episode_seeds([4, 2]).tolist() == [4, 2]
    assert np.array_equal(episode_seeds(seed=3, episodes=5), evaluation_seeds(3, 5))
    assert np.array_equal(episode_seeds(), evaluation_seeds(0, 1000))
    with pytest.raises(ValueError, match="either seeds, or seed and episodes"):
        episode_seeds([1], seed=2)


def test_chunks_do_not_change_the_outcomes() -> None:
    behaviour = load_behaviour(HANDMADE)
    controller = compile_behaviour(behaviour)
    seeds = evaluation_seeds(3, 23)
    env = make_env(behaviour, 23)
    whole = evaluate(controller, env, seeds)
    reports: list[tuple[int, int]] = []
    chunked = evaluate_in_chunks(controller, env, seeds, chunk=5,
                                 on_chunk=lambda done, won: reports.append((done, won)))
    for name in ("seeds", "returns", "lengths", "success", "fitness"):
        assert np.array_equal(getattr(whole, name), getattr(chunked, name)), name
    assert [done for done, _ in reports] == [5, 10, 15, 20, 23]
    assert reports[-1][1] == int(whole.success.sum())


def test_the_summary_is_the_outcomes_statistics() -> None:
    behaviour = load_behaviour(HANDMADE)
    evaluation = evaluate_behaviour(behaviour, seed=2, episodes=40)
    result = evaluation.result
    assert np.array_equal(result.seeds, evaluation_seeds(2, 40))
    rate = result.success.mean()
    rows = {label: (value, interval, n) for label, value, interval, n in evaluation.rows()}
    assert rows["success rate (Wilson)"][0] == f"{100 * rate:.1f} %"
    assert rows["mean fitness"][0] == f"{result.fitness.mean():.3f}"
    assert rows["mean return"][2] == "40"
    low, high = result.mean_fitness.low, result.mean_fitness.high
    assert low <= result.fitness.mean() <= high
    assert rows["mean fitness"][1] == f"[{low:.3f}, {high:.3f}]"
    data = evaluation.to_dict("handmade.yaml")
    assert data["behaviour"] == behaviour.name and data["file"] == "handmade.yaml"
    assert data["seed"] == 2 and data["episodes"] == 40
    assert data["seeds"] == result.seeds.tolist()
    assert math.isclose(data["success_rate"]["value"], rate)


def test_listed_seeds_have_no_drawing_seed_and_one_episode_has_no_interval() -> None:
    evaluation = evaluate_behaviour(load_behaviour(HANDMADE), [7])
    assert evaluation.seed is None and evaluation.result.seeds.tolist() == [7]
    rows = {label: interval for label, _, interval, _ in evaluation.rows()}
    assert rows["mean fitness"] == "-"


def test_no_success_statistics_where_the_environment_defines_none() -> None:
    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    deployable = resolve_behaviour(with_rules(cartpole, np.zeros(cartpole.rule_count,
                                                                 dtype=np.intp)),
                                   {"environment.success": "never"})
    evaluation = evaluate_behaviour(deployable, episodes=3)
    assert [label for label, *_ in evaluation.rows()] == ["mean fitness", "mean return"]
    assert "success_rate" not in evaluation.summary()
    assert "steps_to_success" not in evaluation.to_dict()


def test_whoever_opens_an_environment_closes_it(monkeypatch: pytest.MonkeyPatch) -> None:
    behaviour = load_behaviour(HANDMADE)
    closed: list[str] = []
    with make_env(behaviour, 8) as env:
        monkeypatch.setattr(env, "close", lambda: closed.append("given"))
        evaluate_behaviour(behaviour, seed=1, episodes=8, env=env)
        assert closed == []  # evaluated in, not opened by, evaluate_behaviour
    assert closed == ["given"]  # the block that opened it closed it

    def opened_here(*args: object) -> object:
        built = make_env(*args)  # type: ignore[arg-type]
        monkeypatch.setattr(built, "close", lambda: closed.append("built"))
        return built

    monkeypatch.setattr("flctool.envs.make_env", opened_here)
    evaluate_behaviour(behaviour, seed=1, episodes=8)
    assert closed == ["given", "built"]
