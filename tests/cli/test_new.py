"""flctool new: writes a valid file, prints to stdout, refuses to overwrite, bad specs exit 1."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from flctool.cli import app

runner = CliRunner()
ARGS = ["new", "chase", "--input", "ball_size:0:1:3", "--input", "pan:-90:90:5",
        "--command", "turn_right:-1", "--command", "forward:0", "--command", "turn_left:1",
        "--env", "pitch"]


def test_new_writes_a_file_that_validates(tmp_path: Path) -> None:
    out = tmp_path / "chase.yaml"
    result = runner.invoke(app, [*ARGS, "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "next: flctool validate" in result.output
    result = runner.invoke(app, ["validate", str(out)])
    assert result.exit_code == 0 and "15 of 15 rules to learn" in result.output
    again = runner.invoke(app, [*ARGS, "-o", str(out)])
    assert again.exit_code == 1 and "exists" in again.output
    assert runner.invoke(app, [*ARGS, "-o", str(out), "--force"]).exit_code == 0


def test_new_prints_the_file_without_out() -> None:
    result = runner.invoke(app, ARGS)
    assert result.exit_code == 0 and result.output.startswith("# chase: scaffolded")


def test_bad_spec_is_one_line_and_exit_1() -> None:
    result = runner.invoke(app, ["new", "x", "--input", "pan:90:-90:3", "--command", "a:1",
                                 "--command", "b:2"])
    assert result.exit_code == 1
    assert "LO 90 must be below HI -90" in result.output and "Traceback" not in result.output


def test_help_has_an_example() -> None:
    result = runner.invoke(app, ["new", "--help"])
    assert result.exit_code == 0 and "Examples:\n    flctool new chase" in result.output
