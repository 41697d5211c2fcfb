"""A compiled controller: the behaviour's numbers as frozen numpy arrays, and inference.

Rule order (eq. 1): rule ``m`` is one combination of sets, enumerated with the **last input
varying fastest** -- the order of ``itertools.product`` and of ``numpy.ndindex``. For inputs
with L = (3, 5) sets, rule 0 is (set 0, set 0), rule 1 is (set 0, set 1), ..., rule 5 is
(set 1, set 0). This order is stable: it is how chromosomes, q tables and exports index rules.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, partial
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np
from numpy.typing import NDArray

from flctool.compile.membership import trapezoid
from flctool.errors import InferenceError
from flctool.spec.models import Behaviour, Rule

if TYPE_CHECKING:
    from flctool.compile.kernels import Layout

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


_Array = TypeVar("_Array", bound=NDArray[Any])


def _frozen(array: _Array) -> _Array:
    frozen = np.ascontiguousarray(array)
    frozen.setflags(write=False)
    return cast(_Array, frozen)


@dataclass(frozen=True, eq=False)
class Controller:
    """Frozen arrays of one behaviour. Build it with :func:`compile_behaviour`.

    Attributes, with N inputs, L_i sets per input, M = prod(L_i) rules and K commands:
        input_names (N,), set_names (N, L_i), output_name, command_names (K,)
        ranges (N, 2): each input's [low, high]
        quadruples: N arrays of shape (L_i, 4)
        rule_grid (M, N): set index of each input in each rule
        singletons (K,): the commands' values c^k
        consequents (M,) or None: command index of each rule, when deployable
    """

    input_names: tuple[str, ...]
    set_names: tuple[tuple[str, ...], ...]
    output_name: str
    command_names: tuple[str, ...]
    ranges: FloatArray
    quadruples: tuple[FloatArray, ...]
    rule_grid: IntArray
    singletons: FloatArray
    consequents: IntArray | None

    @property
    def n_inputs(self) -> int:
        return len(self.input_names)

    @property
    def n_rules(self) -> int:
        return int(self.rule_grid.shape[0])

    @property
    def n_commands(self) -> int:
        return int(self.singletons.shape[0])

    @property
    def shape(self) -> tuple[int, ...]:
        """(L_1, ..., L_N): sets per input."""
        return tuple(len(names) for names in self.set_names)

    # -- inference -----------------------------------------------------------------------
    # The public methods validate and shape; the work is done by compiled kernels
    # (flctool.compile.kernels) that walk only the rules that fire and give exactly what the
    # plain eq. 1-3 give (tests compare with a loop over rules).

    def check_states(self, states: FloatArray) -> FloatArray:
        """States as a (B, N) float array, clipped to the ranges; NaN is an error."""
        array = self._as_states(states)
        if np.isnan(array).any():
            self._raise_nan(array)
        # Out-of-range values (and +-inf) are clipped: a sensor past its end reads as the end.
        return np.clip(array, self.ranges[:, 0], self.ranges[:, 1])

    def memberships(self, states: FloatArray) -> list[FloatArray]:
        """Membership of each input in each of its sets: (B, N) -> N arrays (B, L_i)."""
        clipped = self.check_states(states)
        return [trapezoid(clipped[:, i], q) for i, q in enumerate(self.quadruples)]

    def activations(self, states: FloatArray) -> FloatArray:
        """Rule activations alpha_m(S), Mamdani minimum (eq. 2): (B, N) -> (B, M).

        Dense by definition; for large M prefer :meth:`active_rules` or :meth:`output`, which
        never make a (B, M) array.
        """
        from flctool.compile import kernels

        array = self._as_states(states)
        alpha = np.zeros((array.shape[0], self.n_rules))
        layout = self._layout
        nan_state = kernels.activations(array, layout.lo, layout.hi, layout.quads,
                                        layout.offsets, layout.strides, layout.max_sets, alpha)
        if nan_state >= 0:
            self._raise_nan(array)
        return alpha

    def active_rules(self, state: FloatArray) -> tuple[IntArray, FloatArray]:
        """The rules that fire for one state (N,), and their activations (eq. 2).

        Returns ``(rules (A,), alpha (A,))`` with ``alpha > 0``, rules in increasing order.
        With overlapping trapezoids A <= 2^N however large M is, and the cost of this call
        follows A, not M: per-step work that uses only these follows the active rules.
        """
        x = np.array(state, dtype=np.float64)  # a copy: writable and contiguous, as compiled
        if x.shape != self._state_shape:
            x = self._as_states(x)[0]  # (1, N) is accepted too; other shapes raise
        rules, alpha, nan_input = self._active_kernel(x)
        if nan_input >= 0:
            self._raise_nan(x[None, :])
        return rules, alpha

    def output(self, states: FloatArray, consequents: IntArray | None = None) -> FloatArray:
        """Crisp output by centre of area over singletons (eq. 3).

        ``states (B, N)`` -> ``(B,)`` with this controller's consequents (or one ``(M,)``
        vector); with a population ``consequents (P, M)`` -> ``(P, B)``. Only the rules that
        fire are visited and no (B, M) array is made, whatever M is.
        """
        from flctool.compile import kernels

        table = self._consequents(consequents)
        array = self._as_states(states)
        # One compiled signature: writable C-contiguous arrays.
        tables = np.ascontiguousarray(table.reshape(-1, self.n_rules), dtype=np.intp)
        if not tables.flags.writeable:
            tables = tables.copy()
        out = np.empty((tables.shape[0], array.shape[0]))
        layout = self._layout
        failed = kernels.infer(array, layout.lo, layout.hi, layout.quads, layout.offsets,
                               layout.strides, layout.max_sets, layout.grid, tables,
                               layout.singletons, out)
        if failed >= 0:
            self._raise_undefined(array, failed)
        return out if table.ndim == 2 else out[0]

    def output_one(self, state: FloatArray) -> float:
        """Crisp output (eq. 3) of one state ``(N,)`` with this controller's consequents.

        The fast path for a control loop that infers one state at a time (about a
        microsecond a call); equal to ``output(state[None])[0]``.
        """
        x = np.array(state, dtype=np.float64)  # a copy: writable and contiguous, as compiled
        if x.shape != self._state_shape:
            x = self._as_states(x)[0]  # (1, N) is accepted too; other shapes raise
        value: float = self._one_kernel(x)
        if value != value:  # a NaN input, or no rule fires (never a NaN output)
            self._raise_undefined(x[None, :], 0)
        return value

    @cached_property
    def _layout(self) -> Layout:
        from flctool.compile import kernels

        return kernels.layout(self.ranges, self.quadruples, self.rule_grid, self.singletons)

    @cached_property
    def _state_shape(self) -> tuple[int]:
        return (self.n_inputs,)

    @cached_property
    def _one_kernel(self) -> Callable[[FloatArray], float]:
        # The kernel with this controller's arrays bound: a one-state call pays only for
        # checking the state and numba's dispatch. The table is copied writable so that the
        # kernel is compiled for one signature.
        from flctool.compile import kernels

        table = np.array(self._consequents(None), dtype=np.intp)
        return partial(kernels.infer_one, self._layout.floats, self._layout.ints, table)

    @cached_property
    def _active_kernel(self) -> Callable[[FloatArray], tuple[IntArray, FloatArray, int]]:
        from flctool.compile import kernels

        return partial(kernels.active_one, self._layout.floats, self._layout.ints)

    def _as_states(self, states: FloatArray) -> FloatArray:
        array = np.asarray(states, dtype=np.float64)
        if array.ndim == 1 and array.shape[0] == self.n_inputs:
            array = array[None, :]
        if array.ndim != 2 or array.shape[1] != self.n_inputs:
            raise InferenceError(
                f"states must have shape (B, {self.n_inputs}) for inputs "
                f"{', '.join(self.input_names)}; got shape {array.shape}")
        if not array.flags.writeable:
            return np.array(array, dtype=np.float64)
        return np.ascontiguousarray(array, dtype=np.float64)

    def _raise_nan(self, states: FloatArray) -> None:
        row, col = np.argwhere(np.isnan(states))[0]
        raise InferenceError(
            f"input '{self.input_names[col]}' is NaN in state {row}",
            hint="NaN has no membership; filter or replace missing sensor readings")

    def _raise_undefined(self, states: FloatArray, row: int) -> None:
        # Why the kernels could not infer state ``row``: a NaN input, or (covering partitions
        # make it rare) every activation underflowed to 0, where eq. 3 would be 0 / 0.
        if np.isnan(states[row]).any():
            self._raise_nan(states)
        raise InferenceError(
            f"no rule fires for state {row}: the sets overlap too little to be computed in "
            "floating point (every membership underflows to 0)",
            hint="widen their overlap")

    def _consequents(self, consequents: IntArray | None) -> IntArray:
        if consequents is None:
            if self.consequents is None:
                raise InferenceError(
                    "this controller has no rule consequents (its behaviour is not deployable)",
                    hint="pass consequents, or complete the rules (flctool learn)")
            return self.consequents
        table = np.asarray(consequents)
        if table.shape[-1] != self.n_rules or table.ndim not in (1, 2):
            raise InferenceError(f"consequents must have shape (M,) or (P, M) with "
                                 f"M = {self.n_rules}; got {table.shape}")
        if table.size and (table.min() < 0 or table.max() >= self.n_commands):
            raise InferenceError(f"consequents must be command indices 0..{self.n_commands - 1}")
        return table.astype(np.intp, copy=False)

    def with_consequents(self, consequents: IntArray) -> Controller:
        """The same controller with the given (M,) consequents."""
        table = self._consequents(consequents)
        if table.ndim != 1:
            raise InferenceError("with_consequents takes one (M,) vector")
        controller = Controller(self.input_names, self.set_names, self.output_name,
                                self.command_names, self.ranges, self.quadruples,
                                self.rule_grid, self.singletons, _frozen(table.copy()))
        for shared in ("_layout", "_active_kernel"):  # same sets: share what depends on them
            if shared in self.__dict__:
                controller.__dict__[shared] = self.__dict__[shared]
        return controller


def compile_behaviour(behaviour: Behaviour) -> Controller:
    """Compile a validated behaviour into a :class:`Controller`."""
    names = tuple(behaviour.inputs)
    set_names = tuple(tuple(v.sets) for v in behaviour.inputs.values())
    shape = tuple(len(s) for s in set_names)
    grid = np.array(list(np.ndindex(*shape)), dtype=np.intp).reshape(math.prod(shape), len(shape))
    commands = tuple(behaviour.output.commands)
    consequents = None
    if behaviour.is_deployable:
        index = {name: k for k, name in enumerate(commands)}
        consequents = np.empty(len(grid), dtype=np.intp)
        for rule in behaviour.rules:
            sets = [set_names[i].index(rule.if_[n]) for i, n in enumerate(names)]
            consequents[int(np.ravel_multi_index(sets, shape))] = index[rule.then]
        consequents = _frozen(consequents)
    return Controller(
        input_names=names,
        set_names=set_names,
        output_name=behaviour.output.name,
        command_names=commands,
        ranges=_frozen(np.array([v.range for v in behaviour.inputs.values()], dtype=np.float64)),
        quadruples=tuple(_frozen(np.array(list(v.sets.values()), dtype=np.float64))
                         for v in behaviour.inputs.values()),
        rule_grid=_frozen(grid),
        singletons=_frozen(np.array(list(behaviour.output.commands.values()), dtype=np.float64)),
        consequents=consequents,
    )


def with_rules(behaviour: Behaviour, consequents: IntArray) -> Behaviour:
    """The behaviour with a complete rule table from (M,) consequent indices (grid order)."""
    commands = tuple(behaviour.output.commands)
    table = np.asarray(consequents)
    if table.shape != (behaviour.rule_count,):
        raise InferenceError(f"consequents must have shape ({behaviour.rule_count},)")
    rules = [Rule.model_validate({"if": dict(zip(behaviour.input_names, sets, strict=True)),
                                  "then": commands[int(k)]})
             for sets, k in zip(behaviour.antecedents(), table, strict=True)]
    return behaviour.model_copy(update={"rules": rules})
