"""Loading behaviour files: valid ones load, and each kind of mistake gets its own located
message. Every bad file here asserts the exact line and the message a person would read."""

from __future__ import annotations

from pathlib import Path

import pytest

from flctool.behaviour import behaviour_from_data, load_behaviour, parse_behaviour
from flctool.behaviour.yaml_source import SourceMap
from flctool.errors import SpecError

GOOD = """\
flctool: 1
name: chase
inputs:
  size:
    range: [0, 1]
    sets:
      small: [0, 0, 0.2, 0.6]
      large: [0.4, 0.8, 1, 1]
  pan:
    range: [-90, 90]
    unit: deg
    sets:
      right: [-90, -90, -30, 10]
      left: [-10, 30, 90, 90]
output:
  name: turn
  commands: {right: -1, ahead: 0, left: 1}
rules:
  - {if: {size: small, pan: right}, then: right}
  - {if: {size: small, pan: left}, then: left}
  - {if: {size: large, pan: right}, then: ahead}
  - {if: {size: large, pan: left}, then: ahead}
"""


def _problems(text: str) -> list[tuple[int | None, str, str]]:
    with pytest.raises(SpecError) as info:
        parse_behaviour(text, "bad.yaml")
    return [(p.line, ".".join(map(str, p.path)), p.message) for p in info.value.problems]


def test_good_file_loads() -> None:
    behaviour = parse_behaviour(GOOD, "good.yaml")
    assert behaviour.input_names == ("size", "pan")
    assert behaviour.rule_count == 4
    assert behaviour.is_deployable
    assert behaviour.inputs["pan"].unit == "deg"
    assert behaviour.learning.population == 10  # the paper's defaults where the file is silent
    assert behaviour.learning.crossover == 0.2
    assert behaviour.learning.mutation == 0.1
    assert behaviour.learning.generations == 30


def test_partial_rules_are_allowed_for_learning() -> None:
    text = GOOD.split("rules:")[0] + "rules:\n  - {if: {size: small, pan: right}, then: right}\n"
    behaviour = parse_behaviour(text)
    assert not behaviour.is_deployable
    assert len(behaviour.missing_rules()) == 3
    assert behaviour.missing_rules()[0] == ("small", "left")


# (case, text, line, path, message) -- message is matched as a substring of the full text.
BAD = [
    ("malformed YAML", GOOD.replace("  name: turn", "  name: [turn"), 17,
     "", "not valid YAML"),
    ("tab indentation", GOOD.replace("    unit: deg", "\tunit: deg"), 11,
     "", "a tab character is used for indentation"),
    ("duplicate key", GOOD.replace("      large: [0.4, 0.8, 1, 1]",
                                   "      large: [0.4, 0.8, 1, 1]\n      small: [0, 0, .1, .3]"),
     9, "inputs.size.sets.small", "duplicate key 'small' (first given on line 7)"),
    ("wrong type", GOOD.replace("range: [0, 1]", "range: [0, big]"), 5,
     "inputs.size.range.1", "'big' is not a number"),
    ("unordered quadruple", GOOD.replace("[0.4, 0.8, 1, 1]", "[0.8, 0.4, 1, 1]"), 8,
     "inputs.size.sets.large", "must satisfy pa <= pb <= pc <= pd"),
    ("set outside the range", GOOD.replace("[0.4, 0.8, 1, 1]", "[0.4, 0.8, 1, 1.5]"), 8,
     "inputs.size.sets.large", "reaches outside the input's range [0, 1]"),
    ("uncovered gap", GOOD.replace("[0, 0, 0.2, 0.6]", "[0, 0, 0.2, 0.3]"), 6,
     "inputs.size.sets", "the values between 0.3 and 0.4 belong to no set"),
    ("uncovered point", GOOD.replace("[0, 0, 0.2, 0.6]", "[0, 0, 0.2, 0.4]"), 6,
     "inputs.size.sets", "the point 0.4 belongs to no set"),
    ("unknown set in a rule", GOOD.replace("{size: small, pan: left}", "{size: small, pan: lefft}"),
     20, "rules.1.if.pan", "input 'pan' has no set 'lefft'. Did you mean 'left'?"),
    ("unknown command", GOOD.replace("then: left}", "then: leftt}"), 20,
     "rules.1.then", "unknown command 'leftt'. Did you mean 'left'?"),
    ("missing version", GOOD.replace("flctool: 1\n", ""), 1,
     "", "the format version 'flctool' is missing"),
    ("future version", GOOD.replace("flctool: 1", "flctool: 2"), 1,
     "flctool", "this file uses format version 2, but this flctool reads version 1 only"),
    ("no inputs", GOOD.split("inputs:")[0] + "inputs: {}\noutput:" + GOOD.split("output:")[1]
     .split("rules:")[0], 3, "inputs", "'inputs' is empty"),
    ("no commands", GOOD.replace("commands: {right: -1, ahead: 0, left: 1}", "commands: {}")
     .split("rules:")[0], 17, "output.commands", "'commands' is empty"),
    ("duplicate rule", GOOD + "  - {if: {size: small, pan: left}, then: right}\n", 23,
     "rules.4", "duplicate rule: the same antecedent as rules[1]"),
    ("unknown key", GOOD.replace("    unit: deg", "    units: deg"), 11,
     "inputs.pan.units", "unknown key 'units'. Did you mean 'unit'?"),
    # a rule that leaves out an input stands for all its sets (flctool/behaviour/rules.py); here
    # that contradicts rules[2]
    ("don't-care conflict", GOOD.replace("{if: {size: large, pan: left}, then: ahead}",
                                         "{if: {size: large}, then: left}"), 22,
     "rules.3", "both cover IF size IS large AND pan IS right, with different commands"),
    ("unknown input in a rule", GOOD.replace("{size: large, pan: left}",
                                             "{size: large, pann: left, pan: left}"), 22,
     "rules.3.if.pann", "rule names an unknown input 'pann'. Did you mean 'pan'?"),
    ("object-building tag", GOOD.replace("name: chase", "name: !!python/object:os.system chase"),
     2, "name", "the YAML tag '!!python/object:os.system' is not allowed"),
    ("empty range", GOOD.replace("range: [0, 1]", "range: [1, 1]"), 5,
     "inputs.size.range", "range [1, 1] must be [low, high] with low < high"),
    ("infinite number", GOOD.replace("range: [0, 1]", "range: [0, .inf]"), 5,
     "inputs.size.range.1", "input should be a finite number"),
    ("bad name", GOOD.replace("      left: [-10", "      far-left: [-10"), 14,
     "inputs.pan.sets.far-left", "'far-left' is not a valid name"),
    ("missing field", GOOD.replace("  name: turn\n", ""), 15,
     "output.name", "required field 'name' is missing"),
    ("bad learning value", GOOD + "learning: {crossover: 1.5}\n", 23,
     "learning.crossover", "input should be less than or equal to 1"),
    ("unknown learner", GOOD + "learning: {learner: hybird}\n", 23,
     "learning.learner", "unknown learner 'hybird'. Did you mean 'hybrid'?"),
    ("unknown adapter", GOOD + "environment: {adapter: ballchase-simm}\n", 23,
     "environment.adapter", "unknown adapter 'ballchase-simm'. Did you mean 'ballchase-sim'?"),
    ("not a mapping", "- just\n- a list\n", 1, "", "a behaviour file must be a mapping"),
    ("output named like an input", GOOD.replace("name: turn", "name: pan"), 16,
     "output.name", "the output is named 'pan', like an input"),
    ("three numbers for a set", GOOD.replace("[0.4, 0.8, 1, 1]", "[0.4, 0.8, 1]"), 8,
     "inputs.size.sets.large", "a set needs 4 numbers [pa, pb, pc, pd]; this one has fewer"),
    ("five numbers for a set", GOOD.replace("[0.4, 0.8, 1, 1]", "[0.4, 0.8, 1, 1, 1]"), 8,
     "inputs.size.sets.large", "a set needs 4 numbers [pa, pb, pc, pd]; this one has more"),
    ("one number for a range", GOOD.replace("range: [0, 1]", "range: [0]"), 5,
     "inputs.size.range", "a range needs 2 numbers [low, high]; this one has fewer"),
    ("a YAML 1.1 boolean is a name in YAML 1.2", GOOD.replace("then: left}", "then: off}"), 20,
     "rules.1.then", "unknown command 'off'"),
    ("a YAML boolean as a name", GOOD.replace("then: left}", "then: true}"), 20,
     "rules.1.then", "'true' reads as a boolean in YAML"),
    ("an empty value", GOOD.replace("name: chase", "name:"), 2,
     "name", "no value is given"),
    ("a version that is not a number", GOOD.replace("flctool: 1", "flctool: '1'"), 1,
     "flctool", "'1' is not a number"),
    ("elites fill the population", GOOD + "learning: {population: 4, elites: 4}\n", 23,
     "learning.elites", "4 elites in a population of 4 copy every individual unchanged"),
    # a value of two forms (a number or a mapping) is reported in the form it is written in
    ("a target out of its unit's range", GOOD + "learning: {stop: {target: {success: 1.5}}}\n",
     23, "learning.stop.target.success", "input should be less than or equal to 1, got 1.5"),
    ("a target's unit misspelt", GOOD + "learning: {stop: {target: {sucess: 0.9}}}\n", 23,
     "learning.stop.target.sucess", "unknown key 'sucess'. Did you mean 'success'?"),
    ("a target that is neither", GOOD + "learning: {stop: {target: high}}\n", 23,
     "learning.stop.target", "input should be a valid number, unable to parse string"),
    ("a list or a word", GOOD + "learning: {sets: {inputs: alll}}\n", 23,
     "learning.sets.inputs", "input should be 'all'"),
    ("a mapping expected", GOOD + "learning: {sets: {inputs: {size: 3}}}\n", 23,
     "learning.sets.inputs.size", "a mapping is expected here, got 3"),
    # a limit the first generation would break (the budget is checked between generations)
    ("a limit below one generation", GOOD + "learning: {stop: {episodes: 10}}\n", 23,
     "learning.stop", "episodes: 10 cannot pay for one generation, which takes 20 "
     "(population 10 x trials 2)"),
]


@pytest.mark.parametrize(("text", "line", "path", "message"),
                         [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_bad_file_is_reported_at_its_line(text: str, line: int | None, path: str,
                                          message: str) -> None:
    problems = _problems(text)
    assert not any("function-" in p_path or "Config" in p_msg for _, p_path, p_msg in problems)
    assert any(p_line == line and p_path == path and message in p_msg
               for p_line, p_path, p_msg in problems), problems


def test_bad_files_are_distinct() -> None:
    assert len({case[1] for case in BAD}) == len(BAD) >= 15


def test_every_problem_is_reported_not_just_the_first() -> None:
    text = (GOOD.replace("[0.4, 0.8, 1, 1]", "[0.8, 0.4, 1, 1]")
            .replace("    unit: deg", "    units: deg")
            .replace("range: [-90, 90]", "range: [-90, x]"))
    problems = _problems(text)
    assert [p[1] for p in problems] == ["inputs.size.sets.large", "inputs.pan.range.1",
                                        "inputs.pan.units"]


def test_every_rule_problem_is_reported() -> None:
    text = GOOD.replace("then: left}", "then: nowhere}").replace("pan: right}, then: ahead",
                                                                  "pan: rihgt}, then: ahead")
    assert [p[0] for p in _problems(text)] == [20, 21]


def test_messages_carry_file_line_column_and_a_fix() -> None:
    with pytest.raises(SpecError) as info:
        parse_behaviour(GOOD.replace("    units: deg", "").replace("    unit: deg",
                                                                     "    units: deg"), "b.yaml")
    text = str(info.value.problems[0])
    assert text == ("b.yaml:11:5: inputs.pan.units: unknown key 'units'. Did you mean 'unit'? "
                    "(fix: allowed keys here: range, unit, sets)")


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SpecError, match="no such file"):
        load_behaviour(tmp_path / "absent.yaml")


def test_empty_file(tmp_path: Path) -> None:
    path = tmp_path / "empty.yaml"
    path.write_text("")
    with pytest.raises(SpecError, match="must be a mapping, but this is empty"):
        load_behaviour(path)


def test_keys_are_the_text_written() -> None:
    # YAML 1.1 reads a bare `off` as false; as a key in a behaviour file it is a name.
    text = (GOOD.replace("commands: {right: -1, ahead: 0, left: 1}",
                         "commands: {right: -1, off: 0, left: 1}")
            .replace("then: ahead}", "then: 'off'}"))
    assert list(parse_behaviour(text).output.commands) == ["right", "off", "left"]


def test_anchors_of_plain_data_are_fine() -> None:
    text = GOOD.replace("      small: [0, 0, 0.2, 0.6]", "      small: &s [0, 0, 0.2, 0.6]")
    assert parse_behaviour(text).inputs["size"].sets["small"] == (0, 0, 0.2, 0.6)


def test_behaviour_is_frozen() -> None:
    behaviour = parse_behaviour(GOOD)
    with pytest.raises(Exception, match="frozen"):
        behaviour.name = "other"  # type: ignore[misc]


def test_model_validation_outside_the_loader_still_checks_consistency() -> None:
    from flctool.behaviour.models import Behaviour

    data = parse_behaviour(GOOD).model_dump(by_alias=True)
    data["rules"][0]["then"] = "nowhere"
    with pytest.raises(ValueError, match="unknown command 'nowhere'"):
        Behaviour.model_validate(data)


# -- hostile and broken inputs ---------------------------------------------------------------
@pytest.mark.parametrize(("written", "message"), [
    ("yes", "'yes' is not a number"), ("off", "'off' is not a number"),
    ("1:00", "'1:00' is not a number"), ("1_000", "'1_000' is not a number"),
    ("true", "'true' is a boolean, not a number"), ("'2'", "'2' is not a number"),
])
def test_a_number_field_never_takes_a_boolean_or_text(written: str, message: str) -> None:
    for old, line, path in (("right: -1,", 17, "output.commands.right"),
                            ("range: [0, 1]", 5, "inputs.size.range.1")):
        new = old.replace("-1", written) if "-1" in old else "range: [0, " + written + "]"
        problems = _problems(GOOD.replace(old, new))
        assert (line, path) in [(p[0], p[1]) for p in problems]
        assert any(message in p[2] for p in problems), problems
    seed = _problems(GOOD + f"learning: {{seed: {written}}}\n")
    assert seed[0][:2] == (23, "learning.seed") and message in seed[0][2]


def test_numbers_are_read_as_yaml_1_2_writes_them() -> None:
    behaviour = parse_behaviour(GOOD + "learning: {seed: 010, population: 0x10}\n")
    assert behaviour.learning.seed == 10 and behaviour.learning.population == 16


def test_a_hyphenated_behaviour_name_is_accepted() -> None:
    behaviour = parse_behaviour(GOOD.replace("name: chase", "name: chase-mine"))
    assert behaviour.name == "chase-mine"


def test_a_hyphenated_set_name_says_how_to_fix_it() -> None:
    problems = _problems(GOOD.replace("name: turn", "name: my-turn"))
    assert problems == [(16, "output.name", "'my-turn' is not a valid name: use letters, "
                         "digits and _ only, starting with a letter or _")]


def test_type_errors_do_not_hide_cross_field_problems() -> None:
    text = (GOOD.replace("range: [-90, 90]", "range: [-90, x]")  # a type error
            .replace("large: [0.4, 0.8, 1, 1]", "large: [0.7, 0.8, 1, 1]")  # a gap in size
            .replace("then: right}\n  - {if: {size: small, pan: left}",
                     "then: rigth}\n  - {if: {size: small, pan: left}"))  # an unknown command
    problems = _problems(text)
    assert [(p[0], p[1]) for p in problems] == [
        (6, "inputs.size.sets"), (10, "inputs.pan.range.1"), (19, "rules.0.then")]
    assert "unknown command 'rigth'" in problems[2][2]


@pytest.mark.parametrize(("extra", "path", "message"), [
    ("learning: {population: 100000000}", "learning.population",
     "population 100,000,000 is more than flctool's limit of 10,000"),
    ("learning: {trials: 100000000}", "learning.trials", "more than flctool's limit"),
    ("learning: {generations: 100000000}", "learning.generations", "more than flctool's limit"),
    ("environment: {adapter: ballchase-sim, max_steps: 100000000}", "environment.max_steps",
     "max_steps 100,000,000 is more than flctool's limit of 1,000,000"),
    ("learning: {population: 10000, trials: 1000}\n"
     "environment: {adapter: gymnasium, id: CartPole-v1, max_steps: 10000}",
     "environment.max_steps", "steps side by side"),
])
def test_sizes_past_the_limits_are_refused(extra: str, path: str, message: str) -> None:
    problems = _problems(GOOD.replace("size:", "ball_size:").replace("{size:", "{ball_size:")
                         + extra + "\n")
    assert any(p[1] == path and message in p[2] for p in problems), problems


def test_a_rule_grid_past_the_limit_is_refused_at_once() -> None:
    inputs = "".join(f"  x{i}:\n    range: [0, 1]\n    sets: {{lo: [0, 0, 0, 1], "
                     "hi: [0, 1, 1, 1]}\n" for i in range(30))
    text = ("flctool: 1\nname: wide\ninputs:\n" + inputs
            + "output:\n  name: a\n  commands: {x: 0}\n")
    problems = _problems(text)
    assert problems[0][:2] == (3, "inputs")
    assert "M = 2 x 2" in problems[0][2] and "1,073,741,824 rules" in problems[0][2]


@pytest.mark.parametrize("description", ["valid", 5])  # 5: the checks of a partial file
def test_the_loader_names_other_rules_by_the_namer_it_is_given(description: object) -> None:
    data = {"flctool": 1, "name": "t", "description": description,
            "inputs": {"x": {"range": [0, 1], "sets": {"low": [0, 0, 0.4, 0.6],
                                                        "high": [0.4, 0.6, 1, 1]}}},
            "output": {"name": "u", "commands": {"up": 1}},
            "rules": [{"if": {"x": "low"}, "then": "up"}, {"if": {"x": "low"}, "then": "up"}]}
    source = SourceMap("t.txt", {("rules", 0): (5, 1), ("rules", 1): (6, 1)})
    with pytest.raises(SpecError) as by_path:
        behaviour_from_data(data, source)
    with pytest.raises(SpecError) as by_line:
        behaviour_from_data(data, source, rule_names=lambda index: f"line {5 + index}")
    assert [(p.line, p.message) for p in by_path.value.problems if p.line] == [
        (6, "duplicate rule: the same antecedent as rules[0]")]
    assert [(p.line, p.message) for p in by_line.value.problems if p.line] == [
        (6, "duplicate rule: the same antecedent as line 5")]


def test_an_unknown_activation_is_located_with_the_choices(minimal_text: str) -> None:
    with pytest.raises(SpecError) as info:
        parse_behaviour(minimal_text + "activation: prod\n", "b.yaml")
    text = str(info.value.problems[0])
    line = len(minimal_text.splitlines()) + 1
    assert text.startswith(f"b.yaml:{line}:1: activation: input should be 'min' or 'product'")
