"""``flctool validate / show / infer / schema`` as a user runs them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour, load_behaviour
from flctool.cli import app

from ..conftest import BEHAVIOURS, ROOT

runner = CliRunner()

BAD = """\
flctool: 1
name: bad
inputs:
  x:
    range: [0, 1]
    sets: {a: [0, 0, 0.5, 0.4], b: [0.3, 0.6, 1, 1]}
    colour: red
output: {name: y, commands: {up: 1}}
"""


def test_version() -> None:
    result = runner.invoke(app, ["--version"])
    assert result.exit_code == 0
    assert result.output.startswith("flctool ")


def test_help_on_every_command() -> None:
    for command in ([], ["validate"], ["show"], ["infer"], ["schema"]):
        result = runner.invoke(app, [*command, "--help"])
        assert result.exit_code == 0, command
        assert "Usage" in result.output


@pytest.mark.slow
def test_validate_shipped_files() -> None:
    files = sorted(str(p) for p in BEHAVIOURS.glob("*.yaml"))
    result = runner.invoke(app, ["validate", *files])
    assert result.exit_code == 0, result.output
    assert result.output.count("ok ") == len(files)
    assert "ballchase-handmade.yaml: ballchase_handmade (deployable)" in result.output


def test_validate_reports_every_problem_and_exits_1(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD)
    result = runner.invoke(app, ["validate", str(bad), str(BEHAVIOURS / "ballchase.yaml")])
    assert result.exit_code == 1
    assert "bad.yaml has 2 problems" in result.output
    assert "bad.yaml:6:" in result.output and "pa <= pb <= pc <= pd" in result.output
    assert "bad.yaml:7:5: inputs.x.colour: unknown key 'colour'" in result.output
    assert "ok " in result.output  # the good file is still checked
    assert "Traceback" not in result.output


def test_validate_goes_on_after_a_file_that_crashes(tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from flctool.cli import behaviour_commands

    real = behaviour_commands.validate_file

    def crash_on_first(path: Path) -> object:
        if path.name == "ballchase.yaml":
            raise RecursionError("maximum recursion depth exceeded")
        return real(path)

    monkeypatch.setattr(behaviour_commands, "validate_file", crash_on_first)
    result = runner.invoke(app, ["validate", str(BEHAVIOURS / "ballchase.yaml"),
                                 str(BEHAVIOURS / "cartpole.yaml")])
    assert result.exit_code == 1
    assert "internal error while checking it: RecursionError" in result.output
    assert "ok " in result.output and "cartpole" in result.output
    assert "Traceback" not in result.output


def test_validate_warns_and_notes_what_it_could_not_check(tmp_path: Path) -> None:
    twin = tmp_path / "twin.yaml"
    twin.write_text((BEHAVIOURS / "cartpole.yaml").read_text().replace(
        "push_right: 1.0", "push_right: -1.0"))
    result = runner.invoke(app, ["validate", str(twin),
                                 str(BEHAVIOURS / "ballchase-robot.yaml")])
    assert result.exit_code == 0, result.output
    assert "warning:" in result.output and "the same value -1" in result.output
    assert "note:" in result.output and "when learn connects to the robot" in result.output


def test_import_module_is_the_only_way_to_run_a_module(tmp_path: Path) -> None:
    result = runner.invoke(app, ["--import-module", "no_such_module_x", "validate",
                                 str(BEHAVIOURS / "cartpole.yaml")])
    assert result.exit_code == 1
    assert "cannot import the module 'no_such_module_x'" in result.output


def test_missing_file_is_bad_input_and_unknown_option_bad_usage(tmp_path: Path) -> None:
    missing = runner.invoke(app, ["validate", str(tmp_path / "none.yaml")])
    assert missing.exit_code == 1 and "none.yaml" in missing.output
    assert runner.invoke(app, ["validate", "--frobnicate"]).exit_code == 2


def test_debug_shows_the_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(BAD)
    result = runner.invoke(app, ["--debug", "show", str(bad)])
    assert result.exit_code == 1
    assert result.exc_info is not None and result.exc_info[0].__name__ == "SpecError"


def test_show_prints_sets_counts_and_rule_grid() -> None:
    result = runner.invoke(app, ["show", str(BEHAVIOURS / "ballchase-handmade.yaml")],
                           env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "M = 15 rules, K = 5 commands" in result.output
    assert "far_right" in result.output and "forward_right" in result.output
    assert "rules: rows ball_size, columns pan" in result.output
    assert "activation" not in result.output  # the paper's min goes without saying


def test_show_says_when_rules_fire_by_the_product(tmp_path: Path) -> None:
    product = tmp_path / "product.yaml"
    product.write_text((BEHAVIOURS / "ballchase-handmade.yaml").read_text()
                       + "activation: product\n")
    result = runner.invoke(app, ["show", str(product)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "activation: product (a rule fires with the product of its memberships)" in \
        " ".join(result.output.split())


def test_show_lists_the_rules_of_other_behaviours(tmp_path: Path) -> None:
    from flctool import with_rules
    from flctool.behaviour import behaviour_to_yaml

    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    learned = tmp_path / "cartpole.yaml"
    learned.write_text(behaviour_to_yaml(with_rules(cartpole, np.zeros(81, dtype=np.intp))))
    result = runner.invoke(app, ["show", str(learned)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "rules, in rule order" in result.output
    assert "M = 81 rules" in result.output and "80" in result.output


def test_show_behaviour_to_learn() -> None:
    result = runner.invoke(app, ["show", str(BEHAVIOURS / "ballchase.yaml")])
    assert result.exit_code == 0
    assert "15 rules still to learn" in result.output
    # what the measured tasks of about its size needed, the nearest first
    assert "similar problems measured (docs/learning.md, seeds 900-909," in result.output
    assert "  ballchase: 15 rules x 5 commands, hybrid, 1,200 training episodes: success " \
        "median 0.994, worst 0.970 (hand-made 1.000)" in result.output
    handmade = runner.invoke(app, ["show", str(BEHAVIOURS / "ballchase-handmade.yaml")])
    assert "similar problems" not in handmade.output


def test_validate_states_the_budget_and_where_each_number_came_from(tmp_path: Path) -> None:
    text = (BEHAVIOURS / "ballchase.yaml").read_text()
    assert "population:" not in text
    mine = tmp_path / "mine.yaml"
    mine.write_text(text.replace("learning:\n", "learning:\n  population: 20\n"
                                 "  protocol: paper\n", 1))
    result = runner.invoke(app, ["validate", str(mine)])
    assert result.exit_code == 0, result.output
    line = mine.read_text().splitlines().index("  population: 20") + 1
    assert "budget: at most" in result.output and "600 training" in result.output
    assert (f"30 generations x 20 individuals x 1 trial (population from the file's line "
            f"{line}, the rest the paper's protocol)") in result.output
    assert "selection.race" in result.output and "selection.confirmation 50 (default)" \
        in result.output


def test_infer_csv_round_trip(tmp_path: Path) -> None:
    states = tmp_path / "states.csv"
    states.write_text("pan,ball_size,note\n10,0.2,a\n-80,0.9,b\n")
    out = tmp_path / "out.csv"
    path = BEHAVIOURS / "ballchase-handmade.yaml"
    result = runner.invoke(app, ["infer", str(path), "--input", str(states), "-o", str(out)])
    assert result.exit_code == 0, result.output
    lines = out.read_text().splitlines()
    assert lines[0] == "pan,ball_size,note,turn"
    controller = compile_behaviour(load_behaviour(path))
    expected = controller.output(np.array([[0.2, 10.0], [0.9, -80.0]]))
    assert [float(line.split(",")[-1]) for line in lines[1:]] == expected.tolist()


def test_infer_from_stdin() -> None:
    result = runner.invoke(app, ["infer", str(BEHAVIOURS / "ballchase-handmade.yaml")],
                           input="ball_size,pan\n0.5,0\n")
    assert result.exit_code == 0
    assert result.output.splitlines() == ["ball_size,pan,turn", "0.5,0,0.0"]


def test_infer_reports_bad_cells_with_lines(tmp_path: Path) -> None:
    states = tmp_path / "states.csv"
    states.write_text("ball_size,pan\n0.2,x\n0.3\n")
    result = runner.invoke(app, ["infer", str(BEHAVIOURS / "ballchase-handmade.yaml"),
                                 "-i", str(states)])
    assert result.exit_code == 1
    assert "states.csv:2:2: pan: 'x' is not a number" in result.output
    assert "states.csv:3: (top level): expected 2 cells, found 1" in result.output


def test_infer_missing_column_and_nan(tmp_path: Path) -> None:
    path = str(BEHAVIOURS / "ballchase-handmade.yaml")
    result = runner.invoke(app, ["infer", path], input="ball_size\n0.2\n")
    assert result.exit_code == 1
    assert "lacks the column(s) pan" in result.output
    result = runner.invoke(app, ["infer", path], input="ball_size,pan\n0.2,nan\n")
    assert result.exit_code == 1
    assert "<stdin>:2:2: pan: NaN is a missing reading, not a value" in result.output


def test_infer_on_a_behaviour_still_to_learn() -> None:
    for states in ("ball_size,pan\n0.2,1\n", "ball_size,pan\n"):
        result = runner.invoke(app, ["infer", str(BEHAVIOURS / "ballchase.yaml")],
                               input=states)
        assert result.exit_code == 1
        assert "is not deployable: 15 of 15 rules have no consequent" in result.output


def test_infer_file_errors_are_messages_not_tracebacks(tmp_path: Path) -> None:
    path = str(BEHAVIOURS / "ballchase-handmade.yaml")
    binary = tmp_path / "states.csv"
    binary.write_bytes(b"ball_size,pan\n\xff,1\n")
    cases = [
        (["-i", str(binary)], "states.csv:2:1: the CSV is not UTF-8 text (byte 0xff;"),
        (["-i", str(tmp_path / "none.csv")], "none.csv: no such file or directory"),
        (["-i", str(tmp_path)], "is a folder, not a states CSV"),
        (["-o", str(tmp_path)], "the output CSV " + str(tmp_path) + " is a folder"),
    ]
    for options, message in cases:
        result = runner.invoke(app, ["infer", path, *options], input="ball_size,pan\n0.1,2\n")
        assert result.exit_code == 1, options
        assert message in result.output, (options, result.output)
        assert result.exc_info is None or result.exc_info[0] is SystemExit


def test_schema_check_passes_on_the_committed_file() -> None:
    result = runner.invoke(app, ["schema", "--check", "--path",
                                 str(ROOT / "schemas" / "behaviour.schema.json")])
    assert result.exit_code == 0, result.output


def test_schema_to_an_unwritable_place(tmp_path: Path) -> None:
    result = runner.invoke(app, ["schema", "--path", str(tmp_path)])
    assert result.exit_code == 1
    assert "is a folder" in result.output


@pytest.mark.slow
def test_schema_check_fails_when_stale(tmp_path: Path) -> None:
    stale = tmp_path / "schema.json"
    stale.write_text("{}\n")
    result = runner.invoke(app, ["schema", "--check", "--path", str(stale)])
    assert result.exit_code == 1
    assert "stale" in result.output
    kept = runner.invoke(app, ["schema", "--path", str(stale)])
    assert kept.exit_code == 1 and "--force" in kept.output
    assert runner.invoke(app, ["schema", "--path", str(stale), "--force"]).exit_code == 0
    assert runner.invoke(app, ["schema", "--check", "--path", str(stale)]).exit_code == 0


def test_show_compare_lists_each_sets_movement(tmp_path: Path) -> None:
    from flctool.behaviour.dump import behaviour_to_data, behaviour_to_yaml
    from flctool.behaviour.load import behaviour_from_data
    from flctool.sets.codec import SetCodec

    data = behaviour_to_data(load_behaviour(BEHAVIOURS / "ballchase.yaml"))
    data["learning"]["sets"] = {"inputs": ["pan"]}
    original = behaviour_from_data(data)
    genes = [0.0] * SetCodec(original).size
    genes[0] = 1.0  # the gap from -90 to far_right's shoulder grows
    learned = tmp_path / "learned.yaml"
    learned.write_text(behaviour_to_yaml(SetCodec(original).decode(genes)))
    result = runner.invoke(app, ["show", str(learned), "--compare",
                                 str(BEHAVIOURS / "ballchase.yaml")], terminal_width=200)
    assert result.exit_code == 0, result.output
    lines = {line.split("│")[2].strip(): line for line in result.output.splitlines()
             if line.count("│") > 5 and line.split("│")[2].strip()}
    assert "0 %" in lines["small"] and "0.0 %" in lines["small"]
    assert "deg" in lines["far_right"] and "0.0 %" not in lines["far_right"]
    assert "pan: coverage 0.5" in result.output


def test_show_compare_refuses_the_controller_shown(tmp_path: Path) -> None:
    from flctool.runs import BEHAVIOUR_FILE

    run = tmp_path / "run"
    run.mkdir()
    (run / "best.yaml").write_text((BEHAVIOURS / "ballchase-handmade.yaml").read_text())
    for compare in (run, run / "best.yaml"):
        result = runner.invoke(app, ["show", str(run), "--compare", str(compare)],
                               terminal_width=200)
        assert result.exit_code == 1
        assert "nothing to compare its sets with" in result.output
        assert str(run / BEHAVIOUR_FILE) in result.output
        assert "Traceback" not in result.output


def test_show_compare_refuses_another_behaviour() -> None:
    result = runner.invoke(app, ["show", str(BEHAVIOURS / "ballchase.yaml"), "--compare",
                                 str(BEHAVIOURS / "cartpole.yaml")])
    assert result.exit_code == 1
    assert "other inputs, ranges or set names" in result.output
