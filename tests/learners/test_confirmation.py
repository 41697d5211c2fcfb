"""The figure a run reports (confirmation), stop.target in user units, and the verdict
against baselines (not_learned)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from flctool import load_behaviour
from flctool.behaviour.learning import StopConfig
from flctool.cli import app
from flctool.errors import SpecError
from flctool.learners import make_learner, train
from flctool.learners.baselines import not_learned_message
from flctool.learners.confirmation import confirmation_seeds
from flctool.rollout import CONFIRMATION_SEED_LOW, TRAIN_SEED_LOW
from flctool.runs import create_run, open_run, resolve_behaviour
from tests.conftest import BEHAVIOURS
from tests.learners.line_env import LineEnv, line_behaviour

runner = CliRunner()


def ballchase(**learning: object) -> object:
    return resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                             {"population": 6, "generations": 4, **learning})


def test_confirmation_seeds_are_fixed_distinct_and_in_their_own_range() -> None:
    seeds = confirmation_seeds(3, 400)
    assert len(set(seeds.tolist())) == 400
    assert seeds.min() >= CONFIRMATION_SEED_LOW and seeds.max() < TRAIN_SEED_LOW
    np.testing.assert_array_equal(confirmation_seeds(3, 50), seeds[:50])
    assert not set(seeds.tolist()) & set(confirmation_seeds(4, 400).tolist())


def test_the_reported_figure_is_a_confirmation_clipped_to_the_possible_fitness() -> None:
    learner = make_learner(ballchase(seed=2), None)
    train(learner)
    final = learner.confirmation.final
    assert final is not None and final.fitness.n == 50
    assert np.array_equal(final.consequents, learner.selected()[2])
    assert 0.0 <= final.fitness.low <= final.fitness.high <= 2.0
    assert 0.0 <= final.success.low <= final.success.value <= final.success.high <= 1.0
    best = learner.selection.best
    assert best is not None and best.validation is not None
    assert best.validation.low >= 0.0 and best.validation.high <= 2.0
    assert learner.usage.confirmation_episodes == 50


def test_a_target_in_user_units_is_checked_on_the_confirmation() -> None:
    learner = make_learner(ballchase(seed=0, generations=30, population=10,
                                     **{"stop.target": {"success": 0.9}}), None)
    history = train(learner)
    assert learner.stop_reason == "target" and len(history) < 30
    final = learner.confirmation.final
    assert final is not None and final.success.value >= 0.9
    # the validated figure only opened the door: it was confirmed on fresh episodes
    assert np.array_equal(final.consequents, learner.selected()[2])


@pytest.mark.parametrize(("target", "message"), [
    (2.5, "outside the fitness this environment can give"),
    ({"success": 1.5}, "less than or equal to 1"),
    ({"success": 0.9, "return": 1}, "exactly one of success, return and fitness")])
def test_a_target_that_cannot_be_reached_is_a_located_error(target: object,
                                                             message: str) -> None:
    with pytest.raises(SpecError, match=message) as error:
        make_learner(ballchase(**{"stop.target": target}), None)
    assert "stop.target" in str(error.value) or "stop" in str(error.value)


def test_a_plain_target_is_a_mean_fitness() -> None:
    target = StopConfig(target=1.5).target_in_units()
    assert target is not None and (target.unit, target.value) == ("fitness", 1.5)


@pytest.mark.slow
def test_a_learned_controller_beats_the_baselines(tmp_path: Path) -> None:
    run = create_run(ballchase(seed=0, generations=10), tmp_path / "run")
    summary = run.train()
    verdict = (summary.selection or {})["baseline"]
    assert summary.status == "finished" and verdict["learned"]
    assert verdict["difference"]["low"] > 0
    assert set(verdict["screened"]) >= {"always turn_left", "random table 1"}
    usage = summary.to_dict()["usage"]
    assert usage["baseline_episodes"] == 10 * len(verdict["screened"]) + 40
    assert usage["episodes"] == sum(v for k, v in usage.items() if k.endswith("_episodes"))


def unlearnable(tmp_path: Path) -> Path:
    """Ballchase with one set per input: one rule, so every controller is a constant command
    and none can beat the best of them."""
    data = yaml.safe_load((BEHAVIOURS / "ballchase.yaml").read_text())
    data["inputs"]["ball_size"]["sets"] = {"any": [0.0, 0.0, 1.0, 1.0]}
    data["inputs"]["pan"]["sets"] = {"any": [-90.0, -90.0, 90.0, 90.0]}
    data["learning"] = {"generations": 2, "population": 4}
    path = tmp_path / "unlearnable.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_a_run_that_cannot_learn_ends_not_learned_with_its_exit_code(tmp_path: Path) -> None:
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", str(unlearnable(tmp_path)), "--out", str(out)])
    assert result.exit_code == 3, result.output
    assert "not learned" in result.stderr and "try:" in result.stderr
    baseline = json.loads((out / "run.json").read_text())["selection"]["baseline"]["baseline"]
    assert f"'{baseline}'" in result.stderr
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "not_learned"
    assert info["selection"]["baseline"]["learned"] is False
    assert open_run(out).summary().status == "not_learned"
    # the baseline it was no better than is there to use instead: its table, deployable
    assert "baseline.yaml" in result.stderr
    written = load_behaviour(out / "baseline.yaml")
    assert written.is_deployable and written.inputs == load_behaviour(out / "best.yaml").inputs
    names = list(written.output.commands)
    learner = make_learner(open_run(out).behaviour)
    expected = dict(learner.baseline_check.baselines(learner))[baseline]
    assert [names.index(rule.then) for rule in written.rules] == expected.tolist()
    assert f"'{baseline}'" in (out / "baseline.yaml").read_text().splitlines()[0]


def verdict(baseline: str, low: float, high: float) -> dict[str, object]:
    return {"learned": False, "baseline": baseline, "baseline_fitness": 1.6,
            "difference": {"value": (low + high) / 2, "low": low, "high": high, "n": 50}}


@pytest.mark.parametrize(("baseline", "advice"), [
    ("always approach", "a controller that always commands 'approach' does better: if that is "
                        "good enough, the task as written may not need these rules"),
    ("random table 2", "a random rule table does better, so the trials did not tell "
                       "controllers apart: measure each on more episodes (--set trials=3"),
    ("handmade.yaml", "your controller 'handmade.yaml' does better: start from it (--init"),
])
def test_not_learned_advice_follows_the_baseline_that_was_as_good(baseline: str,
                                                                  advice: str) -> None:
    message = not_learned_message(verdict(baseline, -0.4, -0.1), ["approach", "dribble"])
    head, tried = message.split("\n")
    assert head == (f"the learned controller is not clearly better than the baseline "
                    f"'{baseline}' (mean fitness 1.600; difference -0.250 [-0.400, -0.100] "
                    f"over the same 50 episodes)")
    assert tried.startswith(f"  try: {advice}"), tried
    # an interval that holds zero: as good, not better
    assert " does as well" in not_learned_message(verdict(baseline, -0.1, 0.2),
                                                  ["approach", "dribble"])


@pytest.mark.parametrize(("learner", "other"), [
    ("hybrid", "try the credit learner (--learner credit"),
    ("fuzzy_q", "try the credit learner (--learner credit"),
    ("credit", "try another learner (--learner hybrid or fuzzy_q)"),
])
def test_not_learned_advice_names_another_learner_than_the_run_s(learner: str,
                                                                 other: str) -> None:
    for baseline in ("always approach", "random table 1", "handmade.yaml"):
        message = not_learned_message(verdict(baseline, -0.1, 0.2), ["approach"], learner)
        assert other in message, message


def test_a_given_baseline_named_like_a_constant_of_other_commands_is_a_given_one() -> None:
    # "always kick" is not a constant here: the behaviour has no command "kick"
    message = not_learned_message(verdict("always kick", -0.1, 0.2), ["approach"])
    assert "your controller 'always kick' does as well" in message


@pytest.mark.slow
def test_a_hand_made_baseline_is_compared_and_recorded(tmp_path: Path) -> None:
    handmade = BEHAVIOURS / "ballchase-handmade.yaml"
    out = tmp_path / "run"
    result = runner.invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), "-g", "2",
                                 "--baseline", str(handmade), "--out", str(out), "--json"])
    assert result.exit_code in (0, 3), result.output
    screened = json.loads((out / "run.json").read_text())["selection"]["baseline"]["screened"]
    assert "ballchase-handmade.yaml" in screened
    line = runner.invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), "--baseline",
                               str(unlearnable(tmp_path)), "--out", str(tmp_path / "x")])
    assert line.exit_code == 1 and "rule grid" in line.stderr


@pytest.mark.slow
def test_resume_is_bit_identical_with_confirmation_and_baselines(tmp_path: Path) -> None:
    behaviour = ballchase(seed=4, generations=6, **{"stop.target": {"success": 0.99}})
    whole = create_run(behaviour, tmp_path / "a")
    whole.train()
    part = create_run(behaviour, tmp_path / "b")
    learner = make_learner(behaviour)

    from flctool.learners import Callback, GenerationMetrics

    class StopAfter(Callback):
        def on_generation(self, metrics: GenerationMetrics) -> bool:
            return metrics.generation < 2

    part.train([StopAfter()], learner=learner)
    open_run(part.path).train()
    last = whole.checkpoint_generations()[-1]
    a, b = whole.checkpoint(last), part.checkpoint(last)
    for state in (a, b):
        state.pop("elapsed"), state["metrics"].pop("wall_time")
    assert a == b
    info = [json.loads((r.path / "run.json").read_text()) for r in (whole, part)]
    assert info[0]["selection"] == info[1]["selection"]
    assert info[0]["best"] == info[1]["best"]


def test_a_fuzzy_q_run_on_the_line_is_confirmed_too() -> None:
    learner = make_learner(line_behaviour(learner="fuzzy_q"), LineEnv())
    train(learner)
    assert learner.confirmation.final is not None
    assert learner.learned is not None


@pytest.mark.parametrize("limit", [120, 400])
def test_confirmation_and_baselines_stay_within_an_episode_budget(limit: int) -> None:
    learner = make_learner(ballchase(seed=3, generations=40, **{"stop.episodes": limit}),
                           None)
    train(learner)
    usage = learner.usage
    assert usage.episodes <= limit and learner.stop_reason == "episodes"
    assert usage.confirmation_episodes > 0 and usage.baseline_episodes > 0


@pytest.mark.slow
def test_learn_says_the_budget_and_why(tmp_path: Path) -> None:
    result = runner.invoke(app, ["learn", str(BEHAVIOURS / "ballchase.yaml"), "-g", "1",
                                 "--set", "trials=2", "--out", str(tmp_path / "run")])
    assert result.exit_code in (0, 3), result.output
    said = " ".join(result.stderr.split())
    assert "budget: at most " in said and "20 training" in said
    assert "for 15 rules to learn x 5 commands" in said
    assert ("training: 1 generation x 10 individuals x 2 trials (generations from "
            "--generations, trials from --set trials, the rest the paper's protocol)") in said
    assert "selection.race 60 (default)" in said


def test_the_confirmation_interval_allows_for_outcomes_too_rare_to_have_shown() -> None:
    from flctool.learners.confirmation import fitness_interval
    from flctool.rollout import mean_interval

    fitness = np.linspace(1.85, 1.9, 50)  # fifty successes, all alike
    every = fitness_interval(fitness, np.ones(50, dtype=bool), (0.0, 2.0))
    plain = mean_interval(fitness)
    assert every.value == plain.value and every.n == 50
    # a failure rate of up to Wilson's 7 % at fitness 0 is still possible
    assert every.low < plain.low - 0.1 and every.high >= plain.high
    assert 0.0 <= every.low <= every.value <= every.high <= 2.0
    unbounded = fitness_interval(fitness, np.ones(50, dtype=bool), (-np.inf, np.inf))
    assert (unbounded.low, unbounded.high) == (plain.low, plain.high)


def test_an_undecided_comparison_is_settled_on_fresh_episodes() -> None:
    """The hand-made shoot controller (0.37 success) against walking straight at the goal
    (about 0.2): 10 confirmation episodes cannot tell them apart, so both run on 10 more,
    then 20 more, on seeds the confirmation's draw continues with."""
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "shoot.yaml"),
                                  {"population": 4, "generations": 1,
                                   "selection.candidates": 0, "selection.confirmation": 10})
    handmade = load_behaviour(BEHAVIOURS / "shoot-handmade.yaml")
    learner = make_learner(behaviour)
    train(learner)
    names = list(handmade.output.commands)
    table = np.array([names.index(rule.then) for rule in handmade.rules], dtype=np.intp)
    check = learner.baseline_check
    before = learner.usage.baseline_episodes
    learner.confirmation.confirm(learner, table, 0, 0)
    check.on_finish(learner)
    assert check.verdict is not None
    difference = check.verdict.difference
    settled = difference.n - 10
    assert settled in (10, 30)  # one round or two
    screened = 10 * len(check.verdict.screened)
    assert learner.usage.baseline_episodes - before == screened + 2 * settled
    assert difference.low > 0 or settled == 30  # decided, or out of rounds
    # and the settling seeds are the confirmation draw's next ones: fresh, disjoint
    seeds = confirmation_seeds(behaviour.learning.seed, 40)
    assert len(set(seeds)) == 40 and set(learner.confirmation.seeds) == set(seeds[:10])


def test_a_trailing_controller_is_decided_at_once() -> None:
    learner = make_learner(ballchase(seed=0, generations=1, population=2,
                                     **{"selection.confirmation": 20}), None)
    train(learner)
    learner.confirmation.confirm(learner, np.zeros(15, dtype=np.intp), 0, 0)  # always right
    before = learner.usage.baseline_episodes
    learner.baseline_check.on_finish(learner)
    verdict = learner.baseline_check.verdict
    assert verdict is not None and verdict.difference.n == 20 and not verdict.learned
    assert learner.usage.baseline_episodes - before == 10 * len(verdict.screened) + 10
