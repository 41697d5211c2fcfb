"""``flctool export`` and ``flctool import`` as a user runs them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flctool import compile_behaviour, load_behaviour, parse_behaviour
from flctool.cli import app

from ..conftest import BEHAVIOURS, ROOT

runner = CliRunner()
HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"


def test_help() -> None:
    for command in ("export", "import"):
        result = runner.invoke(app, [command, "--help"])
        assert result.exit_code == 0 and "Usage" in result.output


def test_export_yaml_to_stdout_is_the_same_controller() -> None:
    result = runner.invoke(app, ["export", str(HANDMADE)])
    assert result.exit_code == 0, result.output
    assert result.output.startswith("# ballchase_handmade: exported by flctool")
    assert parse_behaviour(result.output) == load_behaviour(HANDMADE)


@pytest.mark.slow
def test_every_format_through_a_file_and_back(tmp_path: Path) -> None:
    want = compile_behaviour(load_behaviour(HANDMADE))
    states = np.random.default_rng(0).uniform([-0.1, -100], [1.1, 100], (1000, 2))
    for format in ("fll", "fcl", "fis"):
        exported = tmp_path / f"ctl.{format}"
        result = runner.invoke(app, ["export", str(HANDMADE), "-f", format, "-o", str(exported)])
        assert result.exit_code == 0, result.output
        assert f"wrote {exported}" in result.output.replace("\n", "")
        back = tmp_path / f"from-{format}.yaml"
        result = runner.invoke(app, ["import", str(exported), "-o", str(back)])
        assert result.exit_code == 0, result.output
        assert runner.invoke(app, ["validate", str(back)]).exit_code == 0
        text = back.read_text()
        assert "flctool: 1" in text and "learning:" not in text
        assert np.array_equal(compile_behaviour(load_behaviour(back)).output(states),
                              want.output(states))


def test_c_writes_header_and_source(tmp_path: Path) -> None:
    result = runner.invoke(app, ["export", str(HANDMADE), "-f", "c", "--prefix", "ballchase_",
                                 "--float", "-o", str(tmp_path / "ballchase")])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ballchase.c", "ballchase.h"]
    assert "float ballchase_output(" in (tmp_path / "ballchase.h").read_text()


def test_a_behaviour_that_acts_by_vote_says_so_where_the_format_cannot(tmp_path: Path
                                                                      ) -> None:
    """FLL, FCL and FIS compute eq. 3's output only: exporting a vote behaviour warns, and the
    engine files say it in a comment; C exports the vote (tests/export/test_c_source.py)."""
    park = ROOT / "benchmarks" / "tasks" / "park-handmade.yaml"
    for format in ("fll", "fcl", "fis"):
        exported = tmp_path / f"park.{format}"
        result = runner.invoke(app, ["export", str(park), "-o", str(exported)])
        assert result.exit_code == 0, result.output
        assert "warning: 'park_handmade' acts by vote" in result.stderr
        if format != "fis":  # FIS has no comments
            assert "It acts by vote (environment.action: vote)" in exported.read_text()
    result = runner.invoke(app, ["export", str(park), "-o", str(tmp_path / "park.c")])
    assert result.exit_code == 0 and "warning" not in result.stderr
    result = runner.invoke(app, ["export", str(HANDMADE), "-o", str(tmp_path / "ball.fll")])
    assert "warning" not in result.stderr and "vote" not in (tmp_path / "ball.fll").read_text()
    result = runner.invoke(app, ["export", str(park), "-f", "bundle", "-o",
                                 str(tmp_path / "bundle")])
    assert result.exit_code == 1 and "--format c (its <prefix>command is the vote)" in (
        result.stderr)


def test_errors_are_messages_not_tracebacks(tmp_path: Path) -> None:
    incomplete = runner.invoke(app, ["export", str(BEHAVIOURS / "ballchase.yaml")])
    assert incomplete.exit_code == 1
    assert "not deployable: 15 of 15 rules" in incomplete.output
    assert "IF ball_size IS small AND pan IS far_right" in incomplete.output

    target = tmp_path / "out.yaml"
    target.write_text("mine")
    exists = runner.invoke(app, ["export", str(HANDMADE), "-o", str(target)])
    assert exists.exit_code == 1 and "already exists" in exists.output
    assert target.read_text() == "mine"
    assert runner.invoke(app, ["export", str(HANDMADE), "-o", str(target), "--force"]
                         ).exit_code == 0

    no_suffix = runner.invoke(app, ["export", str(HANDMADE), "-o", str(tmp_path / "x")])
    assert no_suffix.exit_code == 1 and "cannot tell the format" in no_suffix.output

    unknown = runner.invoke(app, ["export", str(HANDMADE), "-f", "jsn"])
    assert unknown.exit_code == 1 and "Did you mean 'json'" in unknown.output

    c_only = runner.invoke(app, ["export", str(HANDMADE), "-f", "fll", "--float"])
    assert c_only.exit_code == 1 and "apply to the c format only" in c_only.output

    odd = tmp_path / "ctl.txt"
    odd.write_text("x")
    suffix = runner.invoke(app, ["import", str(odd)])
    assert suffix.exit_code == 1 and "cannot tell the format" in suffix.output


def test_import_reports_the_construct_and_line(tmp_path: Path) -> None:
    exported = tmp_path / "ctl.fll"
    runner.invoke(app, ["export", str(HANDMADE), "-f", "fll", "-o", str(exported)])
    text = exported.read_text().replace("pan is right then", "pan is very right then")
    exported.write_text(text)
    line = next(i for i, s in enumerate(text.splitlines(), start=1) if "very" in s)
    result = runner.invoke(app, ["import", str(exported)])
    assert result.exit_code == 1
    assert f"ctl.fll:{line}: the hedge 'very'" in result.output.replace("\n", "")


def test_import_writes_one_file_per_output(tmp_path: Path) -> None:
    from ..export.test_fis import TWO_OUTPUTS

    source = tmp_path / "two.fis"
    source.write_text(TWO_OUTPUTS, encoding="utf-8")
    result = CliRunner().invoke(app, ["import", str(source), "-o", str(tmp_path / "two.yaml")])
    assert result.exit_code == 0, result.output
    assert "2 outputs, imported as one behaviour each" in result.output
    assert (tmp_path / "two_u.yaml").is_file() and (tmp_path / "two_v.yaml").is_file()
    to_stdout = CliRunner().invoke(app, ["import", str(source)])
    assert to_stdout.exit_code != 0 and "give -o NAME.yaml" in to_stdout.output
