"""``flctool experiment`` end to end, and its errors."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from flctool.cli import app
from flctool.runs import open_run

from ..conftest import BEHAVIOURS

runner = CliRunner()
TINY = ["--set", "generations=3", "--set", "population=4", "--heldout", "20"]


@pytest.mark.slow
def test_experiment_writes_a_report_and_continues(tmp_path: Path) -> None:
    out = tmp_path / "exp"
    args = ["experiment", str(BEHAVIOURS / "ballchase.yaml"), "--seeds", "2", "--learners",
            "pitt,hybrid", *TINY, "--out", str(out)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    assert "mean fitness rises sooner than Pitt's" in result.output
    # the spread across seeds is named: a bracket would read as a confidence interval
    assert re.search(r"pitt: held-out success median [0-9.]+, interquartile range [0-9.]+ to "
                     r"[0-9.]+ across 2 seeds", result.output), result.output
    # each progress line once, though output goes to a file (not a terminal)
    progress = [line for line in result.output.splitlines() if line.startswith("runs ")]
    assert len(progress) == len(set(progress))
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
        (["--set", "seed=3"], "'seed' is decided by the experiment"),
        (["--set", "crossover=2"], "learning.crossover"),
        (["--set", "stop.seconds=5"], "would not reproduce"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, ["experiment", file, *extra, *out])
        assert result.exit_code == 1, (extra, result.output)
        assert message in result.output, result.output
        assert "Traceback" not in result.output
    assert not (tmp_path / "x").exists()


@pytest.mark.slow
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


@pytest.mark.slow
def test_one_file_carries_the_settings_of_every_compared_learner(tmp_path: Path) -> None:
    """exploration for the fuzzy_q runs, pitt_crossover for the pitt runs, and a --set of
    q for the runs that read q: each run's behaviour.yaml holds its learner's keys only."""
    from flctool.behaviour import load_behaviour
    from flctool.behaviour.learning import FuzzyQConfig, HybridConfig, PittConfig, learner_keys

    from ..experiment.helpers import write_mixed

    file = write_mixed(tmp_path)
    out = tmp_path / "exp"
    args = ["experiment", str(file), "--seeds", "2", "--heldout", "10",
            "--set", "q.temperature=0.2", "--out", str(out)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    models = {"pitt": PittConfig, "hybrid": HybridConfig, "fuzzy_q": FuzzyQConfig}
    for learner, model in models.items():
        for seed in (0, 1):
            path = out / "runs" / f"{learner}-seed{seed}" / "behaviour.yaml"
            written = yaml.safe_load(path.read_text())["learning"]
            # every key of its learner but the unset ones, which are not written: 'sets' (no
            # sets learned), 'restart_after' (the learner's default) and 'extend' (the file
            # gives its generations)
            assert tuple(written) == tuple(k for k in learner_keys(model)
                                           if k not in ("sets", "restart_after", "extend")), \
                learner
            learning = load_behaviour(path).learning  # a valid file of its learner
            assert (learning.learner, learning.seed, learning.generations) == (learner, seed, 2)
            assert len(open_run(path.parent).metrics()) == 2
    assert yaml.safe_load((out / "runs" / "pitt-seed0" / "behaviour.yaml").read_text())[
        "learning"]["pitt_crossover"] == "one_point"
    for learner in ("hybrid", "fuzzy_q"):  # the runs that read q
        assert open_run(out / "runs" / f"{learner}-seed0").behaviour.learning.q.temperature \
            == 0.2
    exploration = open_run(out / "runs" / "fuzzy_q-seed0").behaviour.learning.exploration
    assert (exploration.policy, exploration.epsilon) == ("epsilon_greedy", 0.3)
    # the same command continues the experiment: the same plan, nothing redone
    stamp = (out / "runs" / "fuzzy_q-seed1" / "best.yaml").stat().st_mtime_ns
    again = runner.invoke(app, [*args, "--json"])
    assert again.exit_code == 0, again.output
    assert (out / "runs" / "fuzzy_q-seed1" / "best.yaml").stat().st_mtime_ns == stamp


def test_keys_no_compared_learner_reads_are_refused(tmp_path: Path) -> None:
    from ..experiment.helpers import write_mixed

    file = str(write_mixed(tmp_path))
    out = ["--out", str(tmp_path / "x")]
    cases = [
        (["--learners", "pitt,hybrid"],
         "learning.exploration: 'exploration' is read by the fuzzy_q learner only, which this "
         "experiment does not compare"),
        (["--learners", "fuzzy_q", "--set", "q.temperature=0.2", "--set",
          "common_starts=true"], "command line (--set common_starts): learning.common_starts: "
         "'common_starts' is read by the pitt and hybrid learners, none of which"),
        (["--learners", "hybrid,fuzzy_q", "--set", "pitt_crossover=uniform"],
         "'pitt_crossover' is read by the pitt learner only, none of which this experiment "
         "compares"),
    ]
    for extra, message in cases:
        result = runner.invoke(app, ["experiment", file, *extra, *out])
        assert result.exit_code == 1, (extra, result.output)
        assert message in " ".join(result.output.split()), result.output
        assert "Traceback" not in result.output
    assert not (tmp_path / "x").exists()
