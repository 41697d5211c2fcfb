"""Compiled inference kernels: eq. 1-3 over only the rules that fire.

With overlapping trapezoids only a few sets of each input have non-zero membership, so only
the rules combining those sets fire (at most 2^N of the M = prod(L_i) rules). The kernels find
each input's non-zero sets (O(sum L_i) per state), enumerate the fired rules in increasing rule
order (the product of the fired sets, last input fastest, as in the rule grid) and never touch
the others: a step costs O(sum L_i + active rules), not O(M), and no (B, M) array is made.
Any number of overlapping sets is handled; two per input is only the common case.

The arithmetic is the plain reference's, operation for operation, so results are identical,
not merely close: the trapezoid's divisions as written (no precomputed inverses), min for
eq. 2, and for eq. 3 the sums sum(alpha_m * c_m) and sum(alpha_m) accumulated from 0.0 in
increasing rule order. Skipping a rule with alpha_m = 0 adds nothing to either sum (x + 0.0 is
x), which is why the sparse sums equal the dense ones bit for bit.

This module imports numba; :mod:`flctool.compile.controller` imports it only when inference
runs, so commands that do not infer do not pay for numba's import. ``cache=True`` keeps the
compiled machine code in numba's cache, so only the first run on a machine compiles.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple, TypeVar, cast

import numba
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
_F = TypeVar("_F", bound=Callable[..., Any])


def _jit(function: _F) -> _F:
    # error_model="numpy": a division by zero gives inf/NaN like numpy instead of a Python
    # exception check on every division (the partitions are validated to cover the ranges,
    # so sum(alpha) > 0 unless memberships underflow, which the kernels report).
    return cast(_F, numba.njit(cache=True, nogil=True, error_model="numpy")(function))


@_jit
def _membership(s: float, pa: float, pb: float, pc: float, pd: float) -> float:
    # trapezoid_scalar's branches. The tests s >= pd and s <= pa return 0.0 exactly where the
    # reference's max(0, .) would (its quotient is <= 0 there, or its edge is vertical), and
    # skip a division for the many sets far from s; elsewhere the same quotient is computed.
    if s > pc:
        if s >= pd:
            return 0.0
        return (pd - s) / (pd - pc)
    if s < pb:
        if s <= pa:
            return 0.0
        return (s - pa) / (pb - pa)
    return 1.0


@_jit
def _fired_sets(states: FloatArray, b: int, lo: FloatArray, hi: FloatArray,
                quads: FloatArray, offsets: IntArray, sets: IntArray, mus: FloatArray,
                counts: IntArray) -> int:
    """Each input's non-zero sets for state ``b``: into ``sets``/``mus`` (N, max L_i) and
    ``counts`` (N,). Returns the index of an input that is NaN, or -1."""
    for i in range(states.shape[1]):
        s = states[b, i]
        if s != s:
            return i
        # Clipping as np.clip does: a sensor past its end (or +-inf) reads as the end.
        s = min(max(s, lo[i]), hi[i])
        count = 0
        first = offsets[i]
        for j in range(first, offsets[i + 1]):
            mu = _membership(s, quads[j, 0], quads[j, 1], quads[j, 2], quads[j, 3])
            if mu > 0.0:
                sets[i, count] = j - first
                mus[i, count] = mu
                count += 1
        counts[i] = count
    return -1


@_jit
def _fired_rules(sets: IntArray, mus: FloatArray, counts: IntArray, strides: IntArray,
                 rules: IntArray, alphas: FloatArray) -> int:
    """The fired rules in increasing rule order into ``rules``/``alphas`` (capacity >=
    prod(counts)); returns how many. Eq. 1 (rule index) and eq. 2 (Mamdani min).

    The product of the fired sets, built input by input: after input i the buffers hold the
    combinations of inputs 0..i in rule order, and input i + 1 splits each entry into one per
    fired set. Expanding from the back lets that happen in place, and the loops have no
    data-dependent exits, so the branch predictor follows them.
    """
    size = 1
    rules[0] = 0
    alphas[0] = np.inf
    for i in range(counts.shape[0]):
        count = counts[i]
        stride = strides[i]
        for entry in range(size - 1, -1, -1):
            rule = rules[entry]
            alpha = alphas[entry]
            for slot in range(count - 1, -1, -1):
                rules[entry * count + slot] = rule + sets[i, slot] * stride
                alphas[entry * count + slot] = min(alpha, mus[i, slot])
        size *= count
    return size


@_jit
def _work(n: int, max_sets: int) -> tuple[IntArray, FloatArray, IntArray]:
    return np.empty((n, max_sets), np.intp), np.empty((n, max_sets)), np.empty(n, np.intp)


@_jit
def _capacity(counts: IntArray) -> int:
    # Room for every stage of _fired_rules' expansion (an input with no fired set, which
    # covering partitions rule out, would empty it only after the earlier ones grew it).
    total = 1
    for count in counts:
        total *= max(count, 1)
    return total


_BLOCK = 32  # states whose memberships are computed together (fits in L1 with ~40 sets)


@_jit
def _block_memberships(states: FloatArray, start: int, count: int, lo: FloatArray,
                       hi: FloatArray, quads: FloatArray, offsets: IntArray, xs: FloatArray,
                       mu: FloatArray) -> int:
    """Memberships of states[start:start + count] in every set, into ``mu (S, _BLOCK)``.

    Returns -1, or the index of the first state with a NaN input. Branch-free, so the loop
    over states vectorises: the reference's branches become selects of the numerator and
    width, then one division (on the middle plateau it may be 0/0 or x/0, and is dropped for
    1.0). Where a selected quotient divides by a vertical edge's zero width, s is past that
    edge, the quotient is -inf and max(., 0) gives the reference's 0.
    """
    for i in range(states.shape[1]):
        nan = False
        for b in range(count):
            s = states[start + b, i]
            nan |= s != s
            xs[i, b] = min(max(s, lo[i]), hi[i])
        if nan:
            for b in range(count):
                for k in range(states.shape[1]):
                    if states[start + b, k] != states[start + b, k]:
                        return start + b
    for i in range(states.shape[1]):
        for j in range(offsets[i], offsets[i + 1]):
            pa, pb, pc, pd = quads[j, 0], quads[j, 1], quads[j, 2], quads[j, 3]
            for b in range(count):
                s = xs[i, b]
                above = s > pc
                numerator = (pd - s) if above else (s - pa)
                width = (pd - pc) if above else (pb - pa)
                value = numerator / width if above or s < pb else 1.0
                mu[j, b] = max(value, 0.0)
    return -1


@_jit
def _compact(mu: FloatArray, b: int, offsets: IntArray, sets: IntArray, mus: FloatArray,
             counts: IntArray) -> None:
    """Each input's non-zero sets of block state ``b`` (as :func:`_fired_sets`). Branch-free:
    every set is written and the count advances only when mu > 0."""
    for i in range(counts.shape[0]):
        count = 0
        first = offsets[i]
        for j in range(first, offsets[i + 1]):
            value = mu[j, b]
            sets[i, count] = j - first
            mus[i, count] = value
            count += value > 0.0
        counts[i] = count


# Up to this many rules, inference walks every rule for a block of states at once (a loop
# over states that vectorises, ~1 ns per rule and state), which beats finding the fired rules
# state by state; above it, only the fired rules are walked, so the cost follows them, not M.
DENSE_RULES = 32


@_jit
def _within(value: float, low: float, high: float) -> float:
    # Eq. 3 is a convex combination of the singletons, but rounding can step past the
    # smallest or largest by an ulp; a command past the robot's largest is never sent.
    return low if value < low else high if value > high else value


@_jit
def _dense_block(start: int, count: int, mu: FloatArray, grid: IntArray, table: IntArray,
                 singletons: FloatArray, alpha: FloatArray, numerators: FloatArray,
                 denominators: FloatArray, out: FloatArray) -> None:
    """Eq. 2-3 over every rule for a block of states: ``grid (M, N)`` holds each rule's
    rows of ``mu``. Each state's sums run over the rules in increasing order, as the
    reference's do. ``denominators[:count]`` keeps each state's sum(alpha)."""
    numerators[:, :count] = 0.0
    denominators[:count] = 0.0
    for m in range(grid.shape[0]):
        first = grid[m, 0]
        for b in range(count):
            alpha[b] = mu[first, b]
        for i in range(1, grid.shape[1]):
            row = grid[m, i]
            for b in range(count):
                alpha[b] = min(alpha[b], mu[row, b])
        for b in range(count):
            denominators[b] += alpha[b]
        for p in range(table.shape[0]):
            value = singletons[table[p, m]]
            for b in range(count):
                numerators[p, b] += alpha[b] * value
    low, high = singletons.min(), singletons.max()
    for p in range(table.shape[0]):
        for b in range(count):
            out[p, start + b] = _within(numerators[p, b] / denominators[b], low, high)


@_jit
def _first_zero(denominators: FloatArray, count: int, start: int) -> int:
    # A reduction without a branch per state (it vectorises); the search runs only when
    # some sum(alpha) is 0, i.e. no rule fired (see infer).
    empty = False
    for b in range(count):
        empty |= denominators[b] == 0.0
    if empty:
        for b in range(count):
            if denominators[b] == 0.0:
                return start + b
    return -1


@_jit
def _sparse_block(start: int, count: int, mu: FloatArray, offsets: IntArray,
                  strides: IntArray, max_sets: int, table: IntArray, singletons: FloatArray,
                  numerators: FloatArray, out: FloatArray) -> int:
    """Eq. 2-3 over only the fired rules, state by state, for a block of states. Returns -1,
    or the first state where no rule fires (see :func:`infer`)."""
    n = strides.shape[0]
    population = table.shape[0]
    sets, mus, counts = _work(n, max_sets)
    rules = np.empty(64, np.intp)  # grown below when more rules fire
    alphas = np.empty(64)
    low, high = singletons.min(), singletons.max()
    for b in range(count):
        _compact(mu, b, offsets, sets, mus, counts)
        capacity = _capacity(counts)
        if capacity > rules.shape[0]:
            rules = np.empty(capacity, np.intp)
            alphas = np.empty(capacity)
        fired = _fired_rules(sets, mus, counts, strides, rules, alphas)
        numerators[:, 0] = 0.0
        denominator = 0.0
        for a in range(fired):
            rule = rules[a]
            alpha = alphas[a]
            denominator += alpha
            for p in range(population):
                numerators[p, 0] += alpha * singletons[table[p, rule]]
        if denominator == 0.0:
            return start + b
        for p in range(population):
            out[p, start + b] = _within(numerators[p, 0] / denominator, low, high)
    return -1


@_jit
def infer(states: FloatArray, lo: FloatArray, hi: FloatArray, quads: FloatArray,
          offsets: IntArray, strides: IntArray, max_sets: int, grid: IntArray,
          table: IntArray, singletons: FloatArray, out: FloatArray) -> int:
    """Eq. 3 for ``states (B, N)`` and consequent tables ``table (P, M)``: writes ``out (P, B)``.

    ``grid (M, N)``, each rule's sets as rows of ``quads``, walks every rule; an empty
    ``grid (0, N)`` walks only the fired rules (see DENSE_RULES).
    Returns -1, or the index of the first state whose output is undefined (``out`` is then
    partial): a state with a NaN input, or one where every activation is 0. Validated
    partitions cover their ranges, so the latter happens only when the memberships underflow
    (sets thousands of orders of magnitude apart) -- the caller raises rather than return
    the NaN that 0 / 0 would give.
    """
    n = states.shape[1]
    dense = grid.shape[0] > 0
    xs = np.empty((n, _BLOCK))
    mu = np.empty((quads.shape[0], _BLOCK))
    alpha = np.empty(_BLOCK)
    numerators = np.empty((table.shape[0], _BLOCK))
    denominators = np.empty(_BLOCK)
    for start in range(0, states.shape[0], _BLOCK):
        count = min(_BLOCK, states.shape[0] - start)
        nan_state = _block_memberships(states, start, count, lo, hi, quads, offsets, xs, mu)
        if nan_state >= 0:
            return nan_state
        if dense:
            _dense_block(start, count, mu, grid, table, singletons, alpha, numerators,
                         denominators, out)
            failed = _first_zero(denominators, count, start)
        else:
            failed = _sparse_block(start, count, mu, offsets, strides, max_sets, table,
                                   singletons, numerators, out)
        if failed >= 0:
            return failed
    return -1


@_jit
def _unpack(floats: FloatArray, ints: IntArray) -> tuple[FloatArray, FloatArray, FloatArray,
                                                         FloatArray, int, IntArray, IntArray]:
    # Views of Layout.floats / Layout.ints: one-state calls pass two arrays instead of seven,
    # because numba's per-argument dispatch cost is most of a one-state call.
    n, sets = ints[0], ints[1]
    quads = floats[2 * n : 2 * n + 4 * sets].reshape((sets, 4))
    return (floats[:n], floats[n : 2 * n], quads, floats[2 * n + 4 * sets :], ints[2],
            ints[3 : 4 + n], ints[4 + n : 4 + 2 * n])


@_jit
def infer_one(floats: FloatArray, ints: IntArray, table: IntArray, state: FloatArray) -> float:
    """Eq. 3 for one ``state (N,)`` with one ``table (M,)``; NaN if an input is NaN or no
    rule fires (every activation underflowed to 0: see :func:`infer`).

    ``floats``/``ints`` are :class:`Layout`'s packed arrays."""
    lo, hi, quads, singletons, max_sets, offsets, strides = _unpack(floats, ints)
    sets, mus, counts = _work(state.shape[0], max_sets)
    if _fired_sets(state.reshape((1, state.shape[0])), 0, lo, hi, quads, offsets, sets, mus,
                   counts) >= 0:
        return np.nan
    capacity = _capacity(counts)
    rules = np.empty(capacity, np.intp)
    alphas = np.empty(capacity)
    fired = _fired_rules(sets, mus, counts, strides, rules, alphas)
    numerator = 0.0
    denominator = 0.0
    for a in range(fired):
        numerator += alphas[a] * singletons[table[rules[a]]]
        denominator += alphas[a]
    return _within(numerator / denominator, singletons.min(), singletons.max())


@_jit
def active_one(floats: FloatArray, ints: IntArray,
               state: FloatArray) -> tuple[IntArray, FloatArray, int]:
    """The fired rules of one ``state (N,)`` in increasing order and their activations
    (eq. 2): ``(rules (A,), alpha (A,), nan_input)``, ``nan_input`` -1 unless an input is NaN.
    """
    lo, hi, quads, _, max_sets, offsets, strides = _unpack(floats, ints)
    sets, mus, counts = _work(state.shape[0], max_sets)
    nan_input = _fired_sets(state.reshape((1, state.shape[0])), 0, lo, hi, quads, offsets,
                            sets, mus, counts)
    if nan_input >= 0:
        return np.empty(0, np.intp), np.empty(0), nan_input
    capacity = _capacity(counts)
    rules = np.empty(capacity, np.intp)
    alphas = np.empty(capacity)
    # Fewer than the capacity only if an input has no non-zero set (memberships underflowed).
    fired = _fired_rules(sets, mus, counts, strides, rules, alphas)
    return rules[:fired], alphas[:fired], -1


@_jit
def activations(states: FloatArray, lo: FloatArray, hi: FloatArray, quads: FloatArray,
                offsets: IntArray, strides: IntArray, max_sets: int, out: FloatArray) -> int:
    """Dense eq. 2 for ``states (B, N)`` into a zeroed ``out (B, M)``; returns -1 or the
    first state with a NaN input."""
    sets, mus, counts = _work(states.shape[1], max_sets)
    rules = np.empty(16, np.intp)
    alphas = np.empty(16)
    for b in range(states.shape[0]):
        if _fired_sets(states, b, lo, hi, quads, offsets, sets, mus, counts) >= 0:
            return b
        capacity = _capacity(counts)
        if capacity > rules.shape[0]:
            rules = np.empty(capacity, np.intp)
            alphas = np.empty(capacity)
        fired = _fired_rules(sets, mus, counts, strides, rules, alphas)
        for a in range(fired):
            out[b, rules[a]] = alphas[a]
    return -1


class Layout(NamedTuple):
    """A controller's sets laid out for the kernels (S = sum L_i sets in all)."""

    lo: FloatArray  # (N,) range lows
    hi: FloatArray  # (N,) range highs
    quads: FloatArray  # (S, 4) every input's sets, input after input
    offsets: IntArray  # (N + 1,) input i's sets are quads[offsets[i]:offsets[i + 1]]
    strides: IntArray  # (N,) rule index = sum(set index * stride), last input fastest
    max_sets: int  # max L_i
    grid: IntArray  # (M, N) each rule's rows of quads if M <= DENSE_RULES, else (0, N)
    singletons: FloatArray  # (K,)
    floats: FloatArray  # lo, hi, quads, singletons in one array (for one-state kernels)
    ints: IntArray  # N, S, max_sets, offsets, strides in one array (for one-state kernels)


def layout(ranges: FloatArray, quadruples: tuple[FloatArray, ...], rule_grid: IntArray,
           singletons: FloatArray) -> Layout:
    """Lay out ``ranges (N, 2)``, ``quadruples`` (N arrays (L_i, 4)), ``rule_grid (M, N)`` and
    ``singletons (K,)`` for the kernels: writable C arrays, so that each kernel is compiled
    for one signature only."""
    sizes = [len(q) for q in quadruples]
    strides = np.ones(len(sizes), dtype=np.intp)
    for i in range(len(sizes) - 2, -1, -1):
        strides[i] = strides[i + 1] * sizes[i + 1]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
    small = rule_grid.shape[0] <= DENSE_RULES
    grid = rule_grid + offsets[:-1] if small else np.empty((0, len(sizes)), dtype=np.intp)
    lo = np.array(ranges[:, 0], dtype=np.float64)
    hi = np.array(ranges[:, 1], dtype=np.float64)
    quads = np.array(np.concatenate(quadruples), dtype=np.float64)
    values = np.array(singletons, dtype=np.float64)
    header = np.array([len(sizes), len(quads), max(sizes)], dtype=np.intp)
    return Layout(lo=lo, hi=hi, quads=quads, offsets=offsets, strides=strides,
                  max_sets=max(sizes), grid=np.array(grid, dtype=np.intp), singletons=values,
                  floats=np.concatenate([lo, hi, quads.ravel(), values]),
                  ints=np.concatenate([header, offsets, strides]).astype(np.intp))
