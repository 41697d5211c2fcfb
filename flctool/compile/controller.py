"""A compiled controller: the behaviour's numbers as frozen numpy arrays, and inference.

Rule order (eq. 1): rule ``m`` is one combination of sets, enumerated with the **last input
varying fastest**. For inputs with L = (3, 5) sets, rule 0 is (set 0, set 0), rule 1 is
(set 0, set 1), ..., rule 5 is (set 1, set 0). This order is stable: it is how chromosomes,
q tables and exports index rules. It is coded once, in :mod:`flctool.behaviour.rule_order`;
:attr:`Controller.rule_grid` holds it as an array.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from functools import cache, cached_property
from typing import TYPE_CHECKING, Any, TypeVar, cast

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.models import Behaviour
from flctool.behaviour.shapes import evaluated_range, set_row
from flctool.compile import vectorised
from flctool.compile.rules import rule_consequents, rule_grid
from flctool.errors import InferenceError, NotDeployableError
from flctool.membership import memberships

if TYPE_CHECKING:
    from flctool.compile.kernels import Layout
    from flctool.compile.sparse import SparseRules

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
_FLOAT64 = np.dtype(np.float64)
# From this many states, output(threads=n) splits the batch (below, starting threads costs
# more than it saves).
THREADED_STATES = 20_000

#: Where inference runs: ``auto`` (numpy first, the compiled kernels once they pay),
#: ``kernels`` (always compiled) or ``numpy`` (never compiled); set by
#: :func:`set_inference`, or in the environment before flctool is imported.
INFERENCE_MODES = ("auto", "kernels", "numpy")
INFERENCE_VARIABLE = "FLCTOOL_INFERENCE"
#: CPU seconds of numpy inference after which a process (``auto``) loads the kernels: about
#: what loading them costs (importing numba and the cached machine code, 0.3 s of CPU
#: measured; compiling them, once per machine, several seconds). Renting until the rent
#: equals the price, then buying, spends at most about twice the cheaper of the two, whatever
#: the work turns out to be; and a small job never pays for the kernels at all.
KERNELS_PAY_AFTER = 0.3
#: ... but where the kernels are not in numba's cache (a machine's first run, or a new
#: flctool or numba), buying them means compiling them: 13-16 s of CPU measured on a loaded
#: 2-core machine (`flctool infer` on 10^6 rows, whose numpy inference costs about 0.5 s),
#: several seconds on a quiet one. Then numpy goes on until it has spent this much: the same
#: rule with the price that is to be paid.
KERNELS_COMPILE_PAY_AFTER = 5.0
#: Called around loading the kernels (the command line shows a notice there, as compiling
#: takes seconds on a machine's first run).
kernel_loading: Callable[[], AbstractContextManager[None]] = nullcontext


class _Inference:
    """This process's choice of path (one per process: loading the kernels is too)."""

    mode = "auto"
    numpy_seconds = 0.0  # CPU spent in numpy inference so far


_kernels_on = False  # read on every call: a module global is the cheapest lookup


def set_inference(mode: str) -> None:
    """Where :class:`Controller` inference runs from now on in this process: ``auto``,
    ``kernels`` or ``numpy`` (:data:`INFERENCE_MODES`). Every path gives the same bits;
    ``kernels`` suits a control loop that must not pause to load them mid-run."""
    global _kernels_on
    if mode not in INFERENCE_MODES:
        raise ValueError(f"unknown inference mode '{mode}'; use one of: "
                         f"{', '.join(INFERENCE_MODES)}")
    _Inference.mode = mode
    _kernels_on = mode == "kernels" or (mode == "auto" and _kernels_pay())


def _kernels_pay() -> bool:
    # The ski-rental rule (KERNELS_PAY_AFTER), with the price of compiling where they are not
    # cached (KERNELS_COMPILE_PAY_AFTER).
    spent = _Inference.numpy_seconds
    return spent >= KERNELS_PAY_AFTER and (spent >= KERNELS_COMPILE_PAY_AFTER
                                           or _kernels_cached())


def _spent_in_numpy(seconds: float) -> None:
    global _kernels_on
    _Inference.numpy_seconds += seconds
    if _Inference.mode == "auto" and _Inference.numpy_seconds >= KERNELS_PAY_AFTER:
        _kernels_on = _kernels_pay()


@cache
def _kernels_cached() -> bool:
    # Whether the batched kernel that large jobs spend on (infer_own: evaluate, infer) would
    # load from numba's cache rather than compile; asked once a process (it imports numba).
    with kernel_loading():
        from flctool.compile import kernels

        return kernels.cached("infer_own")


def _inference_from_environment() -> None:
    mode = os.environ.get(INFERENCE_VARIABLE, "auto")
    try:
        set_inference(mode)
    except ValueError:
        set_inference("auto")  # a mistyped variable must not break every command


_inference_from_environment()


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
        quadruples: N arrays of shape (L_i, 4): each set's trapezoid corners, or the
            parameters of its shape padded with 0 (flctool.behaviour.shapes.set_row)
        rule_grid (M, N): set index of each input in each rule
        singletons (K,): the commands' values c^k
        consequents (M,) or None: command index of each rule, when deployable
        kinds: None when every set is a trapezoid, else N tuples (L_i,) of the sets'
            shape codes (flctool.behaviour.shapes.CODES; 0 the trapezoid)
        product: whether eq. 2 is the product of a rule's memberships, multiplied in input
            order (the behaviour's ``activation: product``), rather than their min
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
    kinds: tuple[tuple[int, ...], ...] | None = None
    product: bool = False

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
    # (flctool.compile.kernels) that give exactly what the plain eq. 1-3 give (tests compare
    # with a loop over rules). Arrays already in the kernels' form (float64, C-contiguous,
    # right shape) go to them untouched: a small call costs little more than the kernel.

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
        kinds = self.kinds
        return [memberships(clipped[:, i], q, None if kinds is None else kinds[i])
                for i, q in enumerate(self.quadruples)]

    def activations(self, states: FloatArray) -> FloatArray:
        """Rule activations alpha_m(S), Mamdani minimum (eq. 2) or the product of the
        memberships (:attr:`product`): (B, N) -> (B, M).

        Dense by definition; for large M prefer :meth:`active_rules` or :meth:`output`, which
        never make a (B, M) array.
        """
        array = self._as_states(states)
        if not _kernels_on:
            started = time.thread_time()
            if np.isnan(array).any():
                self._raise_nan(array)
            dense = vectorised.activations(array, self.ranges, self.quadruples, self.kinds,
                                           self._strides, self.n_rules, self.product)
            _spent_in_numpy(time.thread_time() - started)
            return dense
        alpha = np.zeros((array.shape[0], self.n_rules))
        layout = self._layout
        if _kernel("activations")(array, layout.floats, layout.ints, alpha) >= 0:
            self._raise_nan(array)
        return alpha

    def active_rules(self, state: FloatArray) -> tuple[IntArray, FloatArray]:
        """The rules that fire for one state (N,), and their activations (eq. 2).

        Returns ``(rules (A,), alpha (A,))``, rules in increasing order: those whose every
        membership is > 0 (so ``alpha > 0``, unless a product underflows to 0).
        With overlapping trapezoids A <= 2^N however large M is, and the cost of this call
        follows A, not M: per-step work that uses only these follows the active rules.
        """
        x = self._as_state(state)
        if not _kernels_on:
            if np.isnan(x).any():
                self._raise_nan(x[None, :])
            return vectorised.active_rules(x, self.ranges, self.quadruples, self.kinds,
                                           self._strides, self.product)
        layout = self._layout
        rules, alpha, nan_input = _kernel("active_one")(layout.floats, layout.ints, x)
        if nan_input >= 0:
            self._raise_nan(x[None, :])
        return rules, alpha

    def output(self, states: FloatArray, consequents: IntArray | None = None, *,
               threads: int = 1) -> FloatArray:
        """Crisp output by centre of area over singletons (eq. 3).

        ``states (B, N)`` -> ``(B,)`` with this controller's consequents (or one ``(M,)``
        vector); with a population ``consequents (P, M)`` -> ``(P, B)``. Only the rules that
        fire are visited and no (B, M) array is made, whatever M is.

        ``threads`` > 1 splits a large batch (from :data:`THREADED_STATES` states) into that
        many contiguous parts inferred at once (the kernels release the GIL); each state's
        output is computed alone, so the result is identical to ``threads=1``.
        """
        kernels_on = _kernels_on
        if kernels_on:
            own_floats, own_ints, own, n_inputs = self._own
        else:
            n_inputs = len(self.input_names)
        # Any float64 (B, N) array goes to the kernel as it is (it reads strides). (Each
        # attribute read here costs tens of ns, a good part of a call on a few states.)
        shape = states.shape if type(states) is np.ndarray else None
        if not (shape is not None and len(shape) == 2 and shape[1] == n_inputs
                and states.dtype is _FLOAT64):
            states = self._as_states(states)
            shape = states.shape
        if not kernels_on:
            return self._output_numpy(states, consequents)
        count = shape[0]
        if consequents is None and own is not None and (threads <= 1
                                                         or count < THREADED_STATES):
            # This controller's consequents on one core: the kernel entry made for it
            # (kernels.infer_own), four arrays and no other argument.
            out = np.empty(count)
            failed = own(own_floats, own_ints, states, out)
            if failed >= 0:
                self._raise_undefined(states, failed)
            return out
        return self._output_tables(states, consequents, threads)

    def _output_numpy(self, states: FloatArray, consequents: IntArray | None) -> FloatArray:
        # output() without the kernels (vectorised.output): the same bits, the same errors.
        started = time.thread_time()
        table = self._consequents(consequents)  # (raises if there are none)
        if np.isnan(states).any():
            self._raise_nan(states)
        out, failed = vectorised.output(states, self.ranges, self.quadruples, self.kinds,
                                        self._strides, self.singletons,
                                        table.reshape(-1, self.n_rules), self.product)
        if failed >= 0:
            self._raise_undefined(states, failed)
        _spent_in_numpy(time.thread_time() - started)
        return out[0] if table.ndim == 1 else out

    def _output_tables(self, states: FloatArray, consequents: IntArray | None,
                       threads: int) -> FloatArray:
        # output() with a population, given consequents or several threads.
        table = self._consequents(consequents)  # (raises if there are none)
        single = table.ndim == 1
        tables = np.array(table.reshape(-1, self.n_rules), dtype=np.intp, order="C")
        population = tables.shape[0]
        count = states.shape[0]
        out = np.empty(population * count)  # (P, B) flat
        if threads > 1 and count >= THREADED_STATES:
            failed = self._infer_threaded(states, tables, out, threads)
        else:
            layout = self._layout
            failed = _kernel("infer")(states, layout.floats, layout.ints, tables, out, 0, count,
                                      layout.dense)
        if failed >= 0:
            self._raise_undefined(states, failed)
        return out if single else out.reshape(population, count)

    def output_one(self, state: FloatArray) -> float:
        """Crisp output (eq. 3) of one state ``(N,)`` with this controller's consequents.

        The fast path for a control loop that infers one state at a time (well under a
        microsecond a call); equal to ``output(state[None])[0]``.
        """
        # Any float64 (N,) array goes to the kernel as it is (it reads strides).
        if not (type(state) is np.ndarray and state.dtype is _FLOAT64
                and state.shape == self._state_shape):
            state = self._as_state(state)
        if not _kernels_on:
            return self._output_one_in_python(state)
        floats, ints, kernel = self._one
        value: float = kernel(floats, ints, state)
        if value != value:  # a NaN input, or no rule fires (never a NaN output)
            self._raise_undefined(state[None, :], 0)
        return value

    def _output_one_in_python(self, state: FloatArray) -> float:
        # output_one() without numpy's per-call costs: the rule base in plain Python (the
        # learners' path, the same bits), a few microseconds a state.
        started = time.thread_time()
        consequents = self._consequent_list  # NotDeployableError without them
        rules = self._rules
        values = state.tolist()
        if any(v != v for v in values):
            self._raise_nan(state[None, :])
        try:
            fired, alphas, _ = rules.activations(values)
        except InferenceError:  # no rule fires: said as the kernels' path says it
            self._raise_undefined(state[None, :], 0)
        value = rules.output(alphas, [consequents[m] for m in fired])
        _spent_in_numpy(time.thread_time() - started)
        return value

    @cached_property
    def _rules(self) -> SparseRules:
        from flctool.compile.sparse import SparseRules

        return SparseRules(self)

    @cached_property
    def _consequent_list(self) -> list[int]:
        return [int(k) for k in self.require_consequents()]

    @cached_property
    def _strides(self) -> tuple[int, ...]:
        # Rule index = sum(set index * stride), the last input fastest (eq. 1's order).
        shape = self.shape
        return tuple(math.prod(shape[i + 1:]) for i in range(len(shape)))

    def _infer_threaded(self, states: FloatArray, tables: IntArray, out: FloatArray,
                        threads: int) -> int:
        from concurrent.futures import ThreadPoolExecutor

        layout = self._layout
        bounds = np.linspace(0, states.shape[0], threads + 1).astype(int).tolist()
        infer = _kernel("infer")
        with ThreadPoolExecutor(threads) as pool:
            failures = list(pool.map(
                lambda start, stop: infer(states, layout.floats, layout.ints, tables, out, start,
                                          stop, layout.dense),
                bounds[:-1], bounds[1:]))
        return next((failed for failed in failures if failed >= 0), -1)

    @cached_property
    def _layout(self) -> Layout:
        from flctool.compile import kernels

        return kernels.layout(self.ranges, self.quadruples, self.rule_grid, self.singletons,
                              self.kinds, self.product)

    @cached_property
    def _tables(self) -> IntArray:
        # This controller's consequents as the (1, M) table the batched kernel takes.
        return np.array(self._consequents(None), dtype=np.intp).reshape(1, self.n_rules)

    @cached_property
    def _own(self) -> tuple[FloatArray, IntArray, Callable[..., int] | None, int]:
        # What output() passes with this controller's consequents, looked up once: the
        # layout's ints followed by the consequents (see kernels.infer_own), and the entry
        # (None without consequents: such calls take the general path, which raises).
        layout = self._layout
        if self.consequents is None:
            return layout.floats, layout.ints, None, self.n_inputs
        ints = np.concatenate([layout.ints, self._tables[0]])
        return layout.floats, ints, _kernel("infer_own"), self.n_inputs

    @cached_property
    def _one(self) -> tuple[FloatArray, IntArray, Callable[..., float]]:
        # What a one-state call passes, looked up once: a call pays only for its checks and
        # the kernel (the same packed arrays as infer_own's).
        self.require_consequents()  # NotDeployableError without them
        floats, ints, _, _ = self._own
        return floats, ints, _kernel("infer_one")

    @cached_property
    def _state_shape(self) -> tuple[int]:
        return (self.n_inputs,)

    def _as_state(self, state: FloatArray) -> FloatArray:
        x = np.array(state, dtype=np.float64)  # a copy: writable and contiguous, as compiled
        if x.shape != self._state_shape:
            x = self._as_states(x)[0].copy()  # (1, N) is accepted too; other shapes raise
        return x

    def _as_states(self, states: FloatArray) -> FloatArray:
        array = np.asarray(states, dtype=np.float64)
        if array.ndim == 1 and array.shape[0] == self.n_inputs:
            array = array[None, :]
        if array.ndim != 2 or array.shape[1] != self.n_inputs:
            raise InferenceError(
                f"states must have shape (B, {self.n_inputs}) for inputs "
                f"{', '.join(self.input_names)}; got shape {array.shape}")
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

    def require_consequents(self) -> IntArray:
        """This controller's consequents (M,); :class:`NotDeployableError` if its behaviour
        has none."""
        return self._consequents(None)

    def _consequents(self, consequents: IntArray | None) -> IntArray:
        if consequents is None:
            if self.consequents is None:
                raise NotDeployableError(
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
                                self.rule_grid, self.singletons, _frozen(table.copy()),
                                self.kinds, self.product)
        for shared in ("_layout", "_rules", "_strides"):  # same sets: share what depends on them
            if shared in self.__dict__:
                controller.__dict__[shared] = self.__dict__[shared]
        return controller


@cache
def _kernel(name: str) -> Callable[..., Any]:
    # A kernel's compiled entry point, found once a process and only when first used
    # (importing numba, and compiling or loading the cached machine code of that kernel).
    with kernel_loading():
        from flctool.compile import kernels

        return kernels.entry(name)


def compile_behaviour(behaviour: Behaviour) -> Controller:
    """Compile a validated behaviour into a :class:`Controller`."""
    names = tuple(behaviour.inputs)
    set_names = tuple(tuple(v.sets) for v in behaviour.inputs.values())
    shape = tuple(len(s) for s in set_names)
    grid = np.array(rule_grid(shape), dtype=np.intp).reshape(math.prod(shape), len(shape))
    commands = tuple(behaviour.output.commands)
    order = rule_consequents(behaviour)
    consequents = None if order is None else _frozen(np.array(order, dtype=np.intp))
    rows = [[set_row(value) for value in v.sets.values()] for v in behaviour.inputs.values()]
    kinds = tuple(tuple(code for code, _ in sets) for sets in rows)
    return Controller(
        input_names=names,
        set_names=set_names,
        output_name=behaviour.output.name,
        command_names=commands,
        # (the declared ranges, moved inside an end that no set fires: evaluated_range)
        ranges=_frozen(np.array([evaluated_range(v.range, v.sets.values())
                                 for v in behaviour.inputs.values()],
                                dtype=np.float64)),
        quadruples=tuple(_frozen(np.array([p for _, p in sets], dtype=np.float64))
                         for sets in rows),
        rule_grid=_frozen(grid),
        singletons=_frozen(np.array(list(behaviour.output.commands.values()), dtype=np.float64)),
        consequents=consequents,
        kinds=kinds if any(any(k) for k in kinds) else None,
        product=behaviour.activation == "product",
    )
