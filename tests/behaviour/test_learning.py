"""The ``learning:`` section: one model per learner, chosen by ``learner``; another learner's
key is a located error naming who reads it; sections an earlier version recorded still load."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from flctool.behaviour import behaviour_to_data, parse_behaviour
from flctool.behaviour.learning import (
    DEFAULT_LEARNER,
    FuzzyQConfig,
    GeneticConfig,
    HybridConfig,
    LearningConfig,
    PittConfig,
    learner_keys,
)
from flctool.behaviour.sections import foreign_key_message, keep_keys_read_by, readers_of
from flctool.errors import SpecError
from flctool.plugins import names, plugins
from flctool.runs import resolve_behaviour
from tests.behaviour.test_load import GOOD

SCHEMA = Path(__file__).parents[2] / "schemas" / "behaviour.schema.json"


def _with_learning(section: str) -> str:
    return GOOD + "learning:\n" + "".join(f"  {line}\n" for line in section.splitlines())


def _problems(text: str) -> list[tuple[int | None, str, str]]:
    with pytest.raises(SpecError) as info:
        parse_behaviour(text, "bad.yaml")
    return [(p.line, ".".join(map(str, p.path)), p.message) for p in info.value.problems]


# Where the file ends and learning: begins (GOOD has 34 lines).
LEARNING_LINE = GOOD.count("\n") + 1


@pytest.mark.parametrize(("learner", "model"), [
    ("pitt", PittConfig), ("fuzzy_q", FuzzyQConfig), ("hybrid", HybridConfig)])
def test_learner_chooses_its_model(learner: str, model: type[LearningConfig]) -> None:
    behaviour = parse_behaviour(_with_learning(f"learner: {learner}\nseed: 3"))
    assert type(behaviour.learning) is model
    assert behaviour.learning.seed == 3


def test_a_section_without_learner_is_the_default_learners() -> None:
    assert DEFAULT_LEARNER == "hybrid"
    behaviour = parse_behaviour(_with_learning("seed: 2\ncrossover: 0.3\nq: {alpha: 0.2}"))
    assert isinstance(behaviour.learning, HybridConfig)
    assert behaviour.learning.crossover == 0.3 and behaviour.learning.q.alpha == 0.2
    assert isinstance(parse_behaviour(GOOD).learning, HybridConfig)  # no section at all


def test_each_learner_reads_its_own_keys() -> None:
    common = {"learner", "seed", "population", "generations", "trials", "selection", "stop",
              "sets", "protocol", "extend"}
    assert set(learner_keys(LearningConfig)) == common
    genetic = {"crossover", "mutation", "elites", "common_starts", "restart_after"}
    assert set(learner_keys(GeneticConfig)) == common | genetic
    assert set(learner_keys(PittConfig)) == common | genetic | {"pitt_crossover"}
    assert set(learner_keys(HybridConfig)) == common | genetic | {"q", "greedy_individual"}
    assert set(learner_keys(FuzzyQConfig)) == common | {"q", "exploration"}


@pytest.mark.parametrize(("section", "path", "message"), [
    ("learner: fuzzy_q\npitt_crossover: one_point", "learning.pitt_crossover",
     "'pitt_crossover' is read by the pitt learner only; remove it or set learner: pitt"),
    ("pitt_crossover: one_point", "learning.pitt_crossover",
     "'pitt_crossover' is read by the pitt learner only; remove it or set learner: pitt"),
    ("learner: pitt\nexploration: {policy: epsilon_greedy}", "learning.exploration",
     "'exploration' is read by the fuzzy_q learner only; remove it or set learner: fuzzy_q"),
    ("learner: pitt\nq: {alpha: 0.2}", "learning.q",
     "'q' is read by the fuzzy_q and hybrid learners, not by pitt; remove it or set learner "
     "to one of them"),
    ("learner: fuzzy_q\nelites: 2", "learning.elites",
     "'elites' is read by the pitt and hybrid learners, not by fuzzy_q; remove it or set "
     "learner to one of them"),
])
def test_another_learners_key_is_a_located_error_naming_its_reader(
        section: str, path: str, message: str) -> None:
    line = LEARNING_LINE + section.count("\n") + 1
    assert _problems(_with_learning(section)) == [(line, path, message)]


def test_a_key_no_learner_reads_is_unknown_with_this_learners_keys() -> None:
    problems = _problems(_with_learning("learner: fuzzy_q\nexplortion: {}"))
    assert problems == [(LEARNING_LINE + 2, "learning.explortion",
                         "unknown key 'explortion'. Did you mean 'exploration'?")]
    with pytest.raises(SpecError) as info:
        parse_behaviour(_with_learning("learner: fuzzy_q\nexplortion: {}"))
    hint = info.value.problems[0].hint
    assert "exploration" in hint and "crossover" not in hint


def test_an_unknown_learner_lists_the_learners() -> None:
    with pytest.raises(SpecError) as info:
        parse_behaviour(_with_learning("learner: hybird"), "bad.yaml")
    problem = info.value.problems[0]
    assert (problem.line, ".".join(map(str, problem.path))) == (LEARNING_LINE + 1,
                                                                "learning.learner")
    assert problem.message == "unknown learner 'hybird'. Did you mean 'hybrid'?"
    assert problem.hint == f"use one of: {', '.join(names('learner'))}"


def test_a_bad_value_is_located_inside_its_learners_model() -> None:
    assert _problems(_with_learning("learner: pitt\npitt_crossover: two_point")) == [
        (LEARNING_LINE + 2, "learning.pitt_crossover",
         "input should be 'uniform' or 'one_point', got 'two_point'")]
    assert _problems(_with_learning("learner: pitt\npopulation: 4\nelites: 4"))[0][1] == (
        "learning.elites")


# A hybrid run's learning section as versions with one flat model wrote it into behaviour.yaml
# and best.yaml: every key of every learner.
EARLIER_RECORD = """\
learner: {learner}
seed: 4
population: 6
generations: 3
crossover: 0.3
mutation: 0.1
pitt_crossover: one_point
elites: 1
trials: 2
common_starts: false
q:
  alpha: 0.2
  gamma: 0.9
  lambda: 0.7
  temperature: 0.15
  initial: 0.0
exploration:
  policy: boltzmann
  epsilon: 0.1
  decay: 1.0
  minimum: 0.0
selection:
  candidates: 10
  episodes: 20
stop: {{}}
"""


@pytest.mark.parametrize("learner", ["pitt", "fuzzy_q", "hybrid"])
def test_a_section_an_earlier_version_recorded_loads_with_its_learners_keys(
        learner: str) -> None:
    learning = parse_behaviour(_with_learning(EARLIER_RECORD.format(learner=learner))).learning
    assert learning.learner == learner
    assert (learning.seed, learning.population, learning.trials) == (4, 6, 2)
    written = behaviour_to_data(parse_behaviour(GOOD).model_copy(update={"learning": learning}))
    # every key but those left unset (None), which are not written: 'sets' when no sets are
    # learned, 'restart_after' when the learner's default applies, 'extend' when the record
    # gives its generations
    assert set(written["learning"]) == set(learner_keys(type(learning))) - {
        "sets", "restart_after", "extend"}
    if isinstance(learning, PittConfig):
        assert learning.pitt_crossover == "one_point" and learning.crossover == 0.3
    if isinstance(learning, (FuzzyQConfig, HybridConfig)):
        assert learning.q.alpha == 0.2


def test_a_section_someone_wrote_keeps_its_stray_keys_to_report() -> None:
    # Short of every key of the earlier flat model, a section is not a record: checked.
    partial = EARLIER_RECORD.format(learner="fuzzy_q").replace("common_starts: false\n", "")
    paths = [path for _, path, _ in _problems(_with_learning(partial))]
    assert paths == ["learning.crossover", "learning.mutation", "learning.pitt_crossover",
                     "learning.elites"]


def test_keep_keys_read_by_drops_what_the_learner_does_not_read() -> None:
    section = {"learner": "pitt", "seed": 1, "crossover": 0.3, "pitt_crossover": "one_point"}
    assert keep_keys_read_by(section, "fuzzy_q") == {"learner": "pitt", "seed": 1}
    assert keep_keys_read_by(section, "hybrid") == {"learner": "pitt", "seed": 1,
                                                     "crossover": 0.3}
    assert keep_keys_read_by(section, "nobody") == section  # validation names the learner


def test_readers_and_messages_come_from_the_plugins() -> None:
    assert readers_of("seed") == names("learner")
    assert readers_of("q") == ("fuzzy_q", "hybrid")
    assert readers_of("no_such_key") == ()
    assert foreign_key_message("no_such_key", "pitt") is None  # a typo, reported as unknown
    assert foreign_key_message("q", "hybrid") is None
    assert all(issubclass(p.config_model(), LearningConfig) for p in plugins("learner"))


def test_switching_learner_by_override_drops_the_old_learners_keys() -> None:
    pitt = parse_behaviour(_with_learning(
        "learner: pitt\nseed: 4\nmutation: 0.3\npitt_crossover: one_point"))
    fuzzy_q = resolve_behaviour(pitt, {"learner": "fuzzy_q"})
    assert isinstance(fuzzy_q.learning, FuzzyQConfig) and fuzzy_q.learning.seed == 4
    hybrid = resolve_behaviour(pitt, {"learning.learner": "hybrid"})
    assert isinstance(hybrid.learning, HybridConfig) and hybrid.learning.mutation == 0.3
    back = resolve_behaviour(fuzzy_q, {"learner": "pitt"})
    assert isinstance(back.learning, PittConfig) and back.learning.pitt_crossover == "uniform"


def test_a_switched_learner_takes_its_own_default_for_a_key_left_at_the_old_one_s() -> None:
    hybrid = parse_behaviour(_with_learning("learner: hybrid\nseed: 4"))
    credit = resolve_behaviour(hybrid, {"learner": "credit"})
    assert credit.learning.population == 100  # credit's default, not the hybrid's 10
    chosen = resolve_behaviour(hybrid, {"learner": "credit", "population": 10})
    assert chosen.learning.population == 10
    given = parse_behaviour(_with_learning("learner: hybrid\npopulation: 24"))
    assert resolve_behaviour(given, {"learner": "credit"}).learning.population == 24
    back = resolve_behaviour(credit, {"learner": "pitt"})
    assert back.learning.population == 10 and back.learning.seed == 4


def test_an_override_of_another_learners_key_is_an_error() -> None:
    pitt = parse_behaviour(_with_learning("learner: pitt"))
    with pytest.raises(SpecError, match="'pitt_crossover' is read by the pitt learner only"):
        resolve_behaviour(pitt, {"learner": "fuzzy_q", "pitt_crossover": "one_point"})
    with pytest.raises(SpecError, match="'exploration' is read by the fuzzy_q learner only"):
        resolve_behaviour(pitt, {"exploration.decay": 0.9})


def test_the_schema_lets_only_the_default_learner_leave_out_learner() -> None:
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    for model in (PittConfig, FuzzyQConfig):
        assert "learner" in schema["$defs"][model.__name__]["required"]
    assert "learner" not in schema["$defs"]["HybridConfig"].get("required", [])
    base = behaviour_to_data(parse_behaviour(GOOD))
    for learning, valid in [({"seed": 1, "q": {"alpha": 0.2}}, True),
                            ({"learner": "pitt", "pitt_crossover": "one_point"}, True),
                            ({"learner": "fuzzy_q", "exploration": {"decay": 0.9}}, True),
                            ({"exploration": {"decay": 0.9}}, False),
                            ({"learner": "fuzzy_q", "crossover": 0.2}, False)]:
        errors = list(jsonschema.Draft202012Validator(schema).iter_errors(
            {**base, "learning": learning}))
        assert (not errors) == valid, (learning, errors)
