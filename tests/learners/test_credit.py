"""The credit learner: rule-wise credit pooled over episodes, tables drawn by Thompson sampling."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flctool import load_behaviour, parse_behaviour
from flctool.compile import compile_behaviour
from flctool.envs import make_env
from flctool.errors import LearnError, SpecError
from flctool.learners import make_learner, train
from flctool.learners.budget import describe_budget
from flctool.learners.credit import CreditLearner, RuleCredit
from flctool.learners.trial import SparseRules, run_trial
from tests.conftest import BEHAVIOURS
from tests.learners.line_env import LINE_BEHAVIOUR, LineEnv, cut_and_resumed, line_behaviour


def test_an_episode_is_credited_to_the_rules_that_fired_by_their_share() -> None:
    credit = RuleCredit(3, 2, prior=1.0)
    tables = np.array([[0, 1, 1], [1, 1, 0]])
    # episode 0 was shaped by rule 0 for 3 parts in 4 and rule 1 for 1; episode 1 by rule 2
    activation = np.array([[3.0, 1.0, 0.0], [0.0, 0.0, 2.0]])
    credit.learn(tables, activation, np.array([1.0, 0.0]))  # advantages +0.5, -0.5
    assert credit.weight.tolist() == [[np.sqrt(0.75), 0.0], [0.0, 0.5], [1.0, 0.0]]
    assert credit.total.tolist() == [[0.5 * np.sqrt(0.75), 0.0], [0.0, 0.25], [-0.5, 0.0]]
    assert credit.spread == 0.5
    # rule 0: command 0 gained; rule 2: command 0 lost, so command 1 (no evidence) leads
    assert credit.greedy().tolist() == [0, 1, 1]


def test_episodes_all_alike_keep_the_last_spread() -> None:
    credit = RuleCredit(1, 2, prior=1.0)
    credit.learn(np.array([[0], [1]]), np.ones((2, 1)), np.array([0.0, 2.0]))
    credit.learn(np.array([[0], [1]]), np.ones((2, 1)), np.array([1.0, 1.0]))
    assert credit.spread == 1.0


def test_draws_without_evidence_are_uniform_and_with_it_follow_the_credit() -> None:
    credit = RuleCredit(2, 4, prior=1.0)
    rng = np.random.default_rng(0)
    first = credit.draw(rng, 4000)
    counts = np.stack([np.bincount(first[:, m], minlength=4) for m in range(2)])
    assert np.all(np.abs(counts / 4000 - 0.25) < 0.03)
    # every pair of commands: command 2 of rule 0 wins every time, rule 1's commands tie
    tables = np.array([[a, b] for a in range(4) for b in range(4)])
    for _ in range(5):
        credit.learn(tables, np.ones((16, 2)), (tables[:, 0] == 2).astype(float))
    later = credit.draw(rng, 1000)
    assert np.mean(later[:, 0] == 2) > 0.95
    assert 0.1 < np.mean(later[:, 1] == 2) < 0.6  # rule 1 still explores


def test_a_trial_adds_each_rules_share_of_every_state_it_acted_on() -> None:
    behaviour = line_behaviour()
    rules = SparseRules(compile_behaviour(behaviour))
    env = LineEnv()
    shaped = [0.0, 0.0, 0.0]
    trial = run_trial(env, rules, 7, [2, 2, 2], credit=shaped)
    # the phi of a state sum to 1: one per state acted on (every step's)
    assert sum(shaped) == pytest.approx(trial.length)
    again = [0.0, 0.0, 0.0]
    assert run_trial(env, rules, 7, [2, 2, 2], chooser=_Up(), credit=again) == trial
    assert again == shaped  # the general loop and the fast one credit alike


class _Up:
    def choose(self, rules: list[int]) -> list[int]:
        return [2] * len(rules)


def test_the_credit_learner_learns_the_line() -> None:
    behaviour = line_behaviour(learner="credit", generations=8, population=20)
    learner = make_learner(behaviour, LineEnv())
    history = train(learner)
    assert len(history) == 8 and history[0].episodes == 20
    assert learner.population.shape == (1, 3)
    assert list(learner.population[0, 1:]) == [2, 2]  # up where the episodes go
    assert history[-1].mean > history[0].mean


def test_a_given_first_generation_is_the_first_tables_tried() -> None:
    behaviour = line_behaviour(learner="credit", population=4, generations=1)
    learner = make_learner(behaviour, LineEnv())
    assert isinstance(learner, CreditLearner)
    learner.start_from(np.full((4, 3), 2, dtype=np.intp))
    train(learner)
    # every table said up everywhere: only command 2 has evidence
    assert (learner.credit.weight[:, :2] == 0).all() and (learner.credit.weight[:, 2] > 0).any()
    with pytest.raises(LearnError, match="keeps no rule strengths"):
        make_learner(behaviour, LineEnv()).start_from(None, np.zeros((3, 3)))


def test_a_resumed_run_continues_bit_for_bit() -> None:
    behaviour = line_behaviour(learner="credit", generations=6, population=8)
    whole = make_learner(behaviour, LineEnv())
    train(whole)
    second, rest = cut_and_resumed(behaviour, after=2)
    assert [m.generation for m in rest] == [3, 4, 5]
    a, b = second.state_dict(), whole.state_dict()
    a.pop("elapsed"), b.pop("elapsed")
    assert a == b and a["credit"] == json.loads(json.dumps(b["credit"]))


@pytest.mark.parametrize("damage", [
    lambda s: s.pop("credit"),
    lambda s: s["credit"].update(total=[[0.0]]),
    lambda s: s["credit"]["weight"][0].__setitem__(0, -1.0),
    lambda s: s["credit"].update(spread=0.0),
    lambda s: s["credit"].update(spread="wide"),
])
def test_a_damaged_credit_is_refused(damage: object) -> None:
    behaviour = line_behaviour(learner="credit", generations=2, population=4)
    learner = make_learner(behaviour, LineEnv())
    train(learner)
    state = json.loads(json.dumps(learner.state_dict()))
    damage(state)  # type: ignore[operator]
    with pytest.raises(LearnError, match="rule credit"):
        make_learner(behaviour, LineEnv()).load_state_dict(state)


def test_learning_the_sets_with_credit_is_a_located_error() -> None:
    text = LINE_BEHAVIOUR.replace("learning:\n", "learning:\n  learner: credit\n"
                                  "  sets: {inputs: [x]}\n")
    with pytest.raises(SpecError) as error:
        parse_behaviour(text, "line.yaml")
    assert "learns rule consequents only" in str(error.value)
    assert "line.yaml" in str(error.value)


def test_a_sized_run_has_all_its_most_generations() -> None:
    behaviour = line_behaviour(learner="credit", extend={"patience": 1, "most": 5},
                               generations=2, population=4)
    learner = make_learner(behaviour, LineEnv())
    history = train(learner)
    assert len(history) == 5  # patience 1 would have ended a genetic run sooner or later
    assert "5 generations (from extend.most; its credit only grows" in describe_budget(behaviour)


def test_shoot_learns_with_credit_and_states_its_budget() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "shoot.yaml")
    assert behaviour.learning.learner == "credit"
    assert "150 generations (from the problem's size" in describe_budget(behaviour)
    # a vote behaviour's trials credit rules too
    park = load_behaviour(BEHAVIOURS.parent / "benchmarks" / "tasks" / "park.yaml")
    rules = SparseRules(compile_behaviour(park))
    env = make_env(park, 1)
    shaped = [0.0] * rules.n_rules
    trial = run_trial(env, rules, 3, [0] * rules.n_rules, credit=shaped)
    assert sum(shaped) == pytest.approx(trial.length)
