"""summary.json and report.md from a real tiny experiment."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from flctool.errors import RunDirError
from flctool.experiment import read_summary, summarise, write_report
from flctool.experiment.executors import LocalExecutor
from flctool.experiment.report import REPORT_FILE, read_records

from .helpers import tiny_experiment


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Path:
    experiment = tiny_experiment(tmp_path_factory.mktemp("exp") / "exp", seeds=3)
    experiment.run(LocalExecutor(1))
    write_report(experiment)
    return experiment.path


@pytest.mark.slow
def test_summary_matches_the_runs(finished: Path) -> None:
    from flctool.experiment import open_experiment

    experiment = open_experiment(finished)
    summary = read_summary(finished)
    records = read_records(experiment)
    hybrid = [r for r in records if r.learner == "hybrid"]
    curve = summary["curves"]["hybrid"]
    assert curve["episodes"] == [4.0, 8.0, 12.0]  # population 4, one trial each
    assert curve["mean"]["median"] == pytest.approx(
        np.median([r.mean for r in hybrid], axis=0).tolist())
    entry = summary["learners"]["hybrid"]
    assert entry["auc_mean"]["values"] == pytest.approx([float(r.mean.sum()) for r in hybrid])
    assert entry["heldout_success"]["values"] == [r.heldout["success_rate"] for r in hybrid]
    cost = entry["cost"]
    assert cost["training_episodes"] == 3 * 12
    assert cost["heldout_episodes"] == 3 * 20
    assert cost["training_steps"] == sum(r.training_steps for r in hybrid)
    # model selection's validation episodes are counted, as each run recorded them
    from flctool.runs import open_run

    usage = [open_run(experiment.runs_dir / f"hybrid-seed{s}").summary().usage.to_dict()
             for s in range(3)]  # type: ignore[union-attr]
    assert cost["selection_episodes"] == sum(u["selection_episodes"] for u in usage) > 0
    assert cost["episodes_per_run_max"] == max(
        u["training_episodes"] + u["selection_episodes"] for u in usage)
    # every pair of learners, for every measure
    pairs = {(c["a"], c["b"]) for c in summary["comparisons"]}
    assert pairs == {("pitt", "hybrid"), ("pitt", "fuzzy_q"), ("hybrid", "fuzzy_q")}
    assert len(summary["comparisons"]) == 3 * len(summary["metrics"])
    for c in summary["comparisons"]:
        assert 0.0 <= c["p"] <= 1.0 and 0.0 <= c["effect_a_greater"] <= 1.0


def test_bands_never_leave_the_fitness_range(finished: Path) -> None:
    summary = read_summary(finished)
    for curve in summary["curves"].values():
        for key in ("q25", "median", "q75"):
            values = np.array(curve["mean"][key])
            assert np.all((values >= 0.0) & (values < 2.0))  # ballchase fitness is in [0, 2)


def test_each_claim_is_answered_with_numbers(finished: Path) -> None:
    summary = read_summary(finished)
    claims = summary["claims"]
    assert [c["curve"] for c in claims] == ["mean", "std"]
    for claim in claims:
        assert claim["verdict"].startswith(("holds", "does not hold"))
        assert 0.0 <= claim["p_area"] <= 1.0
        assert len(claim["area_hybrid"]["values"]) == 3
    report = (finished / REPORT_FILE).read_text()
    assert "mean fitness rises sooner than Pitt's: " in report
    assert "population std falls sooner than Pitt's: " in report
    assert "one-sided p (hybrid larger) = " in report
    assert "| pitt | hybrid |" in report
    assert "held-out episodes" in report


@pytest.mark.slow
def test_claims_need_both_learners(tmp_path: Path) -> None:
    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("hybrid", "fuzzy_q"))
    experiment.run(LocalExecutor(1))
    summary = summarise(experiment)
    assert {c["verdict"] for c in summary["claims"]} == {"not tested"}
    assert "needs both the pitt and hybrid" in write_report(experiment)["claims"][0]["reason"]


def test_a_given_level(finished: Path) -> None:
    from flctool.experiment import open_experiment

    summary = summarise(open_experiment(finished), level=5.0)  # above any fitness
    entry = summary["learners"]["pitt"]["episodes_to_level"]
    assert entry["reached"] == 0 and entry["median"] is None
    assert entry["values"] == [None, None, None]
    json.dumps(summary, allow_nan=False)
    assert not math.isnan(summary["level"])


def test_an_unfinished_experiment_cannot_be_summarised(tmp_path: Path) -> None:
    experiment = tiny_experiment(tmp_path / "exp", seeds=1)
    with pytest.raises(RunDirError, match="has not started"):
        summarise(experiment)
