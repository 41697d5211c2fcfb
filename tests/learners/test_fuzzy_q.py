"""Fuzzy Q-learning (eq. 4-9): hand-computed updates, traces, terminal steps, exploration."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flctool.behaviour.learning import FuzzyQConfig
from flctool.errors import LearnError
from flctool.learners import make_learner, train
from flctool.learners.extension import HELD_ATTEMPTS
from flctool.learners.fuzzy_q import (
    LOCKED_GENERATIONS,
    LOCKED_RATIO,
    BoltzmannChooser,
    EpsilonGreedyChooser,
    FuzzyQ,
    FuzzyQLearner,
    HeldChooser,
    UniformStream,
    boltzmann_greediness,
    greedy_consequents,
    held_text,
    locked_text,
    unrewarded_text,
)
from tests.learners.line_env import LineEnv, cut_and_resumed, line_behaviour

Q0 = np.array([[0.0, 0.5],
               [0.2, -0.1]])


def test_value_is_eq_5_and_greedy_value_takes_each_rules_best() -> None:
    fq = FuzzyQ(Q0, alpha=0.5, gamma=0.9, lambda_=0.0)
    assert fq.value([0, 1], [0.25, 0.75], [1, 0]) == pytest.approx(0.25 * 0.5 + 0.75 * 0.2)
    assert fq.greedy_value([0, 1], [0.4, 0.6]) == pytest.approx(0.4 * 0.5 + 0.6 * 0.2)


def test_one_step_update_without_traces_is_eq_7() -> None:
    fq = FuzzyQ(Q0, alpha=0.5, gamma=0.9, lambda_=0.0)
    # Q(S,a) = 0.275; target = 1 + 0.9 * max q_1 = 1.18; dQ = 0.905
    delta = fq.learn([0, 1], [0.25, 0.75], [1, 0], 1.0, [1], [1.0], terminal=False)
    assert delta == pytest.approx(0.905)
    expected = Q0.copy()
    expected[0, 1] += 0.5 * 0.905 * 0.25
    expected[1, 0] += 0.5 * 0.905 * 0.75
    np.testing.assert_allclose(fq.table(), expected, rtol=0, atol=1e-15)
    assert fq.table()[0, 1] == pytest.approx(0.613125)
    assert fq.table()[1, 0] == pytest.approx(0.539375)
    # with lambda = 0 nothing of step t reaches step t + 1
    fq.learn([1], [1.0], [1], 0.0, [], [], terminal=True)
    assert fq.table()[0, 1] == pytest.approx(0.613125)


def test_two_steps_with_replacing_traces() -> None:
    fq = FuzzyQ(Q0, alpha=0.5, gamma=0.9, lambda_=0.5)
    fq.learn([0, 1], [0.25, 0.75], [1, 0], 1.0, [1], [1.0], terminal=False)
    np.testing.assert_allclose(fq.traces(), [[0.0, 0.25], [0.75, 0.0]])
    # step 2: Q = q_1^1 = -0.1, terminal, r = 0 -> dQ = 0.1; traces decay by lambda gamma
    # = 0.45 except the chosen (rule 1, command 1), which is replaced by phi = 1
    delta = fq.learn([1], [1.0], [1], 0.0, [], [], terminal=True)
    assert delta == pytest.approx(0.1)
    np.testing.assert_allclose(fq.traces(), [[0.0, 0.1125], [0.3375, 1.0]])
    np.testing.assert_allclose(fq.table(), [[0.0, 0.61875], [0.55625, -0.05]], atol=1e-15)


def test_a_replacing_trace_is_set_not_accumulated() -> None:
    fq = FuzzyQ(np.zeros((1, 2)), alpha=0.1, gamma=1.0, lambda_=1.0)
    fq.learn([0], [1.0], [0], 0.0, [0], [1.0], terminal=False)
    fq.learn([0], [1.0], [0], 0.0, [0], [1.0], terminal=False)
    assert fq.traces()[0, 0] == 1.0


def test_a_terminal_step_does_not_bootstrap() -> None:
    q = np.array([[5.0, 7.0]])
    fq = FuzzyQ(q, alpha=1.0, gamma=1.0, lambda_=0.0)
    assert fq.learn([0], [1.0], [0], -1.0, [0], [1.0], terminal=True) == pytest.approx(-6.0)
    fq = FuzzyQ(q, alpha=1.0, gamma=1.0, lambda_=0.0)
    # the same step cut by the time limit does bootstrap: -1 + 7 - 5
    assert fq.learn([0], [1.0], [0], -1.0, [0], [1.0], terminal=False) == pytest.approx(1.0)


def test_state_round_trips() -> None:
    fq = FuzzyQ(Q0, alpha=0.5, gamma=0.9, lambda_=0.5)
    fq.learn([0, 1], [0.25, 0.75], [1, 0], 1.0, [1], [1.0], terminal=False)
    other = FuzzyQ(np.zeros((2, 2)), alpha=0.5, gamma=0.9, lambda_=0.5)
    other.load_state_dict(fq.state_dict())
    assert other.q == fq.q and other.trace == fq.trace


def test_boltzmann_choice_frequencies() -> None:
    row = np.array([0.2, 0.0, -0.1])
    fq = FuzzyQ(row[None, :], alpha=0.1, gamma=0.9, lambda_=0.0)
    chooser = BoltzmannChooser(fq, 0.2, UniformStream(np.random.default_rng(0)))
    draws = 30_000
    counts = np.bincount([chooser.choose([0])[0] for _ in range(draws)], minlength=3)
    expected = np.exp(row / 0.2) / np.exp(row / 0.2).sum() * draws
    assert float(((counts - expected) ** 2 / expected).sum()) < 13.8  # chi2(2) 0.999


def test_epsilon_greedy_explores_at_rate_epsilon_and_breaks_ties_evenly() -> None:
    fq = FuzzyQ(np.array([[0.0, 1.0, 0.0], [0.5, 0.5, 0.0]]), 0.1, 0.9, 0.0)
    greedy = EpsilonGreedyChooser(fq, 0.0, UniformStream(np.random.default_rng(1)))
    assert {greedy.choose([0])[0] for _ in range(50)} == {1}
    ties = np.bincount([greedy.choose([1])[0] for _ in range(4000)], minlength=3)
    assert ties[2] == 0 and 1800 < ties[0] < 2200
    explorer = EpsilonGreedyChooser(fq, 0.3, UniformStream(np.random.default_rng(2)))
    picks = np.array([explorer.choose([0])[0] for _ in range(20_000)])
    assert (picks != 1).mean() == pytest.approx(0.3 * 2 / 3, abs=0.015)


class _Counting:
    """A chooser whose every draw is a new number: shows when a rule draws."""

    def __init__(self) -> None:
        self.draws = 0

    def choose(self, rules: list[int]) -> list[int]:
        self.draws += len(rules)
        return list(range(self.draws - len(rules), self.draws))


def test_a_held_command_is_kept_for_hold_firings_of_its_rule() -> None:
    held = HeldChooser(_Counting(), 3, UniformStream(np.random.default_rng(0)))
    # rule 0 fires every step, rule 1 on some: each counts its own firings
    picks = [held.choose(rules) for rules in ([0, 1], [0], [0, 1], [0], [0, 1], [1], [0])]
    assert [p[0] for p in picks[:5]] + [picks[6][0]] == [0, 0, 0, 2, 2, 2]
    assert [picks[0][1], picks[2][1], picks[4][1], picks[5][0]] == [1, 1, 1, 3]


def test_zeta_holds_are_n_or_longer_with_probability_one_in_n() -> None:
    held = HeldChooser(_Counting(), None, UniformStream(np.random.default_rng(3)))
    commands = np.array([held.choose([0])[0] for _ in range(200_000)])
    lengths = np.bincount(commands)[:-1]  # the last hold may be cut short
    for n in (1, 2, 5, 20):
        assert (lengths >= n).mean() == pytest.approx(1 / n, rel=0.05)


def test_auto_holds_are_the_default_and_the_paper_protocol_draws_every_step() -> None:
    assert FuzzyQConfig().hold == "auto"
    assert FuzzyQConfig(protocol="paper").hold == 1
    assert FuzzyQConfig.model_validate({"protocol": "paper", "exploration": {"hold": 7}}).hold == 7


def test_greedy_consequents_take_the_strongest_command() -> None:
    assert list(greedy_consequents(np.array([[0.0, 1.0], [2.0, 2.0]]))) == [1, 0]


def test_exploration_decays_to_its_floor() -> None:
    behaviour = line_behaviour(learner="fuzzy_q")
    config = behaviour.learning.exploration.model_copy(update={"decay": 0.5, "minimum": 0.05})
    learner = FuzzyQLearner(behaviour.model_copy(update={"learning": behaviour.learning.model_copy(
        update={"exploration": config})}), LineEnv())
    assert learner.exploration(0) == pytest.approx(0.15)
    assert learner.exploration(1) == pytest.approx(0.075)
    assert learner.exploration(5) == pytest.approx(0.05)


@pytest.mark.parametrize("policy", ["boltzmann", "epsilon_greedy"])
@pytest.mark.parametrize("hold", [1, 5, "zeta"])
def test_fuzzy_q_learns_to_go_up(policy: str, hold: int | str) -> None:
    behaviour = line_behaviour(learner="fuzzy_q", generations=15, population=10)
    explore = behaviour.learning.exploration.model_copy(update={"policy": policy,
                                                                "epsilon": 0.5, "hold": hold})
    behaviour = behaviour.model_copy(update={"learning": behaviour.learning.model_copy(
        update={"exploration": explore})})
    learner = make_learner(behaviour, LineEnv())
    history = train(learner)
    assert len(history) == 15 and history[0].episodes == 10
    assert learner.population.shape == (1, 3)
    # "up" wins in the rules the episodes visit most: mid and high
    assert list(learner.population[0, 1:]) == [2, 2]
    assert history[-1].mean > history[0].mean


def test_greediness_counts_the_rules_whose_strengths_moved() -> None:
    table = np.array([[0.0, -10.0, -10.0],   # moved: strongest 0, gap 10
                      [0.0, 0.0, 0.0],       # never updated (initial 0): left out
                      [-1.0, -3.0, -2.0]])   # moved: gap 2
    share, gap = boltzmann_greediness(table, 1.0, 0.0)  # type: ignore[misc]
    expected = (1 / (1 + 2 * np.exp(-10.0)) + 1 / (1 + np.exp(-2.0) + np.exp(-1.0))) / 2
    assert share == pytest.approx(expected) and gap == pytest.approx(6.0)
    assert boltzmann_greediness(np.zeros((2, 3)), 1.0, 0.0) is None


def _line_run(temperature: float) -> FuzzyQLearner:
    behaviour = line_behaviour(learner="fuzzy_q", generations=15, population=10)
    q = behaviour.learning.q.model_copy(update={"temperature": temperature})
    behaviour = behaviour.model_copy(update={"learning": behaviour.learning.model_copy(
        update={"q": q})})
    learner = make_learner(behaviour, LineEnv())
    assert isinstance(learner, FuzzyQLearner)
    train(learner)
    return learner


def test_a_run_whose_exploration_locked_in_says_so_and_one_exploring_does_not() -> None:
    locked = _line_run(0.001).exploration_record()
    assert locked["locked"] and locked["policy"] == "boltzmann" and locked["level"] == 0.001
    assert locked["greedy_since"] <= 14 - LOCKED_GENERATIONS
    assert locked["strength_gap"] >= LOCKED_RATIO * 0.001 and locked["greedy_share"] > 0.99
    assert f"since generation {locked['greedy_since']}" in locked_text(locked)
    assert "raise learning.q.temperature towards" in locked_text(locked)
    exploring = _line_run(10.0).exploration_record()
    assert not exploring["locked"] and exploring["strength_gap"] < LOCKED_RATIO * 10.0


def test_greedy_since_resumes_and_a_damaged_one_is_refused() -> None:
    learner = _line_run(0.001)
    state = learner.state_dict()
    assert state["greedy_since"] == learner.greedy_since
    again = _line_run(10.0)
    again.load_state_dict(state)
    assert again.greedy_since == learner.greedy_since
    for key in ("greedy_since", "varied_at"):
        for damaged in ("x", True, 99, -2):
            with pytest.raises(LearnError, match=key):
                again.load_state_dict({**state, key: damaged})
    old = {key: value for key, value in state.items()
           if key not in ("greedy_since", "varied_at")}
    again.load_state_dict(old)  # a checkpoint from before: counted from the resumed generation
    assert again.greedy_since == again.varied_at == state["generation"]


def test_episodes_that_all_score_the_same_count_as_no_signal_only_below_the_greedy_one() -> None:
    # one step from x in [2, 8] never reaches 9 or 1: every episode is truncated with return 0,
    # exploring or greedy, so the run had no signal, and nothing better was to be had either
    # (as CartPole balanced for all 500 steps); acrobot-fuzzy-q's seed 611, whose greedy
    # controllers validate far above its -500 episodes, is the slow CLI test's
    learner = make_learner(line_behaviour(learner="fuzzy_q", generations=8, population=5),
                           LineEnv(max_steps=1))
    assert isinstance(learner, FuzzyQLearner)
    train(learner)
    record = learner.exploration_record()
    assert record["varied_at"] == -1 and record["fitness"] == 0.0
    assert learner.selection.best is not None
    assert learner.selection.best.validation_value() == 0.0 and not record["unrewarded"]
    assert unrewarded_text(record).startswith(
        "every training episode in the whole run scored the same (fitness 0)")
    rewarded = _line_run(10.0).exploration_record()
    assert not rewarded["unrewarded"] and rewarded["varied_at"] == 14


def test_auto_holds_the_draws_once_a_run_has_had_no_reward_signal() -> None:
    learner = make_learner(line_behaviour(learner="fuzzy_q", generations=8, population=5),
                           LineEnv(max_steps=1))
    assert isinstance(learner, FuzzyQLearner)
    train(learner)  # every episode scores 0, as the greedy controllers validate: a signal
    learner.advance()
    assert learner.held_from is None and learner.hold_now() == 1
    learner.fitness = np.array([-1.0])  # the same score, now below the validated 0: none
    assert learner.unrewarded()
    learner.advance()
    assert learner.held_from == learner.generation + 1 and learner.hold_now() is None
    assert f"so from generation {learner.held_from} each rule held" in held_text(
        learner.exploration_record()) and held_text({"held_from": None}) is None
    state = learner.state_dict()
    again = make_learner(line_behaviour(learner="fuzzy_q", generations=8, population=5),
                         LineEnv(max_steps=1))
    again.load_state_dict(state)
    assert isinstance(again, FuzzyQLearner) and again.held_from == learner.held_from
    for damaged in ("x", True, 0, learner.generation + 2):
        with pytest.raises(LearnError, match="held_from"):
            again.load_state_dict({**state, "held_from": damaged})


def test_a_run_that_holds_its_draws_starts_afresh_in_each_fresh_attempt() -> None:
    behaviour = line_behaviour(learner="fuzzy_q", generations=3, population=5,
                               extend={"patience": 1})
    learner = make_learner(behaviour, LineEnv(max_steps=1))
    assert isinstance(learner, FuzzyQLearner)
    train(learner)
    extension = learner.extension
    assert not extension.attempts and extension.starts == [0]  # a step at a time: one attempt
    most = extension.most
    learner.held_from = learner.generation + 1  # as auto does once a run has had no signal
    extension.open_attempts(learner.held_from, HELD_ATTEMPTS)
    assert extension.attempts and extension.most == max(most, learner.held_from
                                                        + HELD_ATTEMPTS * 3)
    learner.fuzzy_q.q[0] = 7.0
    learner.advance()  # no attempt begins next: the strengths go on
    assert learner.fuzzy_q.q[0] == 7.0
    extension.starts.append(learner.generation + 1)  # the attempt ended; a fresh one fits
    learner.advance()
    assert np.all(learner.fuzzy_q.table() == learner.config.q.initial)
    # a resumed run has the same room and attempts
    again = make_learner(behaviour, LineEnv(max_steps=1))
    again.load_state_dict(json.loads(json.dumps(learner.state_dict())))
    assert again.extension.attempts and again.extension.most == extension.most
    assert again.extension.starts == extension.starts


@pytest.mark.parametrize("hold", [5, "zeta"])
def test_a_run_that_holds_its_draws_resumes_bit_for_bit(hold: int | str) -> None:
    behaviour = line_behaviour(learner="fuzzy_q", generations=8, population=5,
                               exploration={"hold": hold})
    whole = make_learner(behaviour, LineEnv())
    history = train(whole)
    resumed, rest = cut_and_resumed(behaviour, after=3)
    assert [m.mean for m in rest] == [m.mean for m in history[4:]]
    assert np.array_equal(resumed.fuzzy_q.table(), whole.fuzzy_q.table())  # type: ignore[attr-defined]


def test_a_run_that_began_to_hold_goes_on_holding_after_a_resume() -> None:
    behaviour = line_behaviour(learner="fuzzy_q", generations=4, population=5)
    learner = make_learner(behaviour, LineEnv())
    assert isinstance(learner, FuzzyQLearner)
    train(learner)
    learner.held_from = learner.generation + 1  # as auto does once a run has had no signal
    again = make_learner(behaviour, LineEnv())
    assert isinstance(again, FuzzyQLearner)
    again.load_state_dict(json.loads(json.dumps(learner.state_dict())))
    assert again.hold_now() is None
    for run in (learner, again):
        run.advance()
    assert np.array_equal(learner.evaluate(4).fitness, again.evaluate(4).fitness)
    assert np.array_equal(learner.fuzzy_q.table(), again.fuzzy_q.table())



@pytest.mark.slow
def test_a_run_in_its_held_attempts_resumes_bit_for_bit() -> None:
    """acrobot-fuzzy-q seed 611 has had no reward signal by generation 4, holds from 5 and
    begins a fresh attempt at 35 (docs/learning.md, "Fresh attempts once a run holds"): cut
    after generation 20, in its first held attempt, and resumed from its checkpoint as a file
    holds it, it ends as the whole run does."""
    from flctool import load_behaviour
    from flctool.learners import Callback, GenerationMetrics
    from flctool.runs import resolve_behaviour
    from tests.conftest import ROOT

    behaviour = resolve_behaviour(
        load_behaviour(ROOT / "benchmarks" / "tasks" / "acrobot-fuzzy-q.yaml"), {"seed": 611})

    class StopAfter(Callback):
        def on_generation(self, metrics: GenerationMetrics) -> bool:
            return metrics.generation < 20

    whole = make_learner(behaviour)
    history = train(whole)
    first = make_learner(behaviour)
    train(first, [StopAfter()])
    resumed = make_learner(behaviour)
    resumed.load_state_dict(json.loads(json.dumps(first.state_dict())))
    rest = train(resumed)
    assert [m.mean for m in rest] == [m.mean for m in history[21:]]
    record = whole.selection_record()
    assert len(record["extension"]["attempts"]) >= 3  # the resumed part began one afresh
    for key in ("extension", "exploration", "usage", "best", "confirmation"):
        assert resumed.selection_record()[key] == record[key], key
