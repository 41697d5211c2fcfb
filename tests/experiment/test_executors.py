"""Executors give the same experiment whatever runs the jobs: 1 or 2 local processes, Ray."""

from __future__ import annotations

import builtins
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from flctool.errors import EnvError, FlcError, MissingDependencyError, RunDirError
from flctool.experiment import make_executor, write_report
from flctool.experiment.executors import LocalExecutor, RayExecutor, unpack_run
from flctool.experiment.report import REPORT_FILE, SUMMARY_FILE

from .helpers import tiny_experiment


def _report(tmp_path: Path, name: str, executor: Any) -> tuple[str, str]:
    experiment = tiny_experiment(tmp_path / name)
    experiment.run(executor)
    write_report(experiment)
    return ((experiment.path / REPORT_FILE).read_text(),
            (experiment.path / SUMMARY_FILE).read_text())


@pytest.mark.slow
def test_one_and_two_local_workers_give_identical_reports(tmp_path: Path) -> None:
    one = _report(tmp_path, "one", LocalExecutor(1))
    two = _report(tmp_path, "two", LocalExecutor(2))
    assert one == two
    best_one = (tmp_path / "one" / "runs" / "hybrid-seed1" / "best.yaml").read_text()
    best_two = (tmp_path / "two" / "runs" / "hybrid-seed1" / "best.yaml").read_text()
    assert best_one == best_two


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    """A real local Ray instance of 2 CPUs, started once for this module's Ray tests."""
    ray = pytest.importorskip("ray", reason="the Ray executor needs the ray extra")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        yield
    finally:
        ray.shutdown()


@pytest.mark.slow
def test_ray_gives_the_report_of_the_local_executor(tmp_path: Path, local_ray: None) -> None:
    local = _report(tmp_path, "local", LocalExecutor(1))
    remote = _report(tmp_path, "ray", RayExecutor())
    assert remote == local
    # the runs came back whole: a run directory as the local executor writes it
    for name in ("checkpoints/gen-00002.json", "metrics.csv", "strengths.csv", "best.yaml",
                 "run.json", "heldout.json"):
        local_file = tmp_path / "local" / "runs" / "hybrid-seed0" / name
        ray_file = tmp_path / "ray" / "runs" / "hybrid-seed0" / name
        assert ray_file.is_file()
        if name == "best.yaml":
            assert ray_file.read_text() == local_file.read_text()


def test_executors_by_name() -> None:
    assert isinstance(make_executor("local"), LocalExecutor)
    assert make_executor("local", 3).workers == 3  # type: ignore[attr-defined]
    assert isinstance(make_executor("ray", address="head:6379"), RayExecutor)
    with pytest.raises(FlcError, match="unknown executor 'dask'") as info:
        make_executor("dask")
    assert "local, ray" in info.value.hint
    with pytest.raises(FlcError, match="address of a Ray cluster"):
        make_executor("local", address="head:6379")
    with pytest.raises(FlcError, match="at least 1"):
        make_executor("local", 0)


def test_missing_ray_gives_the_install_hint(tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    real_import = builtins.__import__

    def no_ray(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "ray" or name.startswith("ray."):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "ray", raising=False)
    monkeypatch.setattr(builtins, "__import__", no_ray)
    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("pitt",))
    with pytest.raises(MissingDependencyError) as info:
        experiment.run(RayExecutor())
    assert info.value.hint == "pip install 'flctool[ray]'"


def test_unpacking_refuses_files_outside_the_run(tmp_path: Path) -> None:
    for name in ("../escape.txt", "/etc/passwd", ""):
        with pytest.raises(RunDirError, match="outside its run directory"):
            unpack_run({name: b"x"}, tmp_path / "run")
    unpack_run({"checkpoints/gen-00000.json": b"{}", "heldout.json": b"{}"}, tmp_path / "run")
    assert (tmp_path / "run" / "checkpoints" / "gen-00000.json").read_bytes() == b"{}"


@pytest.mark.slow
def test_a_flctool_error_in_a_ray_worker_reads_as_locally(tmp_path: Path,
                                                          local_ray: None) -> None:
    experiment = tiny_experiment(tmp_path / "exp", seeds=1, learners=("pitt",))
    job = experiment.jobs()[0]
    # no held-out episodes: the worker's test of best.yaml refuses them with an EnvError
    damaged = job.__class__(job.learner, job.seed, job.behaviour, 0, 0)
    with pytest.raises(EnvError, match="must be at least 1, got 0"):
        RayExecutor().run([damaged], experiment.runs_dir, lambda _: None)
