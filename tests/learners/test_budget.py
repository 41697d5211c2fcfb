"""The budget a run states before it starts: every number, and where it came from."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from flctool import load_behaviour
from flctool.behaviour import behaviour_from_data, behaviour_to_data, behaviour_to_yaml
from flctool.behaviour.learning import ExtendConfig, SelectionConfig
from flctool.learners import make_learner, train
from flctool.learners.budget import plan_budget
from flctool.learners.extension import most_generations
from flctool.learners.selection import race_cost
from flctool.plugins import names
from flctool.runs import resolve_behaviour
from tests.conftest import BEHAVIOURS
from tests.learners.line_env import LineEnv, line_behaviour


def test_the_paper_s_protocol_is_one_key_away() -> None:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"protocol": "paper"})
    assert behaviour.learning.extend is None
    plan = plan_budget(behaviour)
    selection = behaviour.learning.selection
    assert (plan.rules, plan.commands, plan.training) == (15, 5, 300)
    validated = 30 + selection.candidates + 1  # every leader, the last candidates, the elite
    race = behaviour.learning.race_episodes
    assert race == 60 and selection.race is None  # unset: the hybrid's reading
    assert plan.selection == validated * selection.episodes + race_cost(
        validated, selection.episodes, race)
    # the screening, the strongest on the rest, and at most two settling rounds (50, 100)
    assert (plan.confirmation, plan.baselines) == (50, (5 + 3) * 10 + 40 + 2 * (50 + 100))
    assert plan.most == 300 + plan.selection + 50 + 420 and plan.limit is None
    lines = plan.lines()
    assert lines[0].startswith(f"budget: at most {plan.most:,} episodes: 300 training")
    assert "30 generations x 10 individuals x 1 trial (the paper's protocol" in lines[1]
    assert "raced on to 60 episodes" in lines[2] and "selection.race 60 (default)" in lines[2]


def test_a_file_without_a_budget_is_extended_up_to_a_bound_from_its_size() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    assert behaviour.learning.extend == ExtendConfig()
    plan = plan_budget(behaviour)
    # 15 rules x log2 5 = 34.8 units: 30 x ceil(34.8 / 30) = 60, and at least 2 x 30
    assert most_generations(15, 5, 30) == 60 and plan.extension == (60, 10)
    assert behaviour.learning.trials == 2  # sized: two trials under the GAs
    assert plan.training == 60 * 10 * 2
    validated = 60 + behaviour.learning.selection.candidates + 1
    assert plan.selection == validated * 20 + race_cost(validated, 20, 60)
    assert all(s.source == "default" for s in plan.settings.values())
    assert "30 to 60 generations (on past 30 until 10 pass without a better selected " \
        "controller" in plan.lines()[1]
    assert "x 10 individuals x 2 trials (the file gives none of them)" in plan.lines()[1]
    assert most_generations(54, 5, 30) == 150 and most_generations(40, 5, 50) == 120
    # a budget given is exact: on the command line, in the file, or extend's own bound
    given = resolve_behaviour(behaviour, {"generations": 12})
    assert given.learning.extend is None and plan_budget(given).training == 120
    paper = resolve_behaviour(behaviour, {"protocol": "paper"})
    assert paper.learning.trials == 1 and plan_budget(paper).training == 300
    bounded = resolve_behaviour(behaviour, {"extend.most": 45})
    assert plan_budget(bounded).extension == (45, 10) and bounded.learning.trials == 2
    assert "45 from extend.most)" in plan_budget(bounded).lines()[1]
    short = resolve_behaviour(behaviour, {"extend.most": 4})  # a run has its generations
    assert "30 to 30 generations" in plan_budget(short).lines()[1]
    assert "30 since extend.most 4 is below generations)" in plan_budget(short).lines()[1]
    assert "60 from the problem's size unless extend.most is given" in plan.lines()[1]


def test_a_fuzzy_q_budget_bounds_the_room_a_held_run_gets() -> None:
    # exploration.hold: auto may open fresh attempts part-way (FuzzyQLearner.advance): the
    # bound counts them, as many as fit from the last generation one may open at
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"learner": "fuzzy_q"})
    plan = plan_budget(behaviour)
    assert plan.extension == (60, 10) and plan.held_most == 60 - 30 + 3 * 30
    assert plan.training == 120 * 10 * 1
    assert ("60 from the problem's size unless extend.most is given; if its exploration "
            "begins to hold (no reward signal), fresh attempts of 30 from there, up to "
            "120)") in " ".join(plan.lines())
    # a hold given, the paper's protocol, or extend.most given: no room beyond most
    for overrides in ({"exploration.hold": "zeta"}, {"protocol": "paper"},
                      {"extend.most": 70}):
        assert plan_budget(resolve_behaviour(behaviour, overrides)).held_most is None


def test_sized_trials_are_the_learner_s_and_a_file_s_trials_stay() -> None:
    behaviour = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    # fuzzy_q's sized budget keeps one trial: its generation is population x trials episodes
    assert resolve_behaviour(behaviour, {"learner": "fuzzy_q"}).learning.trials == 1
    assert resolve_behaviour(behaviour, {"learner": "pitt"}).learning.trials == 2
    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")  # fuzzy_q, no budget
    assert cartpole.learning.extend is not None and cartpole.learning.trials == 1
    assert resolve_behaviour(cartpole, {"learner": "hybrid"}).learning.trials == 2
    # trials the file or an override gives stay, whatever the budget
    written = resolve_behaviour(behaviour, {"trials": 3})
    assert written.learning.trials == 3
    assert resolve_behaviour(written, {"generations": 40}).learning.trials == 3
    # one trial with the extension: given trials are not the sized default
    assert resolve_behaviour(behaviour, {"trials": 1}).learning.extend is not None
    # a budget with trials given keeps them
    kept = resolve_behaviour(behaviour, {"generations": 40, "trials": 2})
    assert kept.learning.trials == 2 and kept.learning.extend is None


def test_a_written_out_copy_gives_up_its_sized_budget_as_the_file_does(tmp_path: Path) -> None:
    # a run directory's behaviour.yaml (or any copy flctool writes) writes extend and trials
    behaviour = load_behaviour(BEHAVIOURS / "ballchase.yaml")
    copy = tmp_path / "copy.yaml"
    copy.write_text(behaviour_to_yaml(behaviour), encoding="utf-8")
    written = load_behaviour(copy)
    assert "trials: 2" in copy.read_text() and written.learning.trials == 2
    for source in (behaviour, written):
        exact = resolve_behaviour(source, {"generations": 12})
        assert (exact.learning.extend, exact.learning.trials) == (None, 1)


def test_each_setting_says_where_it_came_from() -> None:
    path = BEHAVIOURS / "mountaincar.yaml"  # a file that gives its generations
    behaviour = resolve_behaviour(load_behaviour(path), {"trials": 2, "stop.episodes": 900})
    plan = plan_budget(behaviour, baselines=1)
    line = next(n for n, text in enumerate(path.read_text().splitlines(), 1)
                if text.strip().startswith("generations:"))
    settings = plan.settings
    assert settings["generations"].source == f"the file's line {line}"
    assert settings["trials"].source == "overrides (trials)"  # the CLI says "--set trials"
    assert settings["population"].source == "default"
    assert settings["stop.episodes"].value == 900 and plan.most == 900
    assert plan.training == behaviour.learning.generations * 10 * 2
    # the given table is a baseline too; at most two settling rounds after
    assert plan.baselines == (3 + 3 + 1) * 10 + 40 + 300
    text = "\n".join(plan.lines())
    assert "trials from overrides (trials)" in text and "limit: stop.episodes 900" in text
    no_selection = resolve_behaviour(load_behaviour(path), {"selection.candidates": 0})
    assert plan_budget(no_selection).selection == 0
    assert "selection: none" in plan_budget(no_selection).lines()[2]


def test_fuzzy_q_does_not_race_unless_the_file_says() -> None:
    behaviour = resolve_behaviour(load_behaviour(BEHAVIOURS / "ballchase.yaml"),
                                  {"learner": "fuzzy_q"})
    plan = plan_budget(behaviour)
    assert behaviour.learning.race_episodes == 0
    assert plan.settings["selection.race"].value == 0
    assert plan.settings["selection.race"].source == "default"
    assert "no race" in plan.lines()[2]
    raced = resolve_behaviour(behaviour, {"selection.race": 60})
    assert raced.learning.race_episodes == 60
    assert make_learner(raced).selection.racing and not make_learner(behaviour).selection.racing


@pytest.mark.parametrize("name", names("learner"))
@pytest.mark.parametrize("race", [0, 36])
def test_a_run_spends_no_more_than_its_budget_says(name: str, race: int) -> None:
    behaviour = line_behaviour(learner=name, generations=8, selection=SelectionConfig(
        candidates=6, episodes=4, race=race))
    learner = make_learner(behaviour, LineEnv())
    train(learner)
    plan = plan_budget(behaviour)
    usage = learner.usage
    assert usage.training_episodes == plan.training
    assert usage.selection_episodes <= plan.selection
    assert usage.episodes <= plan.most


_LEARNING = st.fixed_dictionaries({}, optional={
    "learner": st.sampled_from(["hybrid", "pitt", "fuzzy_q"]),
    "generations": st.integers(1, 40),
    "trials": st.integers(1, 3),
    "extend": st.sampled_from([{}, {"patience": 5}]),
    "protocol": st.sampled_from(["auto", "paper"]),
})
_OVERRIDES = st.fixed_dictionaries({}, optional={
    "generations": st.integers(1, 40),
    "protocol": st.just("paper"),
    "trials": st.integers(1, 3),
    "learner": st.sampled_from(["hybrid", "pitt", "fuzzy_q"]),
})


@settings(max_examples=150, deadline=None)
@given(learning=_LEARNING, overrides=_OVERRIDES)
def test_a_budget_reads_the_same_from_a_file_and_its_written_out_copy(
        learning: dict[str, object], overrides: dict[str, object]) -> None:
    assume(not (learning.get("protocol") == "paper" and "extend" in learning))
    assume(not (overrides.get("protocol") == "paper" and "extend" in learning))
    base = behaviour_to_data(load_behaviour(BEHAVIOURS / "ballchase.yaml"), defaults=False)
    behaviour = behaviour_from_data({**base, "learning": {"seed": 1, **learning}})
    copy = behaviour_from_data(behaviour_to_data(behaviour))  # every key written out
    budget = [(b.learning.learner, b.learning.trials, b.learning.generations, b.learning.extend)
              for b in (resolve_behaviour(behaviour, overrides),
                        resolve_behaviour(copy, overrides))]
    assert budget[0] == budget[1]
    learner, trials, _, extend = budget[0]
    if "trials" in overrides:  # trials given on the command line are exact
        assert trials == overrides["trials"]
    elif "protocol" in overrides or "generations" in overrides:
        if "trials" not in learning and "extend" not in learning:
            assert trials == 1 and extend is None  # a given budget replaces the sized one
    elif not {"generations", "extend", "trials", "protocol"} & set(learning):
        # a file that gives no budget: extended, and two trials under the GAs
        assert extend == ExtendConfig() and trials == (1 if learner == "fuzzy_q" else 2)
