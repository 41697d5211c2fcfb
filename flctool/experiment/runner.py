"""An experiment: every learner on every seed, each run's best controller tested on a common
held-out set.

An experiment directory holds::

    experiment.json     the plan: learners, seeds, held-out episodes and seed, overrides
    experiment.lock     held while a process runs the experiment (see flctool.dirlock)
    behaviour.yaml      the resolved behaviour every run starts from (the file plus --set);
                        its learning: may carry the keys of every compared learner
                        (:mod:`flctool.experiment.behaviour`)
    runs/<learner>-seed<S>/
                        one run directory per (learner, seed), as ``flctool learn`` writes it,
                        plus heldout.json: the held-out evaluation of its best.yaml
    summary.json, report.md, figures
                        written by :mod:`flctool.experiment.report` from the run directories

A job is one (learner, seed). It is finished when its run is finished and heldout.json is
written; a killed experiment started again skips finished jobs and resumes unfinished runs from
their last checkpoint (bit for bit, see :mod:`flctool.runs`), so nothing finished is redone.
Every job depends on its learner, seed and behaviour alone, so the results do not depend on
the executor, the number of workers or the order in which jobs finish.
"""

from __future__ import annotations

import json
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flctool.atomic import remove_stale_temporaries, write_text_atomic
from flctool.behaviour import Behaviour, load_behaviour
from flctool.behaviour.overrides import resolve_behaviour
from flctool.dirlock import DirectoryLock
from flctool.errors import RunDirError
from flctool.evaluation import evaluate_behaviour
from flctool.experiment.behaviour import (
    ExperimentBehaviour,
    read_experiment_behaviour,
    share_behaviour,
)
from flctool.plugins import names as plugin_names
from flctool.runs import (
    BEHAVIOUR_FILE,
    BEST_FILE,
    CHECKPOINT_DIR,
    ENDED,
    Run,
    create_run,
    open_run,
)
from flctool.version import __version__

EXPERIMENT_FORMAT = 1
PLAN_FILE = "experiment.json"
RUNS_DIR = "runs"
HELDOUT_FILE = "heldout.json"
LOCK_FILE = "experiment.lock"
#: Default seed of the held-out episodes: ``flctool evaluate best.yaml --seed 0`` draws the same.
HELDOUT_SEED = 0
HELDOUT_EPISODES = 500


@dataclass(frozen=True)
class ExperimentPlan:
    """What an experiment runs: every learner on seeds ``0..seeds-1``, and how each run's
    best controller is tested (``heldout_episodes`` episodes drawn from ``heldout_seed`` by
    :func:`flctool.rollout.evaluation_seeds`, the seeds ``flctool evaluate`` uses, which never
    overlap training's)."""

    behaviour: str
    learners: tuple[str, ...]
    seeds: int
    heldout_episodes: int = HELDOUT_EPISODES
    heldout_seed: int = HELDOUT_SEED
    overrides: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"format": EXPERIMENT_FORMAT, "behaviour": self.behaviour,
                "learners": list(self.learners), "seeds": self.seeds,
                "heldout_episodes": self.heldout_episodes, "heldout_seed": self.heldout_seed,
                "overrides": dict(self.overrides)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ExperimentPlan:
        return cls(str(data["behaviour"]), tuple(str(x) for x in data["learners"]),
                   int(data["seeds"]), int(data["heldout_episodes"]),
                   int(data["heldout_seed"]), dict(data.get("overrides") or {}))


@dataclass(frozen=True)
class Job:
    """One run of the experiment: ``behaviour`` is resolved (its learner and seed set)."""

    learner: str
    seed: int
    behaviour: Behaviour
    heldout_episodes: int
    heldout_seed: int

    @property
    def name(self) -> str:
        """The run directory's name under ``runs/``."""
        return run_name(self.learner, self.seed)


@dataclass(frozen=True)
class JobOutcome:
    """What a finished job reports to the progress display."""

    learner: str
    seed: int
    heldout_success: float
    skipped: bool  # finished before this session: nothing was run


def run_name(learner: str, seed: int) -> str:
    return f"{learner}-seed{seed}"


def parse_learners(text: str) -> tuple[str, ...]:
    """``"pitt,hybrid"`` -> ``("pitt", "hybrid")``: known names, each once."""
    known = plugin_names("learner")
    names = tuple(part.strip() for part in text.split(",") if part.strip())
    if not names:
        raise RunDirError("--learners names no learner",
                          hint=f"give a comma-separated list of {', '.join(known)}")
    unknown = [n for n in names if n not in known]
    if unknown:
        raise RunDirError(f"unknown learner(s) in --learners: {', '.join(unknown)}",
                          hint=f"use {', '.join(known)}")
    if len(set(names)) != len(names):
        raise RunDirError(f"--learners names a learner twice: {text}",
                          hint="give each learner once")
    return names


# -- one job ------------------------------------------------------------------------------
def run_job(job: Job, directory: Path) -> JobOutcome:
    """Train (or resume) the job's run in ``directory`` and test its best controller on the
    held-out episodes; a job already finished there is only read back."""
    heldout_path = directory / HELDOUT_FILE
    if (directory / BEHAVIOUR_FILE).is_file():
        run = open_run(directory)
    else:
        _clear_unstarted(directory)
        run = create_run(job.behaviour, directory)
    if heldout_path.is_file() and run.info().get("status") in ENDED:
        return JobOutcome(job.learner, job.seed, read_heldout(directory)["success_rate"], True)
    if run.info().get("status") not in ENDED:
        run.train()
    result = heldout_evaluation(run, job.heldout_seed, job.heldout_episodes)
    write_text_atomic(heldout_path, json.dumps(result, indent=2) + "\n")
    return JobOutcome(job.learner, job.seed, result["success_rate"], False)


def _clear_unstarted(directory: Path) -> None:
    """Remove what a kill inside :func:`create_run` leaves (an empty checkpoints folder, a
    temporary file) so the run can be created; anything else stays, and create_run refuses
    the folder with its own message."""
    if not directory.is_dir():
        return
    remove_stale_temporaries(directory)  # no writer runs there: the job is not started
    checkpoints = directory / CHECKPOINT_DIR
    if checkpoints.is_dir() and not checkpoints.is_symlink() and not any(checkpoints.iterdir()):
        checkpoints.rmdir()


def heldout_evaluation(run: Run, seed: int, episodes: int) -> dict[str, Any]:
    """The run's best.yaml on ``episodes`` held-out episodes drawn from ``seed``: success
    count and rate, mean fitness, and the episodes and steps the test cost."""
    # what `flctool evaluate --seed SEED --episodes EPISODES` reports
    result = evaluate_behaviour(load_behaviour(run.path / BEST_FILE), seed=seed,
                                episodes=episodes).result
    return {"seed": seed, "episodes": result.episodes,
            "successes": int(result.success.sum()),
            "success_rate": float(result.success.mean()),
            "mean_fitness": float(result.fitness.mean()),
            "steps": int(result.lengths.sum())}


def read_heldout(directory: Path) -> dict[str, Any]:
    path = directory / HELDOUT_FILE
    try:
        data: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
        float(data["success_rate"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise RunDirError(f"{path} cannot be read ({exc})",
                          hint=f"delete {path}; the experiment then tests that run again"
                          ) from None
    return data


# -- the experiment -----------------------------------------------------------------------
class Experiment:
    """An experiment directory. Make one with :func:`prepare_experiment`, open one with
    :func:`open_experiment`."""

    def __init__(self, path: Path, plan: ExperimentPlan, behaviour: ExperimentBehaviour,
                 ) -> None:
        self.path = path
        self.plan = plan
        self.behaviour = behaviour

    @property
    def runs_dir(self) -> Path:
        return self.path / RUNS_DIR

    def jobs(self) -> list[Job]:
        """Every (learner, seed), learners in the plan's order, then seeds."""
        return [Job(learner, seed, resolve_behaviour(self.behaviour.of(learner),
                                                     {"seed": seed}),
                    self.plan.heldout_episodes, self.plan.heldout_seed)
                for learner in self.plan.learners for seed in range(self.plan.seeds)]

    def is_finished(self, job: Job) -> bool:
        directory = self.runs_dir / job.name
        if not (directory / HELDOUT_FILE).is_file():
            return False
        try:
            info = json.loads((directory / "run.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return False
        return isinstance(info, dict) and info.get("status") in ENDED

    def run(self, executor: Executor, on_done: Callable[[JobOutcome], None] = lambda _: None,
            ) -> list[JobOutcome]:
        """Run every unfinished job with ``executor``; finished ones are reported as skipped.
        Returns the outcomes in job order. Holds the experiment's lock meanwhile: two
        processes running one experiment would both run its unfinished jobs."""
        lock = DirectoryLock(self.path / LOCK_FILE)
        try:
            acquired = lock.acquire()
        except OSError as exc:
            raise RunDirError(f"cannot lock {self.path / LOCK_FILE}: {exc.strerror or exc}",
                              hint="the lock file must be a plain file (not a link) in a "
                              "writable folder") from None
        if not acquired:
            raise RunDirError(
                f"{self.path} is being run by another flctool process"
                f"{f' (pid {lock.holder})' if lock.holder else ''}",
                hint="wait for it to finish, or stop it (Ctrl-C), then run the same command "
                "again to continue")
        try:
            return self._run(executor, on_done)
        finally:
            lock.release()

    def _run(self, executor: Executor, on_done: Callable[[JobOutcome], None],
             ) -> list[JobOutcome]:
        jobs = self.jobs()
        outcomes: dict[str, JobOutcome] = {}
        todo = []
        for job in jobs:
            if self.is_finished(job):
                heldout = read_heldout(self.runs_dir / job.name)
                outcomes[job.name] = JobOutcome(job.learner, job.seed,
                                                float(heldout["success_rate"]), True)
                on_done(outcomes[job.name])
            else:
                todo.append(job)

        def record(outcome: JobOutcome) -> None:
            outcomes[run_name(outcome.learner, outcome.seed)] = outcome
            on_done(outcome)

        self.runs_dir.mkdir(parents=True, exist_ok=True)
        executor.run(todo, self.runs_dir, record)
        return [outcomes[job.name] for job in jobs]

    def run_dirs(self) -> list[tuple[str, int, Path]]:
        """(learner, seed, run directory) of every job, in job order."""
        return [(learner, seed, self.runs_dir / run_name(learner, seed))
                for learner in self.plan.learners for seed in range(self.plan.seeds)]


class Executor(ABC):
    """Runs jobs and reports each outcome as it arrives; the implementations are in
    :mod:`flctool.experiment.executors`."""

    @abstractmethod
    def run(self, jobs: Sequence[Job], root: Path,
            on_done: Callable[[JobOutcome], None]) -> None:
        """Run every job, job ``j`` in ``root / j.name``, calling ``on_done`` as each ends."""


def prepare_experiment(behaviour: Behaviour | ExperimentBehaviour, plan: ExperimentPlan,
                       path: Path) -> Experiment:
    """A new experiment directory, or the existing one at ``path`` if it holds the same plan
    (then running it continues where it stopped). ``behaviour`` is read for the plan's
    learners (:func:`~flctool.experiment.behaviour.read_experiment_behaviour`), or is one
    behaviour whose learning keys serve every learner that reads them."""
    if isinstance(behaviour, Behaviour):
        behaviour = share_behaviour(behaviour, plan.learners)
    elif behaviour.learners != plan.learners:
        raise ValueError(f"the behaviour was read for the learners {behaviour.learners}, "
                         f"the plan compares {plan.learners}")
    if any(b.learning.stop.seconds is not None for b in behaviour.behaviours.values()):
        raise RunDirError("learning.stop.seconds: a time budget ends runs at different points "
                          "on different machines, so the experiment would not reproduce",
                          hint="budget episodes or steps instead (stop.episodes, stop.steps)")
    plan_file = path / PLAN_FILE
    if plan_file.is_file():
        existing = open_experiment(path)
        # the same plan: the same options, and each learner's runs start from the same
        # behaviour (however the directory's behaviour.yaml writes it)
        if existing.plan != plan or existing.behaviour != behaviour:
            differs = [key for key, value in plan.to_dict().items()
                       if existing.plan.to_dict().get(key) != value]
            if existing.plan.learners == plan.learners and existing.behaviour != behaviour:
                differs.append("the behaviour")
            raise RunDirError(f"{path} holds an experiment with a different plan (it differs "
                              f"in: {', '.join(differs)})",
                              hint="give the same file and options to continue it, or another "
                              "--out for a new experiment")
        return existing
    if path.exists() and (not path.is_dir() or any(path.iterdir())):
        raise RunDirError(f"{path} exists and is not an experiment directory",
                          hint="choose another --out")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RunDirError(f"cannot create the experiment directory {path}: {exc.strerror}",
                          hint="choose another --out") from None
    write_text_atomic(path / BEHAVIOUR_FILE, _behaviour_text(behaviour))
    write_text_atomic(plan_file, json.dumps(plan.to_dict(), indent=2) + "\n")
    return Experiment(path, plan, behaviour)


def open_experiment(path: str | Path) -> Experiment:
    """An existing experiment directory; :class:`RunDirError` if it is not one."""
    path = Path(path)
    plan_file = path / PLAN_FILE
    if not plan_file.is_file():
        raise RunDirError(f"{path} is not an experiment directory: it has no {PLAN_FILE}",
                          hint="give the directory flctool experiment wrote (see its --out)")
    try:
        plan = ExperimentPlan.from_dict(json.loads(plan_file.read_text(encoding="utf-8")))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise RunDirError(f"{plan_file} cannot be read ({exc})",
                          hint="start the experiment again in another --out") from None
    return Experiment(path, plan, read_experiment_behaviour(path / BEHAVIOUR_FILE,
                                                            plan.learners))


def is_experiment(path: Path) -> bool:
    return (path / PLAN_FILE).is_file()


def _behaviour_text(behaviour: ExperimentBehaviour) -> str:
    return behaviour.to_yaml(
        f"Resolved by flctool experiment {__version__}: the behaviour file with any "
        "command-line overrides;\nevery run starts from it with its own learner and seed, "
        "keeping the learning keys its learner reads.")
