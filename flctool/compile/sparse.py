"""The rule base of a controller as plain Python data, evaluated one state at a time.

The learners' hot loop (:mod:`flctool.learners.trial`) and ``flctool infer`` on a small table
use it. It imports no numpy: with overlapping trapezoids only 2-4 of the M rules fire per
state, and numpy's per-call overhead on lists that small costs more than the arithmetic (and
loading numpy costs more than inferring a few rows).

The crisp output is computed with exactly the operations of :meth:`Controller.output` (both
sums accumulated left to right in rule order, then one division), so it gives the same bits.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Protocol

from flctool.behaviour.models import Behaviour
from flctool.behaviour.shapes import evaluated_range, set_row
from flctool.compile.defuzzify import centre_of_area
from flctool.errors import InferenceError
from flctool.membership import firing_sets

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray


class CompiledRules(Protocol):
    """What a rule base is read from: the arrays of a compiled
    :class:`~flctool.compile.controller.Controller` (which holds its rule base as a
    ``SparseRules``, so this module names no controller)."""

    @property
    def input_names(self) -> tuple[str, ...]: ...

    @property
    def ranges(self) -> NDArray[np.float64]: ...

    @property
    def quadruples(self) -> tuple[NDArray[np.float64], ...]: ...

    @property
    def singletons(self) -> NDArray[np.float64]: ...

    @property
    def kinds(self) -> tuple[tuple[int, ...], ...] | None: ...

    @property
    def product(self) -> bool: ...


class SparseRules:
    """The rule base of a controller as plain Python data, evaluated one state at a time.

    Gives exactly the activations of :meth:`Controller.active_rules` (same formulas, same
    floating-point operations), normalised to phi_m = alpha_m / sum(alpha) (eq. 7).
    """

    def __init__(self, controller: CompiledRules) -> None:
        """The rule base of a compiled controller (see also :meth:`from_behaviour`)."""
        self._build(controller.input_names, controller.ranges.tolist(),
                    [quads.tolist() for quads in controller.quadruples],
                    controller.singletons.tolist(), controller.kinds, controller.product)

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour) -> SparseRules:
        """The rule base of a validated behaviour, without compiling it (nor loading numpy):
        the same numbers as ``SparseRules(compile_behaviour(behaviour))``."""
        rules = cls.__new__(cls)
        inputs = behaviour.inputs.values()
        rows = [[set_row(value) for value in v.sets.values()] for v in inputs]
        kinds = tuple(tuple(code for code, _ in sets) for sets in rows)
        rules._build(list(behaviour.inputs),
                     [evaluated_range(v.range, v.sets.values()) for v in inputs],
                     [[p for _, p in sets] for sets in rows],
                     list(behaviour.output.commands.values()),
                     kinds if any(any(k) for k in kinds) else None,
                     behaviour.activation == "product")
        return rules

    def _build(self, input_names: Sequence[str], ranges: Sequence[Sequence[float]],
               quadruples: Sequence[Sequence[Sequence[float]]],
               singletons: Sequence[float],
               kinds: Sequence[Sequence[int]] | None, product: bool) -> None:
        # From plain numbers: each input's [low, high], each of its sets' four corners
        # (pa, pb, pc, pd) in set order (or its shape's parameters, whose code is in kinds),
        # and the commands' singletons, all as Python floats; product: eq. 2 multiplies.
        self.singletons: list[float] = [float(v) for v in singletons]
        self.n_commands = len(self.singletons)
        self.n_rules = math.prod(len(quads) for quads in quadruples)
        self._names = tuple(input_names)
        self._low, self._high = min(self.singletons), max(self.singletons)
        self._lows = [float(low) for low, _ in ranges]
        self._highs = [float(high) for _, high in ranges]
        self._sets = [[tuple(float(v) for v in quad) for quad in quads]
                      for quads in quadruples]
        self._kinds = [None if kinds is None else tuple(kinds[i])
                       for i in range(len(self._sets))]
        self._product = product

    def fire(self, state: list[float]) -> tuple[list[int], list[float], list[float]]:
        """Active rules of one state (N,) in increasing order, their activations alpha_m
        (eq. 2), and phi_m = alpha_m / sum(alpha) (eq. 7)."""
        rules, alphas, total = self.activations(state)
        return rules, alphas, [a / total for a in alphas]

    def activations(self, state: list[float]) -> tuple[list[int], list[float], float]:
        """Active rules of one state (N,) in increasing order, their activations alpha_m
        (eq. 2), and sum(alpha) added in rule order (the denominator of eq. 3 and eq. 7)."""
        if len(state) != len(self._sets):
            raise InferenceError(f"the state has {len(state)} values for "
                                 f"{len(self._sets)} inputs")
        rules = [0]
        alphas = [1.0]
        product = self._product
        for i, value in enumerate(state):
            if value != value:  # NaN: every comparison below would be false
                raise InferenceError(f"the environment observed NaN for input "
                                     f"'{self._names[i]}'",
                                     hint="NaN has no membership: check what the environment "
                                     "observes for it (a Gymnasium environment's or a robot's "
                                     "reading; flctool's simulators refuse the file values "
                                     "that could overflow)")
            low, high, sets = self._lows[i], self._highs[i], self._sets[i]
            s = low if value < low else high if value > high else value  # clip to the range
            members = firing_sets(s, sets, self._kinds[i])  # (index, mu > 0) in set order
            if i == 0:  # the first input: min(1.0, mu) and 1.0 * mu are mu, as 0 < mu <= 1
                rules = [j for j, _ in members]
                alphas = [mu for _, mu in members]
            else:
                width = len(sets)
                rules = [r * width + j for r in rules for j, _ in members]
                if product:  # eq. 2 as the product, multiplied in input order
                    alphas = [a * mu for a in alphas for _, mu in members]
                else:
                    alphas = [a if a < mu else mu for a in alphas for _, mu in members]
        total = add_in_order(alphas)
        if not total > 0.0:  # covered ranges fire a rule; only underflow leaves none
            raise InferenceError(f"no rule fires for the state {state}: the sets overlap too "
                                 "little to be computed in floating point",
                                 hint="widen the sets' overlap")
        return rules, alphas, total

    def output(self, alphas: list[float], commands: list[int]) -> float:
        """Crisp output of eq. 3 from the firing rules' activations and command indices."""
        return self.clip(centre_of_area(zip(alphas, map(self.singletons.__getitem__, commands),
                                            strict=True), 0.0))

    def clip(self, value: float) -> float:
        """Within the commands, as Controller.output keeps it (rounding may step an ulp
        past)."""
        return self._low if value < self._low else self._high if value > self._high else value

    def vote(self, alphas: list[float], commands: list[int]) -> float:
        """The action mode ``vote``: each command's firing rules sum their activations (in
        rule order) and the singleton of the strongest command is the output; ties go to
        the command listed first. Exactly what :func:`flctool.rollout.vote_output` gives."""
        totals = [0.0] * self.n_commands
        for a, k in zip(alphas, commands, strict=True):
            totals[k] += a
        best = 0
        for k in range(1, self.n_commands):
            if totals[k] > totals[best]:
                best = k
        return self.singletons[best]


def add_in_order(values: Iterable[float]) -> float:
    """Plain left-to-right addition from 0.0, as the compiled kernels do.

    Every sum that a run's results depend on goes through here: Python >= 3.12's builtin
    ``sum()`` of floats is compensated and rounds differently, so using it would make runs
    differ between Python versions.
    """
    total = 0.0
    for value in values:
        total += value
    return total
