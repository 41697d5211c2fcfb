"""Shared helpers of the benchmark scripts: timing, states, JSON, training a run and
evaluating what it learned, and the same controller built in the libraries users would pick
instead (scikit-fuzzy, pyfuzzylite, simpful).

Each builder makes the other library compute eq. 1-3 exactly as flctool does (Mamdani min,
centre of area over singletons, sum over rules), so outputs can be checked equal before
anything is timed. Inputs are expected inside their ranges (flctool clips; simpful does not).
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flctool import Behaviour, Controller
from flctool.learners.metrics import Usage
from flctool.rollout import EvaluationResult
from flctool.runs import Run, RunSummary

ROOT = Path(__file__).resolve().parents[1]
BALLCHASE = ROOT / "behaviours" / "ballchase-handmade.yaml"


# -- training, then evaluating what was learned ----------------------------------------------
@dataclass(frozen=True)
class Trained:
    """A run trained to its end and its ``best.yaml`` evaluated on held-out episodes."""

    run: Run
    summary: RunSummary
    best: Behaviour
    result: EvaluationResult
    #: CPU seconds of ``run.train()`` (this process, every thread): training, selection and
    #: confirmation, without the held-out evaluation.
    train_cpu_seconds: float

    @property
    def usage(self) -> Usage:
        """Every episode and step the run spent (training, selection, confirmation,
        baselines); the held-out evaluation is not among them."""
        return self.summary.usage or Usage()

    def counts(self) -> dict[str, int]:
        """The run's episodes and steps as the benchmarks' JSON records them."""
        usage = self.usage
        return {"training_episodes": usage.training_episodes,
                "selection_episodes": usage.selection_episodes,
                "confirmation_episodes": usage.confirmation_episodes,
                "episodes": usage.episodes, "steps": usage.steps}


def train_and_evaluate(behaviour: Behaviour, out: Path, episodes: int,
                       seeds: Sequence[int] | np.ndarray | None = None) -> Trained:
    """Train ``behaviour`` in a new run directory ``out``, then evaluate its ``best.yaml`` on
    ``episodes`` held-out episodes: the seeds ``flctool evaluate`` runs (which training and
    selection never use), or ``seeds``."""
    from flctool import compile_behaviour, load_behaviour
    from flctool.envs import make_env
    from flctool.rollout import TRAIN_SEED_LOW, evaluate, evaluation_seeds
    from flctool.runs import BEST_FILE, create_run

    run = create_run(behaviour, out)
    started = time.process_time()
    summary = run.train()
    cpu = time.process_time() - started
    best = load_behaviour(run.path / BEST_FILE)
    held_out = evaluation_seeds(0, episodes) if seeds is None else np.asarray(seeds,
                                                                                dtype=np.int64)
    assert held_out.max() < TRAIN_SEED_LOW  # held out: training and selection never use these
    with make_env(best, len(held_out)) as env:
        result = evaluate(compile_behaviour(best), env, held_out)
    return Trained(run, summary, best, result, cpu)


# -- timing ---------------------------------------------------------------------------------
def best_seconds(run: Callable[[], object], repeats: int) -> float:
    """The least CPU time (``time.process_time``: this process, every thread) of ``repeats``
    runs: the least disturbed by the other processes of a shared machine."""
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        run()
        best = min(best, time.process_time() - start)
    return best


def best_wall_seconds(run: Callable[[], object], repeats: int) -> float:
    """The fastest of ``repeats`` runs in wall time: only for what spreads over cores."""
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def per_call_seconds(call: Callable[[Any], object], items: Sequence[Any], repeats: int) -> float:
    """Seconds per call of ``call(item)`` over ``items``: best of ``repeats`` passes."""
    def one_pass() -> None:
        for item in items:
            call(item)
    return best_seconds(one_pass, repeats) / len(items)


def uniform_states(controller: Controller, count: int, seed: int) -> np.ndarray:
    """``(count, N)`` states drawn uniformly inside the input ranges."""
    rng = np.random.default_rng(seed)
    return rng.uniform(controller.ranges[:, 0], controller.ranges[:, 1],
                       size=(count, controller.n_inputs))


def machine() -> dict[str, Any]:
    """What the figures were measured on."""
    import numba

    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "python": sys.version.split()[0],
            "numpy": np.__version__, "numba": numba.__version__,
            "platform": platform.platform()}


def write_json(path: Path, data: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2) + "\n")


def check_equal(name: str, got: np.ndarray, expected: np.ndarray, tolerance: float) -> float:
    """Largest difference; raises if any is above ``tolerance`` (outputs must agree first)."""
    difference = float(np.max(np.abs(np.asarray(got) - expected)))
    if not difference <= tolerance:
        raise SystemExit(f"{name} disagrees with flctool by {difference:.3g} "
                         f"(> {tolerance:g}); not timing a different computation")
    return difference


def rule_texts(behaviour: Behaviour, controller: Controller) -> list[tuple[dict[str, str], str]]:
    """Every rule as ({input: set}, command), in rule order."""
    assert controller.consequents is not None
    return [(dict(zip(behaviour.input_names, sets, strict=True)),
             controller.command_names[int(k)])
            for sets, k in zip(behaviour.antecedents(), controller.consequents, strict=True)]


def _check_edges(behaviour: Behaviour) -> None:
    # Libraries that interpolate a sampled membership (scikit-fuzzy) cannot jump inside a
    # range; vertical edges at a range's end are fine (clipping never goes past them).
    for name, variable in behaviour.inputs.items():
        lo, hi = variable.range
        for set_name, (pa, pb, pc, pd) in variable.sets.items():
            if (pa == pb and pa > lo) or (pc == pd and pd < hi):
                raise SystemExit(f"{name}.{set_name}: a vertical edge inside the range; the "
                                 "library builders here support them only at the range ends")


# -- scikit-fuzzy ---------------------------------------------------------------------------
def skfuzzy_simulation(behaviour: Behaviour, controller: Controller) -> Any:
    """A ``skfuzzy.control`` simulation computing eq. 1-3.

    Inputs: each set sampled at every breakpoint (its membership is piecewise linear between
    them, so interpolation is exact). Output: skfuzzy accumulates rules with max, clips each
    output set at its cut (memberships <= 1) and defuzzifies the sampled union by centroid.
    Here ``accumulation_method = np.add`` makes a command's cut the sum of its rules'
    activations; every rule is weighted by lambda = 2^-k <= 1/M (exact, and eq. 3 does not
    change when all activations are scaled) so a cut never reaches 1; and each command is a
    plateau of half-width eps at its value with feet of width delta = 1e-12 eps. Clipped at
    w, that shape has centroid exactly at the command's value and area 2 w (eps + delta) -
    delta w^2, proportional to w within 1e-12: the centroid is eq. 3 to ~1e-12.
    """
    from skfuzzy import control

    _check_edges(behaviour)
    antecedents = {}
    for name, variable in behaviour.inputs.items():
        points = {*variable.range}
        for quad in variable.sets.values():
            points.update(quad)
        universe = np.array(sorted(points))
        antecedent = control.Antecedent(universe, name)
        for set_name, quad in variable.sets.items():
            antecedent[set_name] = _trapezoid_samples(universe, quad)
        antecedents[name] = antecedent
    values = np.unique(controller.singletons)
    eps = 0.25 * float(np.diff(values).min()) if len(values) > 1 else 0.25
    delta = 1e-12 * eps
    corners = np.array([-eps - delta, -eps, eps, eps + delta])
    universe = np.unique((values[:, None] + corners[None, :]).ravel())
    consequent = control.Consequent(universe, behaviour.output.name, defuzzify_method="centroid")
    consequent.accumulation_method = np.add
    for command, value in behaviour.output.commands.items():
        consequent[command] = ((universe >= value - eps) & (universe <= value + eps)) * 1.0
    weight = 2.0 ** -int(np.ceil(np.log2(controller.n_rules + 1)))
    rules = []
    for sets, command in rule_texts(behaviour, controller):
        terms = [antecedents[name][set_name] for name, set_name in sets.items()]
        condition = terms[0]
        for term in terms[1:]:
            condition = condition & term
        rules.append(control.Rule(condition, consequent[command] % weight))
    return control.ControlSystemSimulation(control.ControlSystem(rules), cache=False)


def _trapezoid_samples(universe: np.ndarray, quad: Sequence[float]) -> np.ndarray:
    from flctool.membership import trapezoid

    return trapezoid(universe, np.array([quad], dtype=np.float64))[:, 0]


def skfuzzy_outputs(simulation: Any, behaviour: Behaviour, states: np.ndarray) -> np.ndarray:
    """All states at once through skfuzzy's array inputs."""
    for i, name in enumerate(behaviour.input_names):
        simulation.input[name] = states[:, i].copy()
    simulation.compute()
    return np.asarray(simulation.output[behaviour.output.name], dtype=np.float64)


def skfuzzy_one(simulation: Any, behaviour: Behaviour) -> Callable[[np.ndarray], float]:
    names = behaviour.input_names
    output = behaviour.output.name

    def infer(state: np.ndarray) -> float:
        for name, value in zip(names, state, strict=True):
            simulation.input[name] = float(value)
        simulation.compute()
        return float(simulation.output[output])
    return infer


# -- pyfuzzylite ----------------------------------------------------------------------------
def fuzzylite_engine(behaviour: Behaviour, controller: Controller) -> Any:
    """A pyfuzzylite engine computing eq. 1-3, read from flctool's own FLL export of the
    controller (Minimum conjunction, constant terms, no aggregation, WeightedAverage)."""
    import fuzzylite as fl

    from flctool import with_rules
    from flctool.export.fll import FllExporter

    assert controller.consequents is not None
    deployable = with_rules(behaviour, controller.consequents)
    return fl.FllImporter().from_string(FllExporter().to_string(deployable))


def fuzzylite_one(engine: Any) -> Callable[[np.ndarray], float]:
    inputs = list(engine.input_variables)
    output = engine.output_variables[0]

    def infer(state: np.ndarray) -> float:
        for variable, value in zip(inputs, state, strict=True):
            variable.value = float(value)
        engine.process()
        return float(output.value)
    return infer


# -- simpful --------------------------------------------------------------------------------
def simpful_system(behaviour: Behaviour, controller: Controller) -> Any:
    """A simpful Sugeno system computing eq. 1-3 (AND is min, crisp output values)."""
    import simpful

    _check_edges(behaviour)
    system = simpful.FuzzySystem(show_banner=False, verbose=False)
    for name, variable in behaviour.inputs.items():
        sets = [simpful.FuzzySet(function=simpful.Trapezoidal_MF(*map(float, quad)),
                                 term=set_name)
                for set_name, quad in variable.sets.items()]
        system.add_linguistic_variable(
            name, simpful.LinguisticVariable(sets, universe_of_discourse=list(variable.range)))
    for command, value in behaviour.output.commands.items():
        system.set_crisp_output_value(command, float(value), verbose=False)
    rules = []
    for sets, command in rule_texts(behaviour, controller):
        condition = " AND ".join(f"({name} IS {set_name})" for name, set_name in sets.items())
        rules.append(f"IF {condition} THEN ({behaviour.output.name} IS {command})")
    system.add_rules(rules, verbose=False)
    return system


def simpful_one(system: Any, behaviour: Behaviour) -> Callable[[np.ndarray], float]:
    names = behaviour.input_names
    output = behaviour.output.name

    def infer(state: np.ndarray) -> float:
        for name, value in zip(names, state, strict=True):
            system.set_variable(name, float(value), verbose=False)
        return float(system.Sugeno_inference([output])[output])
    return infer
