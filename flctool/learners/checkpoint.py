"""A learner's checkpoint: what it holds, and the one place it is validated.

A checkpoint is everything a learner needs to continue bit for bit after a generation (what
:meth:`~flctool.learners.base.Learner.state_dict` returns; a run directory writes one per
generation, with that generation's metrics, as ``checkpoints/gen-NNNNN.json``). A file may
be damaged (a disk fault, an edit) or hostile, so :func:`read_checkpoint` checks every field
before anything uses it -- types, shapes, command indices, finite numbers, random generator
states that can be restored, a selection record of this behaviour's controllers -- and
returns a :class:`Checkpoint`, or raises one :class:`~flctool.errors.LearnError` that says
what is wrong. Run directories (:mod:`flctool.runs`) and learners both read through it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.errors import LearnError
from flctool.learners.baselines import Verdict
from flctool.learners.confirmation import Confirmed
from flctool.learners.metrics import GenerationMetrics, Usage
from flctool.learners.selection import Candidate

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

#: The learner's random generators, each with its state in every checkpoint.
STREAMS = ("ga", "env", "explore")
#: What every checkpoint holds; learners with rule strengths add "q" and "traces", run
#: directories add "metrics", and runs with model selection "selection".
REQUIRED = ("learner", "generation", "elapsed", "population", "fitness", "rng")
DAMAGED_HINT = ("delete the damaged checkpoint (and any later ones) to resume from the one "
                "before")
#: The counts of a checkpoint's usage record (it may also hold their totals).
USAGE_FIELDS = tuple(f.name for f in fields(Usage))
#: Random generator states hold 128-bit integers (PCG64); anything larger is tampering.
_MAX_RNG_INT = 1 << 128
#: No run reaches this many generations (-1: before the first).
_MAX_GENERATION = 1 << 31


@dataclass(frozen=True)
class Expected:
    """What the reader knows a checkpoint must match."""

    n_rules: int
    n_commands: int
    learner: str | None = None  # the learner it must be of
    generation: int | None = None  # the generation its file is named after
    max_population: int | None = None  # the run's population size
    #: True: it must hold the q table and traces; None: it may (then they are checked).
    strengths: bool | None = None
    metrics: bool = False  # a run directory's checkpoint holds its generation's metrics
    #: The set genes per controller (``learning.sets``): each must then hold that many.
    set_genes: int = 0


@dataclass(frozen=True)
class SelectionState:
    """The run callbacks' record: model selection's (:class:`~flctool.learners.selection.
    ModelSelection`) and the budget's (:class:`~flctool.learners.budget.Budget`), kept in one
    ``selection`` object as the runs of earlier versions wrote it."""

    hall: list[Candidate]
    best: Candidate | None
    usage: Usage
    stop_reason: str | None
    finalized: bool
    validated: list[dict[str, Any]]
    confirmations: list[Confirmed] = field(default_factory=list)  # none before confirmation
    #: Hand-made baseline tables (name, consequents (M,)) and the end-of-run verdict.
    baselines: list[tuple[str, IntArray]] = field(default_factory=list)
    verdict: Verdict | None = None
    #: Whether candidates race when the run ends (False: a version without races wrote
    #: it), and the last race's rounds.
    racing: bool = False
    race: list[dict[str, Any]] = field(default_factory=list)
    #: The extension's count (best figure, generation it improved at); None: a run without
    #: an extension, or of a version without them.
    extension: dict[str, Any] | None = None


@dataclass(frozen=True)
class Checkpoint:
    """A checkpoint that passed :func:`read_checkpoint`."""

    learner: str
    generation: int
    elapsed: float
    population: IntArray  # (P, M) command indices
    fitness: FloatArray  # (P,), finite
    rng: dict[str, dict[str, Any]]  # stream -> a state its generator accepts
    selection: SelectionState | None
    q: FloatArray | None = None  # (M, K), finite
    traces: FloatArray | None = None  # (M, K), finite
    metrics: GenerationMetrics | None = None
    set_genes: FloatArray | None = None  # (P, G) in [-1, 1], when the run learns the sets


def damaged(problem: str, hint: str = DAMAGED_HINT) -> LearnError:
    """The error for a checkpoint that cannot be used: "the checkpoint <problem>" (or
    "the checkpoint's ..." for a problem starting with "'s")."""
    space = "" if problem.startswith("'s ") else " "
    return LearnError(f"the checkpoint{space}{problem}", hint=hint)


def read_checkpoint(data: Any, expected: Expected) -> Checkpoint:
    """``data`` (parsed JSON) as a :class:`Checkpoint`, or a :class:`LearnError` naming the
    first problem."""
    if not isinstance(data, dict):
        raise damaged(f"holds a JSON {type(data).__name__}, not an object")
    required = REQUIRED + (("metrics",) if expected.metrics else ())
    missing = [key for key in required if key not in data]
    if missing:
        raise damaged(f"has no {', '.join(repr(key) for key in missing)}")
    learner = data["learner"]
    if expected.learner is not None and learner != expected.learner:
        raise damaged(f"is of learner '{learner}', not '{expected.learner}'",
                      hint="resume with the learner the run was started with")
    if not isinstance(learner, str):
        raise damaged("is damaged: its 'learner' is not a name")
    generation = data["generation"]
    if not _is_int(generation) or not -1 <= generation < _MAX_GENERATION:
        raise damaged("is damaged: its 'generation' is not a generation number")
    if expected.generation is not None and generation != expected.generation:
        raise damaged(f"is of generation {generation!r}, not {expected.generation}")
    elapsed = data["elapsed"]
    if not (isinstance(elapsed, (int, float)) and not isinstance(elapsed, bool)
            and math.isfinite(elapsed)):
        raise damaged("is damaged: its 'elapsed' is not a finite number")
    metrics = _metrics(data, generation) if expected.metrics else None
    population = _array(data["population"], "population", "iu").astype(np.intp)
    fitness = _finite(data["fitness"], "fitness")
    _check_population(population, fitness, expected)
    q, traces = (_strengths(data, key, expected) for key in ("q", "traces"))
    return Checkpoint(learner, generation, float(elapsed), population, fitness,
                      _rng(data["rng"]), _selection(data.get("selection"), expected),
                      q, traces, metrics, _set_genes(data, population.shape[0], expected))


def _set_genes(data: dict[str, Any], individuals: int,
               expected: Expected) -> FloatArray | None:
    """The set genomes (P, G) of a run that learns the sets: genes in [-1, 1]."""
    if not expected.set_genes:
        if "set_genes" in data:
            raise damaged("holds set genes, but the behaviour learns no sets",
                          hint="resume with the behaviour the run was started with")
        return None
    if "set_genes" not in data:
        raise damaged("has no set genes, but the behaviour learns its sets",
                      hint="resume with the behaviour the run was started with")
    genes = _finite(data["set_genes"], "set_genes")
    _check_set_genome(genes, (individuals, expected.set_genes))
    return genes


def _check_set_genome(genes: FloatArray, shape: tuple[int, ...]) -> None:
    if genes.shape != shape:
        raise damaged(f"'s set genes have shape {genes.shape}, not {shape}",
                      hint="resume with the behaviour the run was started with")
    if genes.size and not (genes.min() >= -1.0 and genes.max() <= 1.0):
        raise damaged("is damaged: its set genes lie outside [-1, 1]")


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _array(value: Any, name: str, kinds: str) -> NDArray[Any]:
    """``value`` as an array of numbers of ``kinds`` (numpy dtype kinds); an empty one too."""
    try:
        array = np.array(value)
    except (TypeError, ValueError, OverflowError):
        array = None
    if array is None or (array.size and array.dtype.kind not in kinds):
        raise damaged(f"is damaged: its '{name}' is not a table of "
                      f"{'whole numbers' if kinds == 'iu' else 'numbers'}")
    return array


def _finite(value: Any, name: str) -> FloatArray:
    table = _array(value, name, "iuf").astype(np.float64)
    if not np.isfinite(table).all():
        raise damaged(f"is damaged: its '{name}' holds NaN or infinity")
    return table


def _check_population(population: IntArray, fitness: FloatArray, expected: Expected) -> None:
    """A population (P, M) of this behaviour's command indices, with its fitness (P,).

    Values must be command indices 0..K-1: anything else would index past the singletons.
    """
    n_rules, n_commands = expected.n_rules, expected.n_commands
    if population.ndim == 2 and population.shape[1] != n_rules:
        raise damaged(f"'s controllers have {population.shape[1]} rules, the behaviour "
                      f"{n_rules}", hint="resume with the behaviour the run was started with")
    if population.ndim != 2 or population.shape[0] < 1:
        raise damaged(f"is damaged: its population has shape {population.shape}, not "
                      f"(individuals, rules) with {n_rules} rules")
    if expected.max_population is not None and population.shape[0] > expected.max_population:
        raise damaged(f"holds {population.shape[0]:,} individuals, more than the run's "
                      f"population of {expected.max_population}")
    if population.min() < 0 or population.max() >= n_commands:
        raise damaged(f"is damaged: its population holds command indices "
                      f"{population.min()}..{population.max()}, outside 0..{n_commands - 1}")
    if fitness.shape != population.shape[:1]:
        raise damaged(f"is damaged: its fitness has shape {fitness.shape}, not "
                      f"({population.shape[0]},) as its population")


def _strengths(data: dict[str, Any], key: str, expected: Expected) -> FloatArray | None:
    """The q table or the traces (M, K), where the checkpoint holds them."""
    shape = (expected.n_rules, expected.n_commands)
    if key not in data:
        if expected.strengths:
            raise damaged(f"has no '{key}' table of shape (rules, commands) = {shape}")
        return None
    table = _finite(data[key], key)
    if table.shape != shape:
        raise damaged(f"is damaged: its '{key}' table has shape {table.shape}, not "
                      f"(rules, commands) = {shape}")
    return table


def _metrics(data: dict[str, Any], generation: int) -> GenerationMetrics:
    # NaN may stand in a metrics column (no validation that generation).
    try:
        metrics = GenerationMetrics.from_row(data["metrics"])
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as exc:
        raise damaged(f"is damaged: its metrics cannot be read ({exc!r})") from None
    if metrics.generation != generation:
        raise damaged(f"has the metrics of generation {metrics.generation}, not {generation}")
    return metrics


def _rng(states: Any) -> dict[str, dict[str, Any]]:
    """The generators' states: a bounded structure of names and integers in [0, 2^128)
    for each stream, that a generator accepts."""
    if not isinstance(states, dict) or len(states) > 16:
        raise damaged("is damaged: its random generator states are not a small object")
    missing = [name for name in STREAMS if name not in states]
    if missing:
        raise damaged(f"has no state of the random generator(s) {', '.join(missing)}")
    pending: list[tuple[Any, int]] = [(states, 0)]
    while pending:
        value, depth = pending.pop()
        if depth > 4:
            raise damaged("is damaged: its random generator states are nested too deep")
        if isinstance(value, dict):
            if len(value) > 16:
                raise damaged("is damaged: its random generator states hold too many fields")
            pending += [(v, depth + 1) for v in value.values()]
        elif isinstance(value, (bool, str)):
            continue
        elif isinstance(value, int):
            if not 0 <= value < _MAX_RNG_INT:
                raise damaged("is damaged: its random generator states hold an integer "
                              "outside [0, 2^128)")
        else:
            raise damaged(f"is damaged: its random generator states hold a "
                          f"{type(value).__name__}")
    for name in STREAMS:
        try:  # the learners' generators are numpy's default, PCG64
            np.random.PCG64().state = states[name]
        except (KeyError, TypeError, ValueError) as exc:
            raise damaged(f"is damaged: its random generator states cannot be restored "
                          f"({name}: {exc!r})") from None
    return {name: states[name] for name in STREAMS}


def _selection(state: Any, expected: Expected) -> SelectionState | None:
    """The selection record, its controllers this behaviour's (None: a run without one)."""
    if state is None:
        return None
    try:
        hall = [Candidate.from_dict(c) for c in state["hall"]]
        best = None if state["best"] is None else Candidate.from_dict(state["best"])
        counts = state["usage"]
        usage = Usage(**{k: int(counts[k]) for k in USAGE_FIELDS if k in counts})
        confirmations = [Confirmed.from_dict(c) for c in state.get("confirmations", [])]
        baseline_state = state.get("baselines") or {"given": [], "verdict": None}
        given = [(str(name), np.array(genes, dtype=np.intp))
                 for name, genes in baseline_state["given"]]
        verdict = (None if baseline_state["verdict"] is None
                   else Verdict.from_dict(baseline_state["verdict"]))
        stop_reason = state["stop_reason"]
        finalized = bool(state["finalized"])
        validated = [dict(v) for v in state["validated"]]
        racing = state.get("racing", False)
        race = [dict(r) for r in state.get("race", [])]
        extension = state.get("extension")
        if extension is not None:
            extension = {"best_seen": float(extension["best_seen"]),
                         "improved_at": int(extension["improved_at"]),
                         "starts": [int(g) for g in extension.get("starts", [0])]}
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as exc:
        raise damaged(f"'s selection record is damaged ({exc!r})") from None
    for candidate in [*hall, *([best] if best else [])]:
        genes = candidate.consequents
        if genes.shape != (expected.n_rules,) or (genes.size and (
                genes.min() < 0 or genes.max() >= expected.n_commands)):
            raise damaged("'s selection record holds a controller that is not one of this "
                          "behaviour")
        if (candidate.sets is None) != (expected.set_genes == 0):
            raise damaged("'s selection record holds a controller that is not one of this "
                          "behaviour (set genes where none are learned, or none where they are)")
        if candidate.sets is not None:
            if not np.isfinite(candidate.sets).all():
                raise damaged("is damaged: its selection record's set genes hold NaN or "
                              "infinity")
            _check_set_genome(candidate.sets, (expected.set_genes,))
    if stop_reason is not None and not isinstance(stop_reason, str):
        raise damaged("'s stop reason is not a name")
    for genes in [c.consequents for c in confirmations] + [g for _, g in given]:
        if genes.shape != (expected.n_rules,) or (genes.size and (
                genes.min() < 0 or genes.max() >= expected.n_commands)):
            raise damaged("'s confirmation or baseline record holds a controller that is not "
                          "one of this behaviour")
    if not isinstance(racing, bool):
        raise damaged("'s selection record is damaged (racing is not true or false)")
    if extension is not None and (math.isnan(extension["best_seen"])
                                  or extension["improved_at"] < -1
                                  or not extension["starts"] or extension["starts"][0] != 0
                                  or extension["starts"] != sorted(set(extension["starts"]))):
        raise damaged("'s extension record is damaged (NaN, a generation before the first, "
                      "or attempts out of order)")
    return SelectionState(hall, best, usage, stop_reason, finalized, validated, confirmations,
                          given, verdict, racing, race, extension)
