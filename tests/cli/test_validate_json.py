"""``flctool validate --json``: every file's problems as data, in the documented schema."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from flctool.cli import app

from ..conftest import BEHAVIOURS

runner = CliRunner()
PROBLEM_KEYS = {"file", "line", "column", "field", "message", "fix"}
FILE_KEYS = {"file", "valid", "behaviour", "deployable", "rules", "rules_to_learn",
             "budget", "problems", "warnings", "notes"}


def test_problems_are_data_with_file_line_column_field_message_and_fix(
        tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("flctool: 1\nname: x\ninputs: 3\n")
    good = BEHAVIOURS / "ballchase.yaml"
    result = runner.invoke(app, ["validate", "--json", str(good), str(bad),
                                 str(tmp_path / "none.yaml")])
    assert result.exit_code == 1
    report = json.loads(result.stdout)  # nothing but the JSON on stdout
    assert report["format"] == 1 and report["valid"] is False
    files = report["files"]
    assert [f["file"] for f in files] == [str(good), str(bad), str(tmp_path / "none.yaml")]
    assert all(set(f) == FILE_KEYS for f in files)
    assert files[0] | {"problems": None, "budget": None} == {
        "file": str(good), "valid": True, "behaviour": "ballchase", "deployable": False,
        "rules": 15, "rules_to_learn": 15, "budget": None, "problems": None, "warnings": [],
        "notes": []}
    budget = files[0]["budget"]
    # no budget in the file: 30 generations, on while improving, to at most 60; 2 trials
    assert budget["training_episodes"] == 60 * 10 * 2
    assert budget["extend"] == {"most_generations": 60, "patience": 10}
    assert budget["settings"]["generations"] == {"value": 30, "from": "default"}
    assert budget["settings"]["trials"] == {"value": 2, "from": "default"}
    # 120 against the baselines, and up to 300 settling an undecided comparison
    assert budget["most_episodes"] == 1200 + budget["selection_episodes_at_most"] + 50 + 420
    assert budget["statement"][0].startswith("budget: at most")
    assert files[1]["budget"] is None  # invalid: nothing to state
    problems = files[1]["problems"]
    assert all(set(p) == PROBLEM_KEYS for p in problems)
    assert {"file": str(bad), "line": 3, "column": 1, "field": "inputs",
            "message": "a mapping is expected here, got 3", "fix": None} in problems
    assert files[2]["problems"] == [{
        "file": str(tmp_path / "none.yaml"), "line": None, "column": None, "field": None,
        "message": "no such file or directory",
        "fix": "check the path; it should name a behaviour file or run directory"}]


def test_a_valid_set_exits_0_and_warnings_are_data_too(tmp_path: Path) -> None:
    text = (BEHAVIOURS / "ballchase-handmade.yaml").read_text()
    twin = tmp_path / "twin.yaml"  # two commands with one singleton: a warning
    twin.write_text(text.replace("forward_left: 0.5", "forward_left: 0.0"))
    result = runner.invoke(app, ["validate", "--json", str(twin)])
    assert result.exit_code == 0, result.output
    [entry] = json.loads(result.stdout)["files"]
    assert entry["valid"] and entry["deployable"] and entry["rules_to_learn"] == 0
    assert entry["budget"] is None  # nothing to learn
    [warning] = entry["warnings"]
    assert set(warning) == PROBLEM_KEYS and warning["line"] is not None
