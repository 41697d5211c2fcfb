"""Executors, chosen by name: ``local`` (processes on this machine) and ``ray`` (a Ray cluster,
or a Ray instance started here).

Both run :func:`flctool.experiment.runner.run_job`, so a job gives the same files whichever
runs it. The local executor writes each run directly into the experiment directory (an
interrupted run resumes from its last checkpoint). A Ray worker may be on another machine
without the experiment directory, so it trains in a temporary folder and sends the run
directory's files back; the driver writes them into the experiment directory (an interrupted
run is started again, which gives the same result, since runs are deterministic).
"""

from __future__ import annotations

import logging
import multiprocessing
import tempfile
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path, PurePosixPath
from typing import Any

from flctool.atomic import write_bytes_atomic
from flctool.errors import FlcError, MissingDependencyError, RunDirError
from flctool.experiment.runner import HELDOUT_FILE, Executor, Job, JobOutcome, run_job

EXECUTOR_NAMES = ("local", "ray")


def make_executor(name: str, workers: int | None = None, address: str | None = None,
                  ) -> Executor:
    """The executor called ``name``; ``workers`` processes (local: default 1; ray: default
    all the CPUs Ray sees), ``address`` of a running Ray cluster (``HOST:PORT``, ray only)."""
    if workers is not None and workers < 1:
        raise FlcError(f"--workers must be at least 1, got {workers}")
    if name == "local":
        if address is not None:
            raise FlcError("--address is the address of a Ray cluster",
                           hint="add --executor ray, or leave out --address")
        return LocalExecutor(workers or 1)
    if name == "ray":
        return RayExecutor(workers, address)
    raise FlcError(f"unknown executor '{name}'", hint=f"use one of: {', '.join(EXECUTOR_NAMES)}")


class LocalExecutor(Executor):
    """``workers`` processes on this machine; with one, jobs run in this process."""

    def __init__(self, workers: int = 1) -> None:
        self.workers = workers

    def run(self, jobs: Sequence[Job], root: Path,
            on_done: Callable[[JobOutcome], None]) -> None:
        if self.workers == 1 or len(jobs) <= 1:
            for job in jobs:
                on_done(run_job(job, root / job.name))
            return
        # spawn: a fresh interpreter per worker, the same on every platform (fork would copy
        # whatever threads the parent holds).
        context = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(min(self.workers, len(jobs)), mp_context=context) as pool:
            pending: set[Future[JobOutcome]] = {
                pool.submit(run_job, job, root / job.name) for job in jobs}
            try:
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for future in done:
                        on_done(future.result())
            except BaseException:
                for future in pending:
                    future.cancel()
                raise


# -- Ray ----------------------------------------------------------------------------------
def _ray() -> Any:
    try:
        import ray
    except ImportError:
        raise MissingDependencyError("ray", "ray", "The Ray executor") from None
    return ray


def run_job_packed(job: Job) -> tuple[JobOutcome, dict[str, bytes]]:
    """Run ``job`` in a temporary folder; its outcome and run directory as {relative path:
    bytes} (what a Ray worker sends back)."""
    with tempfile.TemporaryDirectory(prefix="flctool-") as folder:
        directory = Path(folder) / job.name
        outcome = run_job(job, directory)
        files = {path.relative_to(directory).as_posix(): path.read_bytes()
                 for path in sorted(directory.rglob("*")) if path.is_file()}
    return outcome, files


def unpack_run(files: dict[str, bytes], directory: Path) -> None:
    """Write a run directory sent back by :func:`run_job_packed` into ``directory``; the
    held-out result last, since it marks the job finished."""
    def order(name: str) -> tuple[bool, str]:
        return name == HELDOUT_FILE, name

    for name in sorted(files, key=order):
        relative = PurePosixPath(name)
        if relative.is_absolute() or ".." in relative.parts or not relative.parts:
            raise RunDirError(f"a worker sent a file outside its run directory: {name!r}",
                              hint="check that every Ray worker runs this flctool version")
        target = directory.joinpath(*relative.parts)
        target.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(target, files[name])


class RayExecutor(Executor):
    """Jobs as Ray tasks, one CPU each. Uses the Ray instance this process is connected to, or
    connects to ``address``, or starts a local one with ``workers`` CPUs."""

    def __init__(self, workers: int | None = None, address: str | None = None) -> None:
        self.workers = workers
        self.address = address

    def run(self, jobs: Sequence[Job], root: Path,
            on_done: Callable[[JobOutcome], None]) -> None:
        ray = _ray()
        if not jobs:
            return
        started = False
        if not ray.is_initialized():
            options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                       "logging_level": logging.WARNING}
            if self.address is not None:
                options["address"] = self.address
            elif self.workers is not None:
                options["num_cpus"] = self.workers
            try:
                ray.init(**options)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                raise FlcError(f"cannot start or reach Ray ({exc})",
                               hint="check --address HOST:PORT (the head's 'ray start "
                               "--head' prints it)") from None
            started = True
        try:
            task = ray.remote(num_cpus=1, max_retries=1)(run_job_packed)
            pending = {task.remote(job): job for job in jobs}
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1)
                for ref in done:
                    job = pending.pop(ref)
                    try:
                        outcome, files = ray.get(ref)
                    except ray.exceptions.RayTaskError as error:
                        # a flctool error in a worker reads as it would have locally
                        cause = getattr(error, "cause", None)
                        if isinstance(cause, FlcError):
                            raise cause from None
                        raise
                    unpack_run(files, root / job.name)
                    on_done(outcome)
        finally:
            if started:
                ray.shutdown()
