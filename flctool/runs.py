"""Run directories: what ``flctool learn`` writes, and how a run is resumed or read back.

A run directory holds::

    behaviour.yaml          the resolved behaviour: the file, its seed, command-line overrides
    run.json                learner, seed, status (running / stopped / finished /
                            not_learned: no better than a baseline), best so far,
                            and the model-selection record: every validated candidate, the
                            episodes and steps of training and of selection, why it stopped
    metrics.csv             one row per generation: generation, mean, std, best, min fitness,
                            episodes, steps, wall_time (seconds), selection_episodes,
                            selection_steps, validated
    strengths.csv           learners with rule strengths: the q table after each generation,
                            one row per (generation, rule, command) -- the paper's Fig. 7
    checkpoints/gen-NNNNN.json
                            after every generation: the evaluated population and its fitness,
                            q table and traces, the state of every random generator, and the
                            generation's metrics row
    best.yaml               the run's best controller, deployable: the best validated
                            candidate (flctool.learners.selection)
    baseline.yaml           a run that ended not_learned: the baseline that did as well or
                            better (a constant command, a random table, the user's), to
                            evaluate or deploy instead

Every file is written atomically (write, then rename), checkpoints first: a run killed at any
moment loses at most the generation in progress, and ``--resume`` rebuilds metrics.csv and
strengths.csv from the checkpoints, then continues bit for bit where an uninterrupted run
would be (only the wall_time column differs).

A run directory may come from someone else: training holds a lock (``run.lock``, released by
the kernel when the process ends, however it ends), never writes through a symbolic link
inside the directory, deletes the temporary files a killed writer left, and reads checkpoints
within bounds (size, finite numbers, population, random generator states).
"""

from __future__ import annotations

import csv
import errno
import io
import json
import math
import os
import re
import time
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, fields
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np

from flctool.atomic import remove_stale_temporaries, sync_file, write_text_atomic
from flctool.behaviour import (
    Behaviour,
    behaviour_to_yaml,
    load_behaviour,
)
from flctool.behaviour.overrides import Override, resolve_behaviour
from flctool.behaviour.rules import with_rules
from flctool.dirlock import DirectoryLock, is_locked
from flctool.envs.base import BatchEnv
from flctool.errors import FlcError, LearnError, RunDirError
from flctool.learners import Callback, GenerationMetrics, Learner, make_learner, train
from flctool.learners.baselines import difference_text
from flctool.learners.checkpoint import Checkpoint, Expected, read_checkpoint
from flctool.learners.confirmation import Confirmed
from flctool.learners.metrics import Usage
from flctool.rollout import Estimate
from flctool.sets.codec import set_gene_count, with_set_genes
from flctool.version import __version__

RUN_FORMAT = 1
#: The status of a run that ended without a controller clearly better than the baselines.
NOT_LEARNED = "not_learned"
#: The statuses of a run that has run to its end (all its generations, or a budget).
ENDED = ("finished", NOT_LEARNED)
BEHAVIOUR_FILE = "behaviour.yaml"
RUN_FILE = "run.json"
METRICS_FILE = "metrics.csv"
STRENGTHS_FILE = "strengths.csv"
BEST_FILE = "best.yaml"
BASELINE_FILE = "baseline.yaml"
CHECKPOINT_DIR = "checkpoints"
LOCK_FILE = "run.lock"
#: A checkpoint larger than this is not read (the largest run flctool accepts, population x
#: rules = 20 million consequents, writes about 200 MB).
MAX_CHECKPOINT_BYTES = 1 << 30
_CHECKPOINT = re.compile(r"^gen-(\d+)\.json$")


# -- files ---------------------------------------------------------------------------------
def _metrics_text(rows: Iterable[GenerationMetrics], header: bool = True) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    if header:
        writer.writerow(GenerationMetrics.columns())
    for m in rows:
        writer.writerow([repr(v) if isinstance(v, float) else v for v in m.row().values()])
    return buffer.getvalue()


def _strengths_text(rows: Iterable[tuple[int, Any]], commands: tuple[str, ...],
                    header: bool = True) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    if header:
        writer.writerow(["generation", "rule", "command", "q"])
    for generation, table in rows:
        for rule, values in enumerate(table):
            for command, value in zip(commands, values, strict=True):
                writer.writerow([generation, rule, command, repr(float(value))])
    return buffer.getvalue()


def _write_error(path: Path, exc: OSError) -> RunDirError:
    """An OSError writing into a run directory, as one clear error."""
    if exc.errno == errno.ENOSPC or exc.errno == errno.EDQUOT:
        hint = "free some disk space, then continue with flctool learn --resume " + str(
            path.parent if path.parent.name != CHECKPOINT_DIR else path.parent.parent)
    elif exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        hint = f"make {path.parent} writable (chmod u+w), or copy the run and resume the copy"
    elif exc.errno == errno.ELOOP:
        hint = "delete the link: flctool never writes through links inside a run directory"
    else:
        hint = "check the run directory"
    return RunDirError(f"cannot write {path}: {exc.strerror or exc}", hint=hint)


def _refuse_links(root: Path, path: Path) -> None:
    """Refuse ``path`` if it, or a folder between ``root`` and it, is a symbolic link: a
    link planted in a run directory must not make flctool write outside it."""
    here = root
    for part in path.relative_to(root).parts:
        here = here / part
        if here.is_symlink():
            raise _write_error(path, OSError(errno.ELOOP, f"{here} is a symbolic link"))


def _write(root: Path, path: Path, text: str, durable: bool = True) -> None:
    """Write ``text`` atomically to ``path`` inside the run directory ``root`` (``durable``:
    fsync'd before the rename, see :func:`~flctool.atomic.write_bytes_atomic`)."""
    _refuse_links(root, path)
    try:
        write_text_atomic(path, text, durable=durable, follow_symlinks=False)
    except OSError as exc:
        raise _write_error(path, exc) from None


def _append(root: Path, path: Path, text: str) -> None:
    _refuse_links(root, path)
    try:
        fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW, 0o666)
        with os.fdopen(fd, "a", encoding="utf-8") as handle:
            handle.write(text)
    except OSError as exc:
        raise _write_error(path, exc) from None


def _best_header(provenance: Mapping[str, Any], run_name: str) -> str:
    validation = provenance.get("validation")
    measured = (f"fitness {provenance['fitness']!r} in training, validated mean fitness "
                f"{validation['value']!r} over {validation['n']} validation episodes "
                "(the best of the candidates on them: optimistic)"
                if validation else f"fitness {provenance['fitness']!r}")
    confirmation = provenance.get("confirmation")
    confirmed = (f"Confirmed on {confirmation['episodes']} fresh episodes: "
                 f"{confirmation_text(confirmation)}.\n" if confirmation else "")
    return (f"Learned by flctool {__version__} with the {provenance['learner']} learner "
            f"(seed {provenance['seed']}) in run {run_name}:\n"
            f"generation {provenance['generation']}, individual {provenance['individual']}, "
            f"{measured}.\n{confirmed}"
            "Deployable: flctool validate / evaluate / export take it as it is.")


def confirmation_text(confirmation: Mapping[str, Any]) -> str:
    """``mean fitness 1.90 [1.84, 1.95], success rate 0.96 [0.87, 0.99], mean return ...``:
    a confirmation record (:meth:`~flctool.learners.confirmation.Confirmed.record`) as
    words."""
    parts = []
    for key, label in (("mean_fitness", "mean fitness"), ("success_rate", "success rate"),
                       ("mean_return", "mean return")):
        estimate = confirmation[key]
        if estimate["value"] is None:
            continue
        interval = ("" if estimate["low"] is None
                    else f" [{estimate['low']:.3f}, {estimate['high']:.3f}]")
        parts.append(f"{label} {estimate['value']:.3f}{interval}")
    return ", ".join(parts)


def _provenance(run: Run, generation: int, individual: int, fitness: float,
                validation: Mapping[str, Any] | None,
                confirmation: Mapping[str, Any] | None = None) -> dict[str, Any]:
    return _provenance_record(run.learner, run.seed, generation, individual, fitness,
                              validation, confirmation)


def _provenance_record(learner: str, seed: int, generation: int, individual: int,
                       fitness: float, validation: Mapping[str, Any] | None,
                       confirmation: Mapping[str, Any] | None = None) -> dict[str, Any]:
    provenance = {"learner": learner, "seed": seed, "generation": generation,
                  "individual": individual, "fitness": fitness}
    if validation is not None:
        provenance["validation"] = dict(validation)
    if confirmation is not None:
        provenance["confirmation"] = dict(confirmation)
    return provenance


def _confirmation_of(confirmations: Iterable[Confirmed], consequents: Any,
                     sets: Any = None) -> dict[str, Any] | None:
    """The record of the latest confirmation of the controller ``consequents`` with the set
    genome ``sets`` (None: the file's sets), if any."""
    for confirmed in reversed(list(confirmations)):
        if confirmed.is_of(consequents, sets):
            return confirmed.record()
    return None


@dataclass(frozen=True)
class BestController:
    """Where a run's best controller (``best.yaml``) came from, and what it scored."""

    learner: str
    seed: int
    generation: int
    individual: int
    #: Its mean fitness over its training trials.
    fitness: float
    #: Its mean fitness over the run's validation episodes; None if it was not validated.
    validation: Estimate | None = None
    #: Its confirmation on fresh episodes, the figure to read (run.json's record of it:
    #: mean_fitness, success_rate, mean_return, episodes); None if it was not confirmed.
    confirmation: dict[str, Any] | None = None

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> BestController:
        """From run.json's ``best`` (:meth:`to_dict`)."""
        validation = record.get("validation")

        def number(key: str) -> float:
            value = validation[key] if validation is not None else None
            return math.nan if value is None else float(value)

        return cls(str(record["learner"]), int(record["seed"]), int(record["generation"]),
                   int(record["individual"]), float(record["fitness"]),
                   None if validation is None else Estimate(
                       number("value"), number("low"), number("high"), int(validation["n"])),
                   None if record.get("confirmation") is None
                   else dict(record["confirmation"]))

    def to_dict(self) -> dict[str, Any]:
        """As run.json records it (NaN as null)."""
        return _provenance_record(self.learner, self.seed, self.generation, self.individual,
                                  self.fitness, self.validation.to_dict()
                                  if self.validation is not None else None,
                                  self.confirmation)


@dataclass(frozen=True)
class RunSummary:
    """What a training session ended with."""

    path: Path
    learner: str
    seed: int
    generations: int  # generations completed in the run (all sessions)
    status: str
    #: The run's best controller so far; None before its first generation.
    best: BestController | None
    last: GenerationMetrics | None
    selection: dict[str, Any] | None = None  # run.json's record of model selection

    @property
    def usage(self) -> Usage | None:
        """Episodes and steps the run spent on training, selection (validation),
        confirmation and baselines; None if the run recorded none (counts a run of an
        earlier version did not record are 0)."""
        recorded = (self.selection or {}).get("usage")
        return Usage(**{f.name: int(recorded.get(f.name, 0)) for f in fields(Usage)}) \
            if recorded else None

    def to_dict(self) -> dict[str, Any]:
        usage = self.usage
        return {"run": str(self.path), "learner": self.learner, "seed": self.seed,
                "generations": self.generations, "status": self.status,
                "best": self.best.to_dict() if self.best is not None else {},
                "usage": usage.to_dict() if usage is not None else {},
                "selection": self.selection,
                "last": self.last.row() if self.last else None,
                "best_file": str(self.path / BEST_FILE)}


class Run:
    """One run directory. Make one with :func:`create_run`, open one with :func:`open_run`."""

    def __init__(self, path: Path, behaviour: Behaviour) -> None:
        self.path = path
        self.behaviour = behaviour

    @property
    def learner(self) -> str:
        return self.behaviour.learning.learner

    @property
    def seed(self) -> int:
        return self.behaviour.learning.seed

    # -- checkpoints ---------------------------------------------------------------------
    def checkpoint_generations(self) -> list[int]:
        """Generations with a checkpoint, in increasing order."""
        folder = self.path / CHECKPOINT_DIR
        if not folder.is_dir():
            return []
        found = (_CHECKPOINT.match(p.name) for p in folder.iterdir())
        return sorted(int(m.group(1)) for m in found if m)

    def checkpoint_path(self, generation: int) -> Path:
        return self.path / CHECKPOINT_DIR / f"gen-{generation:05d}.json"

    def checkpoint(self, generation: int, strengths: bool | None = None) -> dict[str, Any]:
        """The checkpoint of ``generation``, checked to be whole (by
        :func:`~flctool.learners.checkpoint.read_checkpoint`; ``strengths``: it must hold a
        q table): :class:`RunDirError` naming the file if it is missing or damaged."""
        return self._read_checkpoint(generation, strengths)[0]

    def _read_checkpoint(self, generation: int, strengths: bool | None = None,
                         ) -> tuple[dict[str, Any], Checkpoint]:
        path = self.checkpoint_path(generation)
        if path.is_symlink():
            raise self._damaged(generation, "the checkpoint is a symbolic link; flctool reads "
                                "and writes only the run directory's own files")
        try:
            size = path.stat().st_size
            if size > MAX_CHECKPOINT_BYTES:
                raise self._damaged(generation, f"the checkpoint has {size:,} bytes, more than "
                                    f"any run writes ({MAX_CHECKPOINT_BYTES:,})")
            data = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise RunDirError(f"{self.path}: no checkpoint of generation {generation}",
                              hint=self._generations_hint()) from None
        except (OSError, ValueError) as exc:
            raise self._damaged(generation, f"the checkpoint cannot be read ({exc})") from None
        except RecursionError:
            raise self._damaged(generation, "the checkpoint cannot be read (its JSON is "
                                "nested too deep)") from None
        behaviour = self.behaviour
        try:
            checkpoint = read_checkpoint(data, Expected(
                behaviour.rule_count, len(behaviour.output.commands), generation=generation,
                max_population=behaviour.learning.population, strengths=strengths,
                metrics=True, set_genes=set_gene_count(behaviour)))
        except LearnError as error:
            raise self._damaged(generation, error.args[0]) from None
        return data, checkpoint

    # -- the lock ------------------------------------------------------------------------
    @contextmanager
    def lock(self) -> Iterator[None]:
        """Hold the run's lock: :class:`RunDirError` if another process holds it (a run
        resumed while it is still training would corrupt it)."""
        path = self.path / LOCK_FILE
        _refuse_links(self.path, path)
        lock = DirectoryLock(path)
        try:
            acquired = lock.acquire()
        except OSError as exc:
            raise _write_error(path, exc) from None
        if not acquired:
            raise RunDirError(
                f"{self.path} is being trained by another flctool process"
                f"{f' (pid {lock.holder})' if lock.holder else ''}",
                hint="wait for it to finish, or stop it (Ctrl-C), then --resume")
        try:
            yield
        finally:
            lock.release()

    def is_locked(self) -> bool:
        """Whether a process (this one included) holds the run's lock now."""
        return is_locked(self.path / LOCK_FILE)

    def _damaged(self, generation: int, problem: str) -> RunDirError:
        path = self.checkpoint_path(generation)
        later = " and the checkpoints after it" if generation < max(
            self.checkpoint_generations(), default=generation) else ""
        then = (f"resume from generation {generation - 1}" if generation > 0
                else "start the run again from generation 0")
        return RunDirError(f"{path}: {problem}",
                           hint=f"delete {path}{later} to {then}")

    def last_checkpoint(self) -> dict[str, Any] | None:
        generations = self.checkpoint_generations()
        return self.checkpoint(generations[-1]) if generations else None

    def _generations_hint(self) -> str:
        done = self.checkpoint_generations()
        return (f"generations 0..{done[-1]} are recorded" if done
                else "the run has no finished generation yet")

    def metrics(self) -> list[GenerationMetrics]:
        """Every recorded generation's metrics, read from the checkpoints."""
        return [GenerationMetrics.from_row(self.checkpoint(g)["metrics"])
                for g in self.checkpoint_generations()]

    # -- controllers ---------------------------------------------------------------------
    def behaviour_for(self, generation: int | None = None,
                      individual: int | None = None) -> tuple[Behaviour, dict[str, Any]]:
        """A deployable behaviour of this run, and its provenance.

        By default the run's best controller (what best.yaml holds): the best validated
        candidate of model selection, as the last checkpoint records it (in runs without
        selection, the best individual of the last generation). ``generation`` picks another
        generation (negative counts from the end), ``individual`` an individual other than
        that generation's best. Provenance: ``{learner, seed, generation, individual,
        fitness}``, with ``validation`` ``{value, low, high, n}`` for a validated one.
        """
        done = self.checkpoint_generations()
        if not done:
            raise RunDirError(f"{self.path}: the run has no finished generation yet",
                              hint="wait for the first generation, or resume the run")
        if generation is None and individual is None:
            selected = self._selected(done[-1])
            if selected is not None:
                return selected
        if generation is None:
            generation = done[-1]
        elif generation < 0:
            generation = done[-1] + 1 + generation
        if generation not in done:
            raise RunDirError(f"{self.path}: no generation {generation} in this run",
                              hint=self._generations_hint())
        checkpoint = self._read_checkpoint(generation)[1]
        population, fitness = checkpoint.population, checkpoint.fitness
        if individual is None:
            individual = int(np.argmax(fitness))
        elif not 0 <= individual < len(population):
            raise RunDirError(f"{self.path}: generation {generation} has individuals "
                              f"0..{len(population) - 1}, not {individual}",
                              hint="pick an individual in that range")
        confirmations = checkpoint.selection.confirmations if checkpoint.selection else []
        genes = None if checkpoint.set_genes is None else checkpoint.set_genes[individual]
        provenance = _provenance(self, generation, individual, float(fitness[individual]),
                                 None, _confirmation_of(confirmations, population[individual],
                                                        genes))
        return with_rules(with_set_genes(self.behaviour, genes), population[individual]), \
            provenance

    def _selected(self, generation: int) -> tuple[Behaviour, dict[str, Any]] | None:
        """The best validated candidate recorded in checkpoint ``generation``, if any."""
        selection = self._read_checkpoint(generation)[1].selection
        candidate = selection.best if selection is not None else None
        if selection is None or candidate is None:
            return None
        behaviour = with_rules(with_set_genes(self.behaviour, candidate.sets),
                               candidate.consequents)
        validation = candidate.validation.to_dict() if candidate.validation else None
        return behaviour, _provenance(self, candidate.generation, candidate.individual,
                                      candidate.fitness, validation,
                                      _confirmation_of(selection.confirmations,
                                                       candidate.consequents, candidate.sets))

    # -- training ------------------------------------------------------------------------
    def train(self, callbacks: Iterable[Callback] = (), env: BatchEnv | None = None,
              learner: Learner | None = None) -> RunSummary:
        """Train from the last checkpoint (or from scratch) to ``learning.generations``.

        ``learner`` (made by :func:`~flctool.learners.make_learner` for this run's behaviour)
        or ``env`` replace the ones built from the behaviour. An environment built here is
        closed when training ends, however it ends (a robot over a link is sent ``stop``); a
        given one, or a given learner's, is left to its opener.
        """
        built = learner is None and env is None
        if learner is None:
            learner = make_learner(self.behaviour, env)
        try:
            with self.lock():
                for folder in (self.path, self.path / CHECKPOINT_DIR):
                    remove_stale_temporaries(folder)  # of a writer killed mid-write
                generations = self.checkpoint_generations()
                if generations:
                    try:
                        learner.load_state_dict(self.checkpoint(generations[-1]))
                    except LearnError as error:  # the run's own learner: the file is damaged
                        raise self._damaged(generations[-1], error.args[0]) from None
                train(learner, [RunRecorder(self), *callbacks])
                return self.summary()
        finally:
            if built:
                learner.env.close()

    def summary(self) -> RunSummary:
        info = self.info()
        done = self.checkpoint_generations()
        # Only the last checkpoint is read: a summary of a long run costs one file, not all.
        last = (GenerationMetrics.from_row(self.checkpoint(done[-1])["metrics"]) if done
                else None)
        best = info.get("best")
        return RunSummary(self.path, self.learner, self.seed, len(done),
                          str(info.get("status", "unknown")),
                          BestController.from_record(best) if best else None, last,
                          info.get("selection"))

    def info(self) -> dict[str, Any]:
        """run.json; a run that says 'running' but whose lock nobody holds was killed (or
        could not write its end), so it reads as 'stopped'."""
        try:
            data: Any = json.loads((self.path / RUN_FILE).read_text("utf-8"))
        except (OSError, ValueError, RecursionError):
            return {}
        if not isinstance(data, dict):
            return {}
        if data.get("status") == "running" and not self.is_locked():
            data["status"] = "stopped"
        return data

    def write_info(self, status: str, best: Mapping[str, Any] | None,
                   selection: Mapping[str, Any] | None = None, *,
                   durable: bool = True) -> None:
        """Write run.json; ``selection`` is the model-selection record (every validated
        candidate, the training and selection usage), kept from the last write if None."""
        if selection is None:
            selection = self.info().get("selection")
        info = {"format": RUN_FORMAT, "flctool": __version__, "behaviour": self.behaviour.name,
                "learner": self.learner, "seed": self.seed,
                "generations": self.behaviour.learning.generations, "status": status,
                "best": dict(best) if best else None,
                "selection": dict(selection) if selection else None}
        text = json.dumps(info, indent=2) + "\n"
        try:
            _write(self.path, self.path / RUN_FILE, text, durable=durable)
        except RunDirError:
            if status == "running":
                raise
            # A full disk has no room for a second copy, but rewriting the small file in
            # place frees its blocks first: the status must not be left 'running'.
            _refuse_links(self.path, self.path / RUN_FILE)
            try:
                fd = os.open(self.path / RUN_FILE, os.O_WRONLY | os.O_TRUNC | os.O_NOFOLLOW)
                with os.fdopen(fd, "w", encoding="utf-8") as handle:
                    handle.write(text)
            except OSError as exc:
                raise _write_error(self.path / RUN_FILE, exc) from None

    def extend(self, generations: int) -> None:
        """Raise the run's generation budget (resume then continues to it)."""
        done = self.checkpoint_generations()
        if done and generations <= done[-1]:
            raise RunDirError(f"{self.path} already has {done[-1] + 1} generations; "
                              f"--generations {generations} would not add any",
                              hint=f"give more than {done[-1] + 1}")
        budget = [Override("generations", generations, "the new generation budget")]
        extend = self.behaviour.learning.extend
        if extend is not None:  # a run that extends itself goes on doing so
            budget.append(Override("extend", extend.model_dump(exclude_none=True),
                                   "the run's own"))
        behaviour = resolve_behaviour(self.behaviour, budget)
        with self.lock():
            _write(self.path, self.path / BEHAVIOUR_FILE, _behaviour_text(behaviour))
        self.behaviour = behaviour


def _behaviour_text(behaviour: Behaviour) -> str:
    return behaviour_to_yaml(behaviour, (
        f"Resolved by flctool learn {__version__}: the behaviour file with its seed and any "
        "command-line overrides.\nflctool learn --resume continues from it."))


# How often best.yaml and run.json are rewritten during a run, and the data reaches the disk.
SNAPSHOT_SECONDS = 1.0


def _fsync(path: Path) -> None:
    try:
        sync_file(path, follow_symlinks=False)
    except OSError as exc:
        raise _write_error(path, exc) from None


class RunRecorder(Callback):
    """Writes checkpoints, metrics, strengths and best.yaml as training goes.

    The bookkeeping policy (docs/performance.md, "Learning and memory"): every generation's
    checkpoint is written atomically as soon as the generation ends, and its rows appended
    to metrics.csv / strengths.csv, so a killed process loses at most the generation in
    progress (the kernel keeps what was written; resume rebuilds the tables from the
    checkpoints). best.yaml and run.json, which the checkpoints determine, are rewritten at
    most every ``SNAPSHOT_SECONDS`` (wall clock) and when training ends, however it ends;
    only then are the checkpoint, best.yaml and run.json fsync'd, so a power loss or an
    operating-system crash loses at most the generations of the last
    ``SNAPSHOT_SECONDS``.
    """

    def __init__(self, run: Run) -> None:
        self.run = run
        self.best: dict[str, Any] | None = None
        self._snapshot_at = time.monotonic()
        self._unsynced: Path | None = None  # the last checkpoint, if written without fsync
        self._recorded = False  # whether this session recorded a generation

    def on_start(self, learner: Learner) -> None:
        super().on_start(learner)
        run = self.run
        done = [g for g in run.checkpoint_generations() if g <= learner.generation]
        # Rebuild the tables from the checkpoints: a kill may have left rows of a generation
        # whose checkpoint never made it, or missed rows whose checkpoint did.
        states = [run.checkpoint(g, strengths=learner.uses_strengths) for g in done]
        # Derived from the checkpoints (and rebuilt from them here), so never fsync'd.
        _write(run.path, run.path / METRICS_FILE, _metrics_text(
            GenerationMetrics.from_row(s["metrics"]) for s in states), durable=False)
        if learner.uses_strengths:
            _write(run.path, run.path / STRENGTHS_FILE, _strengths_text(
                ((s["generation"], s["q"]) for s in states),
                learner.controller.command_names), durable=False)
        run.write_info("running", run.info().get("best"), durable=False)
        self._snapshot_at = time.monotonic()

    def on_generation(self, metrics: GenerationMetrics) -> bool:
        learner = self.learner
        if learner is None:
            raise FlcError("the run recorder was not started")
        run = self.run
        state = learner.state_dict()
        state["metrics"] = metrics.row()
        now = time.monotonic()
        snapshot = now - self._snapshot_at >= SNAPSHOT_SECONDS
        checkpoint = run.checkpoint_path(metrics.generation)
        _write(run.path, checkpoint, json.dumps(state) + "\n", durable=snapshot)
        self._unsynced = None if snapshot else checkpoint
        self._recorded = True
        _append(run.path, run.path / METRICS_FILE, _metrics_text([metrics], header=False))
        strengths = learner.strengths()
        if strengths is not None:
            _append(run.path, run.path / STRENGTHS_FILE, _strengths_text(
                [(metrics.generation, strengths.tolist())], learner.controller.command_names,
                header=False))
        if snapshot:  # else on_end or a later generation writes them (SNAPSHOT_SECONDS)
            self._snapshot_at = now
            # as Run.behaviour_for picks it
            generation, individual, consequents, fitness, candidate = learner.selected()
            validation = (candidate.validation.to_dict()
                          if candidate is not None and candidate.validation else None)
            learned_sets = learner.selected_sets()
            learned = with_set_genes(run.behaviour, learned_sets)
            self._write_best(with_rules(learned, consequents),
                             _provenance(run, generation, individual, fitness, validation,
                                         _confirmation_of(learner.confirmation.confirmed,
                                                          consequents, learned_sets)))
            run.write_info("running", self.best, learner.selection_record())
        return True

    def _write_best(self, behaviour: Behaviour, provenance: dict[str, Any]) -> None:
        _write(self.run.path, self.run.path / BEST_FILE, behaviour_to_yaml(
            behaviour, _best_header(provenance, self.run.path.name)))
        self.best = provenance

    def on_end(self) -> None:
        learner = self.learner
        finished = learner is not None and learner.finished
        written = False  # whether best.yaml and the last checkpoint are on disk
        try:
            # The checkpoints are the record: a stop between a checkpoint and best.yaml
            # (Ctrl-C, an error) still leaves best.yaml and run.json naming the last
            # checkpoint's best.
            if self.run.checkpoint_generations():
                try:
                    behaviour, provenance = self.run.behaviour_for()
                except FlcError:
                    pass  # a damaged checkpoint: report what the run knew, not a second error
                else:
                    if provenance != self.best:
                        self._write_best(behaviour, provenance)
            if self._unsynced is not None:
                _fsync(self._unsynced)  # the last checkpoint (see the policy above)
            written = True
        finally:
            # however the above ends (a full disk fails best.yaml first): never 'running'
            selection = None  # kept from run.json, unless this session recorded generations
            if learner is not None and self._recorded:
                selection = learner.selection_record()
            # a run whose best.yaml could not be written is not finished: resume writes it
            status = "finished" if finished and written else "stopped"
            if status == "finished" and learner is not None and learner.learned is False:
                status = NOT_LEARNED  # no better than a baseline (flctool.learners.baselines)
            self.run.write_info(status, self.best or self.run.info().get("best"), selection)
            if learner is not None and status in ENDED:  # after the status: it is the record
                self._write_baseline(learner, status == NOT_LEARNED)

    def _write_baseline(self, learner: Learner, not_learned: bool) -> None:
        """baseline.yaml: the baseline a run that did not learn was no better than, as a
        deployable file; a run that (resumed) learned after all has none."""
        path = self.run.path / BASELINE_FILE
        verdict = learner.baseline_check.verdict
        if not not_learned or verdict is None:
            if path.is_file() and not path.is_symlink():
                path.unlink()
            return
        genes = dict(learner.baseline_check.baselines(learner))[verdict.baseline]
        header = (f"The baseline '{verdict.baseline}' of run {self.run.path.name} (flctool "
                  f"{__version__}):\nmean fitness {verdict.baseline_fitness!r} on the run's "
                  f"{verdict.difference.n} confirmation episodes; the learned controller "
                  f"(best.yaml) minus it: {difference_text(verdict.difference.to_dict())},\n"
                  "so the run ended not_learned.\nDeployable: flctool validate / evaluate / "
                  "export take it as it is.")
        _write(self.run.path, path, behaviour_to_yaml(with_rules(self.run.behaviour, genes),
                                                      header))


# -- creating and opening runs ------------------------------------------------------------
def default_run_dir(behaviour: Behaviour, root: Path = Path("runs")) -> Path:
    """``runs/<name>-<learner>-seed<S>-<YYYYmmdd-HHMMSS>`` (with a suffix if taken)."""
    stamp = datetime.now().strftime("%Y%m%d-%H%M%S")
    learning = behaviour.learning
    base = root / f"{behaviour.name}-{learning.learner}-seed{learning.seed}-{stamp}"
    path, n = base, 1
    while path.exists():
        n += 1
        path = base.with_name(f"{base.name}-{n}")
    return path


def create_run(behaviour: Behaviour, out: Path | None = None) -> Run:
    """A new run directory for ``behaviour`` (resolved: seed and overrides applied)."""
    if behaviour.environment is None:
        raise RunDirError(f"behaviour '{behaviour.name}' has no 'environment' section, so "
                          "there is nothing to learn in",
                          hint="add e.g. 'environment: {adapter: ballchase-sim}'")
    path = Path(out) if out is not None else default_run_dir(behaviour)
    if path.exists() and not path.is_dir():
        raise RunDirError(f"{path} exists and is not a directory",
                          hint="choose another --out")
    if path.is_dir() and any(path.iterdir()):
        raise RunDirError(f"{path} is not empty",
                          hint=f"resume it with --resume {path}, or choose another --out")
    try:
        (path / CHECKPOINT_DIR).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RunDirError(f"cannot create the run directory {path}: {exc.strerror}",
                          hint="choose another --out") from None
    run = Run(path, behaviour)
    _write(path, path / BEHAVIOUR_FILE, _behaviour_text(behaviour))
    run.write_info("created", None, durable=False)
    return run


def open_run(path: str | Path) -> Run:
    """An existing run directory; raises :class:`RunDirError` if it is not one."""
    path = Path(path)
    if not path.is_dir():
        raise RunDirError(f"{path}: no such run directory",
                          hint="give the directory flctool learn wrote (see its --out)")
    for name in (BEHAVIOUR_FILE, RUN_FILE, BEST_FILE, CHECKPOINT_DIR):
        if (path / name).is_symlink():  # reads, like writes, stay inside the directory
            raise RunDirError(f"{path / name} is a symbolic link; flctool reads and writes "
                              "only the run directory's own files",
                              hint="replace the link with the file itself, or resume a copy "
                              "of the run")
    if not (path / BEHAVIOUR_FILE).is_file():
        raise RunDirError(f"{path} is not a run directory: it has no {BEHAVIOUR_FILE}",
                          hint="give the directory flctool learn wrote (see its --out)")
    run = Run(path, load_behaviour(path / BEHAVIOUR_FILE))
    _check_record(run)
    return run


def _check_record(run: Run) -> None:
    """Refuse a run.json that does not describe the run: another format, or a learner or
    seed other than behaviour.yaml's (an edited record would otherwise be ignored, or
    trusted)."""
    path = run.path / RUN_FILE
    try:
        record: Any = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return  # a run killed inside create_run: behaviour.yaml is the record
    except (OSError, ValueError, RecursionError) as exc:
        raise RunDirError(f"{path} cannot be read ({exc})",
                          hint=f"restore it, or delete it: flctool rebuilds it from "
                          f"{BEHAVIOUR_FILE} and the checkpoints") from None
    if not isinstance(record, dict):
        raise RunDirError(f"{path} holds no run record (a {type(record).__name__})",
                          hint=f"delete it: flctool rebuilds it from {BEHAVIOUR_FILE} and the "
                          "checkpoints")
    version = record.get("format")
    if version != RUN_FORMAT:
        newer = isinstance(version, int) and not isinstance(version, bool) and \
            version > RUN_FORMAT
        raise RunDirError(f"{path} has format {version!r}; this flctool reads run "
                          f"directories of format {RUN_FORMAT}",
                          hint="upgrade flctool: pip install --upgrade flctool" if newer
                          else f"restore the file, or delete it: flctool rebuilds it from "
                          f"{BEHAVIOUR_FILE} and the checkpoints")
    for key, recorded in (("learner", run.learner), ("seed", run.seed)):
        if key in record and record[key] != recorded:
            raise RunDirError(f"{path} records {key} {record[key]!r}, but the run's "
                              f"{BEHAVIOUR_FILE} has {recorded!r}: the record was edited",
                              hint=f"restore it, or delete it: flctool rebuilds it from "
                              f"{BEHAVIOUR_FILE} and the checkpoints")
