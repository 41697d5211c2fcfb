"""``flctool experiment`` end to end, and its errors."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from flctool.cli import app

from ..conftest import BEHAVIOURS

runner = CliRunner()
TINY = ["--set", "generations=3", "--set", "population=4", "--heldout", "20"]


def test_experiment_writes_a_report_and_continues(tmp_path: Path) -> None:
    out = tmp_path / "exp"
    args = ["experiment", str(BEHAVIOURS / "ballchase.yaml"), "--seeds", "2", "--learners",
            "pitt,hybrid", *TINY, "--out", str(out)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "mean fitness rises sooner than Pitt's" in result.output
    report = (out / "report.md").read_text()
    assert report.startswith("# Experiment: ballchase")
    # run again: nothing is redone, the report is the same
    stamp = (out / "runs" / "pitt-seed0" / "best.yaml").stat().st_mtime_ns
    again = runner.invoke(app, [*args, "--json"])
    assert again.exit_code == 0, again.output
    assert json.loads(again.stdout)["plan"]["seeds"] == 2
    assert (out / "runs" / "pitt-seed0" / "best.yaml").stat().st_mtime_ns == stamp
    assert (out / "report.md").read_text() == report


def test_bad_options_are_clear_errors(tmp_path: Path) -> None:
    file = str(BEHAVIOURS / "ballchase.yaml")
    out = ["--out", str(tmp_path / "x")]
    cases = [
        (["--learners", "pitt,qlearn"], "unknown learner(s) in --learners: qlearn"),
        (["--executor", "dask"], "unknown executor 'dask'"),
        (["--set", "seed=3"], "--set seed is decided by the experiment"),
        (["--set", "crossover=2"], "learning.crossover"),
        (["--set", "stop.seconds=5"], "would not reproduce"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, ["experiment", file, *extra, *out])
        assert result.exit_code == 1, (extra, result.output)
        assert message in result.output, result.output
        assert "Traceback" not in result.output
    assert not (tmp_path / "x").exists()


def test_another_plan_in_the_same_directory_is_refused(tmp_path: Path) -> None:
    file = str(BEHAVIOURS / "ballchase.yaml")
    out = ["--out", str(tmp_path / "exp")]
    first = runner.invoke(app, ["experiment", file, "--seeds", "1", "--learners", "pitt",
                                *TINY, *out])
    assert first.exit_code == 0, first.output
    second = runner.invoke(app, ["experiment", file, "--seeds", "2", "--learners", "pitt",
                                 *TINY, *out])
    assert second.exit_code == 1
    assert "different plan" in second.output and "seeds" in second.output
