"""First-order Takagi-Sugeno outputs as constants: a conversion done only on request, with its
error measured.

A first-order Takagi-Sugeno rule concludes a linear function of the inputs,
``z_r(x) = a_r . x + b_r``, and the output is the weighted average of the rules' functions,
each weighted by its rule's activation (fuzzylite's ``WeightedAverage``, MATLAB's
``wtaver``). flctool's commands are constants (eq. 3). ``flctool import FILE
--linear-singletons`` gives each rule that concludes a linear term a constant of its own. The
converted output ``sum_m alpha_m c_m / sum_m alpha_m`` is linear in those constants, so they
are fitted to the first-order output on a dense set of states: by least squares, then
re-weighted towards the smallest largest difference (Lawson's iteration), keeping the
constants whose largest difference is smallest. That largest difference, measured on those
states and on :func:`~flctool.export.mamdani.measurement_states`' (the file's rules as
written, with its conjunction, weights, OR and NOT), is reported, so the user decides whether
the approximation is good enough. Constant terms stay exact.

The same option rewrites a Takagi-Sugeno output's rules that flctool's grid has none like
(OR, NOT, weights, inputs left out; :func:`flctool.export.imported.expanded_rules`), in a
zero-order output too, and measures that the same way.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from flctool.behaviour import Behaviour
from flctool.compile import compile_behaviour
from flctool.export.imported import ImportedController, OriginalRule, as_written
from flctool.export.mamdani import (
    climbed,
    grid_states,
    measurement_states,
    round_up,
    rule_activations,
)

#: Rounds of Lawson's re-weighting after the least-squares fit (fewer for a large fit).
ROUNDS = 40
#: Rounds without a 0.1 % smaller largest difference after which the re-weighting stops.
PATIENCE = 8
#: The most multiply-adds the re-weighting spends (rows x constants^2, per round).
BUDGET = 3e10
#: Fits, each on the states where the last erred most too; the best is kept.
PASSES = 2
#: Points per input where a set's centre (its membership-weighted mean) is taken.
CENTRE_POINTS = 201


@dataclass(frozen=True)
class LinearOutput:
    """A first-order output as read: each of the file's terms (behaviour-file names) as its
    input coefficients then its constant (a constant term: zeros then it), the rules as
    written (:func:`flctool.export.imported.as_written`), the conjunction (fuzzylite's name),
    whether the behaviour's rules differ from the file's, and the output range."""

    terms: Mapping[str, tuple[float, ...]]
    rules: tuple[OriginalRule, ...]
    conjunction: str
    rewritten: bool
    range: tuple[float, float]


def linear_output(controller: ImportedController, output_range: tuple[float, float]
                  ) -> LinearOutput:
    """The Takagi-Sugeno output of ``controller`` (after :func:`build_behaviour`): the terms
    as the file gives them (``controller.terms``) and its rules as written."""
    n = len(controller.inputs)
    terms = {c.name: c.linear if c.linear is not None and len(c.linear) == n + 1
             else (0.0,) * n + (c.value,) for c in controller.terms}
    written = as_written(controller)
    return LinearOutput(terms, written["rules"], written["conjunction"], written["rewritten"],
                        output_range)


def first_order_outputs(behaviour: Behaviour, output: LinearOutput, states: np.ndarray
                        ) -> np.ndarray:
    """(S,) the first-order output for (S, N) ``states`` (clipped to the ranges): the
    weighted average of the rules' linear functions, weights their activations as written
    (as fuzzylite computes it); NaN where no rule fires."""
    x = compile_behaviour(behaviour).check_states(states)
    alpha = rule_activations(behaviour, output.rules, output.conjunction, x)  # (S, R)
    functions = np.array([output.terms[command] for _, _, command, _ in output.rules])
    z = x @ functions[:, :-1].T + functions[:, -1]  # (S, R)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray((alpha * z).sum(axis=1) / alpha.sum(axis=1), dtype=np.float64)


def command_weights(behaviour: Behaviour, states: np.ndarray) -> np.ndarray:
    """(S, K) each command's share of the activation (eq. 3's weights, summed over the rules
    that conclude it): the converted output is this times the constants."""
    controller = compile_behaviour(behaviour)
    consequents = controller.require_consequents()
    k = controller.n_commands
    weights = np.zeros((len(states), k))
    chunk = max(1, 4_000_000 // max(1, controller.n_rules))
    for start in range(0, len(states), chunk):
        alpha = controller.activations(states[start:start + chunk])
        block = np.zeros((len(alpha), k))
        for c in range(k):
            block[:, c] = alpha[:, consequents == c].sum(axis=1)
        total = block.sum(axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            weights[start:start + chunk] = np.where(total > 0, block / total, 0.0)
    return weights


def centre_values(behaviour: Behaviour, functions: Mapping[str, tuple[float, ...]]
                  ) -> dict[str, float]:
    """Each fitted command's function at the centre of its rules' sets (each set's
    membership-weighted mean over its input's range), averaged over its rules: where the fit
    has no state that fires the command, and the start of the fit."""
    controller = compile_behaviour(behaviour)
    grid = np.column_stack([np.linspace(lo, hi, CENTRE_POINTS) for lo, hi in controller.ranges])
    centres = []
    for i, mu in enumerate(controller.memberships(grid)):
        area = mu.sum(axis=0)
        centres.append({name: float(mu[:, s] @ grid[:, i]) / area[s] if area[s] > 0
                        else float(np.mean(controller.ranges[i]))
                        for s, name in enumerate(controller.set_names[i])})
    sums: dict[str, list[float]] = {}
    for rule in behaviour.rules:
        if rule.then in functions:
            f = functions[rule.then]
            x = [centres[i][rule.if_[name]] for i, name in enumerate(behaviour.input_names)]
            value = (math.fsum(a * v for a, v in zip(f, x, strict=False)) + f[-1]
                     if len(f) == len(x) + 1 else f[-1])
            sums.setdefault(rule.then, []).append(value)
    return {name: math.fsum(v) / len(v) for name, v in sums.items()}


def fit(weights: np.ndarray, target: np.ndarray, start: np.ndarray) -> np.ndarray:
    """The constants ``c`` minimising the largest ``|weights @ c - target|`` as far as
    least squares re-weighted by Lawson's iteration reaches; ``start`` where a constant has
    no weight (the least-squares step changes only the constants the states fire)."""
    rows, k = weights.shape
    rounds = max(1, min(ROUNDS, int(BUDGET / max(1, rows * k * k))))
    w = np.full(rows, 1.0 / rows)
    best, best_error, stalled = start, math.inf, 0
    for _ in range(rounds + 1):
        root = np.sqrt(w)
        step = np.linalg.lstsq(weights * root[:, None], root * (target - weights @ start),
                               rcond=None)[0]
        constants = start + step
        error = np.abs(weights @ constants - target)
        worst = float(error.max()) if rows else 0.0
        stalled = 0 if worst < best_error * (1 - 1e-3) else stalled + 1
        if worst < best_error:
            best, best_error = constants, worst
        if stalled >= PATIENCE:
            break
        w = w * error
        total = w.sum()
        if not (total > 0 and math.isfinite(total)):
            break
        w = w / total + 1e-9 / rows  # (a floor: no state drops out of the fit entirely)
    return best


@dataclass(frozen=True)
class LinearConversion:
    """What converting a first-order output changed, measured: ``deviation`` is the largest
    |converted - first-order| output over ``states`` states; ``span`` the width of the file's
    output over them."""

    deviation: float
    states: int
    span: float
    fitted: int
    expanded: bool = False
    #: Whether the file has first-order terms (else only the rules were rewritten).
    linear: bool = True

    def stated(self) -> float:
        """The deviation rounded up to 4 significant digits (never below the measured one)."""
        return round_up(self.deviation)

    def report(self) -> str:
        stated = self.stated()
        share = (f" ({stated / self.span:.2%} of the output's span on those states)"
                 if self.span > 0 else "")
        rules = ("rules rewritten as flctool's (OR, NOT and rules that leave out an input "
                 "expanded over the sets, a combination given several terms given a constant "
                 "of its own, weights dropped; measured against the rules as written)")
        done = (f"first-order (linear) output terms replaced by constants, one per rule, "
                f"fitted to the first-order output by least squares ({self.fitted} "
                f"constants){' and the ' + rules if self.expanded else ''}"
                if self.linear else f"the Takagi-Sugeno output's {rules}, "
                f"{self.fitted} constants fitted by least squares")
        return (f"{done}: the largest difference from the Takagi-Sugeno output (the weighted "
                f"average of the rules' terms, linear functions of the inputs, as fuzzylite "
                f"computes it) is {stated:.4g}{share}, measured on {self.states} states")


def convert(behaviour: Behaviour, output: LinearOutput, free: Mapping[str, tuple[float, ...]]
            ) -> tuple[Behaviour, str]:
    """The behaviour with each command of ``free`` (its function: coefficients then
    constant, the mean of several for a command made of several terms) fitted, and what the
    conversion changed: measured where the rules are complete (else the converted controller
    has no output to compare everywhere, and each command is its function at the centre of
    its rules' sets)."""
    values = dict(behaviour.output.commands)
    values.update(centre_values(behaviour, free))
    behaviour = with_commands(behaviour, values)
    if not behaviour.is_deployable:
        return behaviour, ("Takagi-Sugeno output converted (a first-order term replaced by "
                           "its function at the centre of its rule's sets, the rules "
                           "rewritten as flctool's); the difference is not measured, since "
                           "the rules do not give every combination of sets a command")
    names = list(values)
    fitted = [k for k, name in enumerate(names) if name in free]
    fixed = [k for k, name in enumerate(names) if name not in free]
    fit_states = measurement_states(behaviour, seed=1)
    checked = np.vstack([measurement_states(behaviour), fit_states, grid_states(behaviour)])
    start = np.array([values[n] for n in names])
    best: tuple[float, Behaviour, np.ndarray] | None = None
    for _ in range(PASSES):  # each pass fits on the states where the last one erred most too
        weights = command_weights(behaviour, fit_states)
        target = first_order_outputs(behaviour, output, fit_states)
        keep = np.isfinite(target) & (weights.sum(axis=1) > 0)
        current = start.copy()
        rest = target[keep] - weights[keep][:, fixed] @ current[fixed]
        current[fitted] = fit(weights[keep][:, fitted], rest, current[fitted])
        candidate = with_commands(behaviour, dict(zip(names, map(float, current),
                                                      strict=True)))
        difference = differences(candidate, output)
        states = np.vstack([checked, climbed(difference, checked, candidate)])
        worst = float(np.max(difference(states)))
        if best is None or worst < best[0]:
            best = (worst, candidate, states)
        fit_states = np.vstack([fit_states, states[len(checked):]])
    assert best is not None
    deviation, behaviour, states = best
    # the share is of the span the file's output covers (a Takagi-Sugeno output is not held
    # to its declared range: MATLAB's invkine1 declares [0, 1.5] and spans 20)
    want = first_order_outputs(behaviour, output, states)
    finite = np.isfinite(want)
    lo, hi = ((float(np.min(want[finite])), float(np.max(want[finite]))) if finite.any()
              else output.range)
    linear = any(any(f[:-1]) for f in output.terms.values())
    conversion = LinearConversion(deviation, len(states), hi - lo, len(fitted),
                                  output.rewritten, linear)
    return behaviour, conversion.report()


def differences(behaviour: Behaviour, output: LinearOutput
                ) -> Callable[[np.ndarray], np.ndarray]:
    """|converted - Takagi-Sugeno| at given states (0 where no rule fires)."""
    controller = compile_behaviour(behaviour)

    def difference(at: np.ndarray) -> np.ndarray:
        gap = np.abs(controller.output(at) - first_order_outputs(behaviour, output, at))
        return np.where(np.isfinite(gap), gap, 0.0)

    return difference


def with_commands(behaviour: Behaviour, values: Mapping[str, float]) -> Behaviour:
    """``behaviour`` with its commands' values replaced (the same names, in order)."""
    data = behaviour.output.model_copy(update={"commands": {
        name: float(values[name]) for name in behaviour.output.commands}})
    return behaviour.model_copy(update={"output": data})


def converted_notes(behaviours: Sequence[Behaviour], controllers: Sequence[ImportedController],
                    ranges: Sequence[tuple[float, float]]
                    ) -> tuple[list[Behaviour], list[str | None]]:
    """Each behaviour with its first-order output converted (:func:`convert`), and the note
    of each output converted (None for the others)."""
    result: list[Behaviour] = []
    notes: list[str | None] = []
    for behaviour, controller, span in zip(behaviours, controllers, ranges, strict=True):
        free = {c.name: c.linear for c in controller.commands if c.linear is not None}
        if not controller.convert_linear:
            result.append(behaviour)
            notes.append(None)
            continue
        converted, note = convert(behaviour, linear_output(controller, span), free)
        result.append(converted)
        notes.append("; ".join([*controller.notes, note]))
    return result, notes
