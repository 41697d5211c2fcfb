"""Compiled inference kernels: eq. 1-3, bit for bit, at every batch size.

Four ways through, each chosen where it is cheapest:

- **a few states** (:func:`infer_one`; with the controller's own consequents
  :func:`infer_own` up to ``OWN_SMALL_BATCH_FEW_INPUTS`` or ``OWN_SMALL_BATCH`` states;
  with a population :func:`infer` up to ``SMALL_BATCH``, ``SMALL_DENSE_BATCH`` for a small
  rule base walked every rule): state by state, each
  input's non-zero sets found (with overlapping trapezoids 1 to 3 of an input's sets), then
  only the rules combining them summed -- an odometer over the fired sets, last input
  fastest, which is increasing rule order;
- **a few states of a small rule base** (:func:`_interleaved_states`, with the own
  consequents; see ``TINY_BATCH``): every rule of each state -- the naive loop, four states
  at a time, and from ``SPLIT_RULE_INPUTS`` as two halves, one min a rule -- cheaper there
  than finding the fired rules (when most rules fire, as with many inputs of 2 sets) or
  setting up the blocks;
- **blocks of states, every rule**: for small rule bases (:func:`walks_every_rule`), the
  memberships and then eq. 2-3 of every rule for ``_BLOCK`` states at once, in loops over
  the states that vectorise;
- **blocks of states, fired rules**: for larger rule bases, the memberships for a block at
  once, then each state's fired rules only: the cost follows the fired rules, not M, and no
  (B, M) array is made.

The arithmetic is the plain reference's, operation for operation, so results are identical,
not merely close: the trapezoid's divisions as written (no precomputed inverses), min for
eq. 2 (or, for a behaviour with ``activation: product``, the product of the memberships
multiplied in input order, ((mu_1 * mu_2) * mu_3) ..., on every walk), and for eq. 3 the
sums sum(alpha_m * c_m) and sum(alpha_m) accumulated from 0.0 in increasing rule order.
Skipping a rule with alpha_m = 0 adds nothing to either sum (x + 0.0 is x), which is why
the sparse sums equal the dense ones bit for bit.

Each kernel is used with one signature (:data:`SIGNATURES`), and :func:`entry` gives its
compiled entry point, which the controller calls without numba's dispatch. This module
imports numba; :mod:`flctool.compile.controller` imports it only when inference runs, so
commands that do not infer do not pay for numba's import. ``cache=True`` keeps the compiled
machine code in numba's cache, so only the first run on a machine compiles. The kernels
release the GIL, so threads can infer parts of a batch at once.
"""

from __future__ import annotations

import math
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
def _membership_free(s: float, pa: float, pb: float, pc: float, pd: float) -> float:
    # _membership without branches (random states make its branches unpredictable): the
    # reference's branches become selects of the numerator and width, then one division (on
    # the middle plateau it may be 0/0 or x/0, and is dropped for 1.0). Where a selected
    # quotient divides by a vertical edge's zero width, s is past that edge, the quotient is
    # -inf and max(., 0) gives the reference's 0.
    above = s > pc
    numerator = (pd - s) if above else (s - pa)
    width = (pd - pc) if above else (pb - pa)
    value = numerator / width if above or s < pb else 1.0
    return max(value, 0.0)


@_jit
def _sigmoid(x: float, centre: float, slope: float) -> float:
    return 1.0 / (1.0 + math.exp(-slope * (x - centre)))


@_jit
def _s_shape(x: float, a: float, b: float) -> float:
    if x <= a:
        return 0.0
    if x <= (a + b) / 2.0:
        t = (x - a) / (b - a)
        return 2.0 * t * t
    if x < b:
        u = (x - b) / (b - a)
        return 1.0 - 2.0 * u * u
    return 1.0


@_jit
def _z_shape(x: float, a: float, b: float) -> float:
    if x <= a:
        return 1.0
    if x <= (a + b) / 2.0:
        t = (x - a) / (b - a)
        return 1.0 - 2.0 * t * t
    if x < b:
        u = (x - b) / (b - a)
        return 2.0 * u * u
    return 0.0


@_jit
def _gauss(x: float, mean: float, sigma: float) -> float:
    return math.exp(-((x - mean) * (x - mean)) / (2.0 * sigma * sigma))


@_jit
def _shaped(kind: int, p0: float, p1: float, p2: float, p3: float, x: float) -> float:
    # membership.shape_membership, operation for operation (math.exp and ** are the C
    # library's exp and pow, as Python's are, so the bits are the same)
    if kind == 1:
        return _gauss(x, p0, p1)
    if kind == 2:
        left = _gauss(x, p0, p1) if x < p0 else 1.0
        right = _gauss(x, p2, p3) if x > p2 else 1.0
        return left * right
    if kind == 3:
        power: float = abs((x - p2) / p0) ** (2.0 * p1)
        return 1.0 / (1.0 + power)
    if kind == 4:
        return _sigmoid(x, p0, p1)
    if kind == 5:
        return abs(_sigmoid(x, p0, p1) - _sigmoid(x, p2, p3))
    if kind == 6:
        return _sigmoid(x, p0, p1) * _sigmoid(x, p2, p3)
    if kind == 7:
        return _s_shape(x, p0, p1)
    if kind == 8:
        return _z_shape(x, p0, p1)
    if kind == 9:
        return _s_shape(x, p0, p1) * _z_shape(x, p2, p3)
    if kind == 10:
        if x < p0 - 0.5 * p1 or x > p0 + 0.5 * p1:
            return 0.0
        return 0.5 * (1.0 + math.cos(2.0 / p1 * math.pi * (x - p0)))
    if kind == 11:
        if p0 <= p1:
            if x < p1:
                return (p1 - p0) / (2.0 * p1 - p0 - x)
        elif x > p1:
            return (p0 - p1) / (p0 - 2.0 * p1 + x)
        return 1.0
    return math.exp(-abs(10.0 / p1 * (x - p0)))


@_jit
def _and(product: bool, alpha: float, mu: float) -> float:
    # Eq. 2's combination of a rule's memberships, one input at a time in input order: the
    # min, or with activation: product their product. Starting from _unit, the first input
    # gives its membership exactly (min(inf, mu) and 1.0 * mu are mu), so every walk folds
    # the same operations in the same order.
    return alpha * mu if product else min(alpha, mu)


@_jit
def _unit(product: bool) -> float:
    return 1.0 if product else np.inf


@_jit
def _fired_sets(states: FloatArray, b: int, lo: FloatArray, hi: FloatArray,
                quads: FloatArray, kinds: IntArray, offsets: IntArray, sets: IntArray,
                mus: FloatArray, counts: IntArray) -> int:
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
            if kinds[j]:  # a shape other than the trapezoid (flctool.behaviour.shapes)
                mu = _shaped(kinds[j], quads[j, 0], quads[j, 1], quads[j, 2], quads[j, 3], s)
            else:
                mu = _membership(s, quads[j, 0], quads[j, 1], quads[j, 2], quads[j, 3])
            if mu > 0.0:
                sets[i, count] = j - first
                mus[i, count] = mu
                count += 1
        counts[i] = count
    return -1


@_jit
def _fired_rules(sets: IntArray, mus: FloatArray, counts: IntArray, strides: IntArray,
                 rules: IntArray, alphas: FloatArray, product: bool) -> int:
    """The fired rules in increasing rule order into ``rules``/``alphas`` (capacity >=
    prod(counts)); returns how many. Eq. 1 (rule index) and eq. 2 (Mamdani min, or the
    product with ``product``).

    The product of the fired sets, built input by input: after input i the buffers hold the
    combinations of inputs 0..i in rule order, and input i + 1 splits each entry into one per
    fired set. Expanding from the back lets that happen in place, and the loops have no
    data-dependent exits, so the branch predictor follows them.
    """
    size = 1
    rules[0] = 0
    alphas[0] = _unit(product)
    for i in range(counts.shape[0]):
        count = counts[i]
        stride = strides[i]
        for entry in range(size - 1, -1, -1):
            rule = rules[entry]
            alpha = alphas[entry]
            for slot in range(count - 1, -1, -1):
                rules[entry * count + slot] = rule + sets[i, slot] * stride
                alphas[entry * count + slot] = _and(product, alpha, mus[i, slot])
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


# Layout.ints starts with N, S, max L_i, M if the rule grid is kept (else 0), whether a few
# states are walked every rule four at a time (interleaves_states: 0 no, 1 yes,
# EVERY_RULE_FIRES yes and every rule can fire at once) and whether eq. 2 is the product
# (activation: product; else the min), then the offsets.
_HEADER = 6
_PRODUCT = 5  # where that last flag is

_BLOCK = 64  # states whose memberships are computed together (fits in L1 with ~40 sets)


@_jit
def _block_memberships(states: FloatArray, start: int, count: int, lo: FloatArray,
                       hi: FloatArray, quads: FloatArray, kinds: IntArray, offsets: IntArray,
                       xs: FloatArray, mu: FloatArray) -> int:
    """Memberships of states[start:start + count] in every set, into ``mu (S, _BLOCK)``.

    Returns -1, or the index of the first state with a NaN input. Branch-free
    (:func:`_membership_free`), so the loop over states vectorises.
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
            kind = kinds[j]
            if kind:  # a shape other than the trapezoid (flctool.behaviour.shapes)
                for b in range(count):
                    mu[j, b] = _shaped(kind, pa, pb, pc, pd, xs[i, b])
                continue
            for b in range(count):
                mu[j, b] = _membership_free(xs[i, b], pa, pb, pc, pd)
    return -1


@_jit
def _compact(mu: FloatArray, b: int, ints: IntArray, scratch: IntArray,
             mus: FloatArray) -> bool:
    """Each input's non-zero sets of block state ``b``, as :func:`_state_sets` writes them
    into ``scratch`` and ``mus``; False if an input has none (memberships underflowed).
    Branch-free: every set is written and the count advances only when mu > 0."""
    n, max_sets = ints[0], ints[2]
    for i in range(n):
        count = 0
        first = ints[_HEADER + i]
        for j in range(first, ints[_HEADER + 1 + i]):
            value = mu[j, b]
            scratch[i * max_sets + count] = j - first
            mus[i * max_sets + count] = value
            count += value > 0.0
        if count == 0:
            return False
        scratch[n * max_sets + i] = count
        scratch[n * max_sets + n + i] = 0
    return True


# Batched inference walks every rule for a block of states at once (loops over states that
# vectorise, 0.11 to 0.22 ns per rule, input and state) while that costs less than finding
# each state's fired rules and walking only those (about 1.2 ns per set, plus a cost per
# state that grows with each input, whatever M is). The costs below were measured on both
# walks for every N <= 8 and L <= 9 with M <= MAX_RULES (1,000 states a batch;
# benchmarks/bench_scaling.py --sweep measures them again and prints the walk each size
# takes); with the switch where they cross, going past it costs no more than staying (no
# cliff). Past 8 inputs the cost per state is extrapolated (x1.7 per input, as from 7 to 8).
_DENSE_NS_PER_RULE_INPUT = (0.17, 0.17, 0.17, 0.2)  # index: N (more: the last); 2 fused
_SPARSE_NS_PER_SET = 1.2
_SPARSE_NS_BY_INPUTS = (0.0, 140.0, 150.0, 200.0, 250.0, 330.0, 460.0, 720.0, 1230.0)  # N
_SPARSE_GROWTH_PAST_LAST = 1.7


def walks_every_rule(n_rules: int, n_inputs: int, n_sets: int) -> bool:
    """Whether batched inference walks every rule (else only each state's fired rules):
    the estimated cheaper one for M rules, N inputs and S sets in all."""
    last = len(_SPARSE_NS_BY_INPUTS) - 1
    per_state = (_SPARSE_NS_BY_INPUTS[min(n_inputs, last)]
                 * _SPARSE_GROWTH_PAST_LAST ** max(0, n_inputs - last))
    sparse = _SPARSE_NS_PER_SET * n_sets + per_state
    dense = _DENSE_NS_PER_RULE_INPUT[min(n_inputs, len(_DENSE_NS_PER_RULE_INPUT) - 1)]
    return dense * n_rules * n_inputs <= sparse


@_jit
def _within(value: float, low: float, high: float) -> float:
    # Eq. 3 is a convex combination of the singletons, but rounding can step past the
    # smallest or largest by an ulp; a command past the robot's largest is never sent.
    return low if value < low else high if value > high else value


@_jit
def _dense_block(count: int, mu: FloatArray, grid: IntArray, values: FloatArray,
                 alpha: FloatArray, numerators: FloatArray, denominators: FloatArray,
                 product: bool) -> None:
    """Eq. 2-3 over every rule for a block of states: ``grid (M, N)`` holds each rule's
    rows of ``mu``, ``values (P, M)`` each rule's singleton c_m. Each state's sums run over
    the rules in increasing order, as the reference's do, into ``numerators[:, :count]``
    and ``denominators[:count]``. Each rule's min, sum(alpha) and sum(alpha * c) are one
    loop over the states, so they stay in registers. With ``product`` eq. 2 multiplies the
    memberships in input order instead (separate loops, so that each still vectorises)."""
    numerators[:, :count] = 0.0
    denominators[:count] = 0.0
    n = grid.shape[1]
    population = values.shape[0]
    for m in range(grid.shape[0]):
        first = grid[m, 0]
        if n <= 2 and population == 1 and not product:  # the common case, fused into one loop
            second = grid[m, n - 1]  # the first row again when n == 1: min(a, a) is a
            value = values[0, m]
            for b in range(count):
                a = min(mu[first, b], mu[second, b])
                denominators[b] += a
                numerators[0, b] += a * value
            continue
        if n == 2 and population == 1:  # the same, for the product
            second = grid[m, 1]
            value = values[0, m]
            for b in range(count):
                a = mu[first, b] * mu[second, b]
                denominators[b] += a
                numerators[0, b] += a * value
            continue
        for b in range(count):
            alpha[b] = mu[first, b]
        for i in range(1, n):
            row = grid[m, i]
            if product:
                for b in range(count):
                    alpha[b] = alpha[b] * mu[row, b]
            else:
                for b in range(count):
                    alpha[b] = min(alpha[b], mu[row, b])
        for b in range(count):
            denominators[b] += alpha[b]
        for p in range(population):
            value = values[p, m]
            for b in range(count):
                numerators[p, b] += alpha[b] * value


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
def _unpack(floats: FloatArray, ints: IntArray) -> tuple[FloatArray, FloatArray, FloatArray,
                                                         FloatArray, int, IntArray, IntArray,
                                                         IntArray, IntArray]:
    # Views of Layout.floats / Layout.ints: calls pass two arrays instead of eight, because
    # unboxing each argument is a good part of a small call.
    n, sets, max_sets, dense_rules = ints[0], ints[1], ints[2], ints[3]
    quads = floats[2 * n : 2 * n + 4 * sets].reshape((sets, 4))
    kinds = _HEADER + 1 + 2 * n  # where the sets' shape codes start in ints
    grid = ints[kinds + sets : kinds + sets + dense_rules * n].reshape((dense_rules, n))
    return (floats[:n], floats[n : 2 * n], quads, floats[2 * n + 4 * sets :], max_sets,
            ints[_HEADER : _HEADER + 1 + n], ints[_HEADER + 1 + n : _HEADER + 1 + 2 * n], grid,
            ints[kinds : kinds + sets])


@_jit
def infer(states: FloatArray, floats: FloatArray, ints: IntArray, tables: IntArray,
          out: FloatArray, start: int, stop: int, dense: bool) -> int:
    """Eq. 3 for ``states[start:stop]`` (of ``states (B, N)``) and consequent tables
    ``tables (P, M)``: writes ``out[p * B + b]`` of ``out (P * B,)``, i.e. (P, B) flat.

    ``floats``/``ints`` are :class:`Layout`'s packed arrays. ``dense`` walks every rule (the
    layout must hold the rule grid: :func:`walks_every_rule`); otherwise only the fired
    rules are walked. Returns -1, or the index of the first state whose output is undefined
    (``out`` is then partial): a state with a NaN input, or one where every activation is 0.
    Validated partitions cover their ranges, so the latter happens only when the memberships
    underflow (sets thousands of orders of magnitude apart) -- the caller raises rather than
    return the NaN that 0 / 0 would give.
    """
    small = SMALL_BATCH
    if dense and ints[3] * ints[0] <= CHEAP_DENSE_RULE_INPUTS:
        small = SMALL_DENSE_BATCH  # a cheap walk of every rule: blocks pay off sooner
    if stop - start <= small:
        return _infer_small(states, floats, ints, tables, out, start, stop)
    return _infer_blocks(states, floats, ints, tables, out, start, stop, dense)


@_jit
def _infer_blocks(states: FloatArray, floats: FloatArray, ints: IntArray, tables: IntArray,
                  out: FloatArray, start: int, stop: int, dense: bool) -> int:
    # infer() block by block (_BLOCK states share the memberships' loops).
    lo, hi, quads, singletons, max_sets, offsets, _, grid, kinds = _unpack(floats, ints)
    n = states.shape[1]
    population = tables.shape[0]
    batch = states.shape[0]
    low, high = singletons.min(), singletons.max()
    dense = dense and grid.shape[0] > 0
    rules = grid.shape[0] if dense else 0
    # One allocation for the work arrays (a small call would otherwise spend much of its
    # time allocating): xs (N, _BLOCK), mu (S, _BLOCK), alpha, denominators (_BLOCK,),
    # numerators (P, _BLOCK), values (P, M) and mus (N * max L_i,).
    n_sets = quads.shape[0]
    work = np.empty((n + n_sets + 2 + population) * _BLOCK + population * rules
                       + n * max_sets)
    at = (n + n_sets) * _BLOCK
    xs = work[: n * _BLOCK].reshape((n, _BLOCK))
    mu = work[n * _BLOCK : at].reshape((n_sets, _BLOCK))
    alpha = work[at : at + _BLOCK]
    denominators = work[at + _BLOCK : at + 2 * _BLOCK]
    at += 2 * _BLOCK
    numerators = work[at : at + population * _BLOCK].reshape((population, _BLOCK))
    at += population * _BLOCK
    values = work[at : at + population * rules].reshape((population, rules))
    mus = work[at + population * rules :]
    for p in range(population):  # each rule's c_m, looked up once rather than once a block
        for m in range(rules):
            values[p, m] = singletons[tables[p, m]]
    scratch = np.empty(n * max_sets + 2 * n, np.intp)
    sums = np.empty((population, 2))
    fired_rules = np.empty(0 if dense or n <= 2 else 64, np.intp)  # grown when more fire
    fired_alphas = np.empty(fired_rules.shape[0])
    for first in range(start, stop, _BLOCK):
        count = min(_BLOCK, stop - first)
        nan_state = _block_memberships(states, first, count, lo, hi, quads, kinds, offsets,
                                       xs, mu)
        if nan_state >= 0:
            return nan_state
        if dense:
            _dense_block(count, mu, grid, values, alpha, numerators, denominators,
                         bool(ints[_PRODUCT]))
        else:
            for b in range(count):  # eq. 2-3 over each state's fired rules
                denominators[b] = 0.0  # no rule fires (see _first_zero)
                if _compact(mu, b, ints, scratch, mus):
                    if n > 2 and _state_capacity(ints, scratch) > fired_rules.shape[0]:
                        fired_rules = np.empty(_state_capacity(ints, scratch), np.intp)
                        fired_alphas = np.empty(fired_rules.shape[0])
                    _state_outputs(floats, ints, scratch, mus, tables, sums, fired_rules,
                                   fired_alphas)
                    for p in range(population):
                        numerators[p, b] = sums[p, 0]
                    denominators[b] = sums[0, 1]
        failed = _first_zero(denominators, count, first)
        if failed >= 0:
            return failed
        for p in range(population):
            for b in range(count):
                out[p * batch + first + b] = _within(numerators[p, b] / denominators[b], low,
                                                     high)
    return -1


@_jit
def _state_sets(floats: FloatArray, ints: IntArray, state: FloatArray, scratch: IntArray,
                mus: FloatArray) -> int:
    """Each input's fired sets for ``state (N,)``, reading the packed layout in place (no
    views: at a hundred nanoseconds a state, making them would be a good part of it).

    Writes ``scratch``: sets (N, max L_i), counts (N,), digits (N,) zeroed; and ``mus``
    (N, max L_i), both flat. Returns -1, or 0 if an input is NaN, 1 if an input has no
    fired set (every membership underflowed: no rule fires).
    """
    n, max_sets = ints[0], ints[2]
    quads = 2 * n  # where the quadruples start in floats
    offsets = _HEADER  # where the offsets start in ints
    kinds = _HEADER + 1 + 2 * n  # where the sets' shape codes start in ints
    for i in range(n):
        s = state[i]
        if s != s:
            return 0
        s = min(max(s, floats[i]), floats[n + i])  # clipped, as np.clip does
        count = 0
        first = ints[offsets + i]
        for j in range(first, ints[offsets + i + 1]):
            q = quads + 4 * j
            if ints[kinds + j]:  # a shape other than the trapezoid (flctool.behaviour.shapes)
                mu = _shaped(ints[kinds + j], floats[q], floats[q + 1], floats[q + 2],
                             floats[q + 3], s)
            else:
                mu = _membership_free(s, floats[q], floats[q + 1], floats[q + 2],
                                      floats[q + 3])
            scratch[i * max_sets + count] = j - first
            mus[i * max_sets + count] = mu
            count += mu > 0.0  # kept only if non-zero, without a branch to mispredict
        if count == 0:
            return 1
        scratch[n * max_sets + i] = count
        scratch[n * max_sets + n + i] = 0
    return -1


@_jit
def _state_sums(floats: FloatArray, ints: IntArray, scratch: IntArray, mus: FloatArray,
                tables: IntArray, p: int) -> tuple[float, float]:
    """sum(alpha_m * c_m) and sum(alpha_m) over the fired rules (eq. 2-3) of the state that
    :func:`_state_sets` wrote, with consequents ``tables[p]``.

    The fired rules are enumerated like an odometer over each input's fired sets, last
    input fastest, so in increasing rule order (eq. 1) -- the reference's order of sums.
    """
    n, max_sets = ints[0], ints[2]
    singletons = 2 * n + 4 * ints[1]
    counts = n * max_sets
    digits = counts + n
    strides = _HEADER + n + 1
    product = bool(ints[_PRODUCT])
    numerator = 0.0
    denominator = 0.0
    if n == 2:  # the common case, without the odometer's bookkeeping
        for a in range(scratch[counts]):
            rule = scratch[a] * ints[strides]
            first = mus[a]
            for b in range(max_sets, max_sets + scratch[counts + 1]):
                alpha = _and(product, first, mus[b])  # eq. 2
                numerator += alpha * floats[singletons + tables[p, rule + scratch[b]]]
                denominator += alpha
        return numerator, denominator
    while True:
        rule = 0
        alpha = _unit(product)
        for i in range(n):
            slot = i * max_sets + scratch[digits + i]
            rule += scratch[slot] * ints[strides + i]
            alpha = _and(product, alpha, mus[slot])  # eq. 2
        numerator += alpha * floats[singletons + tables[p, rule]]
        denominator += alpha
        i = n - 1
        while i >= 0:
            scratch[digits + i] += 1
            if scratch[digits + i] < scratch[counts + i]:
                break
            scratch[digits + i] = 0
            i -= 1
        if i < 0:
            return numerator, denominator


@_jit
def _state_capacity(ints: IntArray, scratch: IntArray) -> int:
    # prod(counts) of the state _state_sets / _compact wrote: how many rules fire.
    n, max_sets = ints[0], ints[2]
    total = 1
    for i in range(n):
        total *= scratch[n * max_sets + i]
    return total


@_jit
def _expand_fired(ints: IntArray, scratch: IntArray, mus: FloatArray, rules: IntArray,
                  alphas: FloatArray) -> int:
    """The fired rules of the state :func:`_state_sets` wrote, in increasing rule order, into
    ``rules``/``alphas`` (capacity >= :func:`_state_capacity`); returns how many. Eq. 1-2.

    For three inputs or more this beats the odometer of :func:`_state_sums`: the product of
    the fired sets is built input by input (after input i the buffers hold the combinations
    of inputs 0..i in rule order; input i + 1 splits each entry into one per fired set,
    from the back so that it happens in place), so each fired rule costs one min, not N.
    """
    n, max_sets = ints[0], ints[2]
    strides = _HEADER + n + 1
    product = bool(ints[_PRODUCT])
    size = 1
    rules[0] = 0
    alphas[0] = _unit(product)
    for i in range(n):
        count = scratch[n * max_sets + i]
        stride = ints[strides + i]
        for entry in range(size - 1, -1, -1):
            rule = rules[entry]
            alpha = alphas[entry]
            for slot in range(count - 1, -1, -1):
                rules[entry * count + slot] = rule + scratch[i * max_sets + slot] * stride
                alphas[entry * count + slot] = _and(product, alpha,
                                                    mus[i * max_sets + slot])
        size *= count
    return size


@_jit
def _listed_sums(floats: FloatArray, ints: IntArray, rules: IntArray, alphas: FloatArray,
                 fired: int, tables: IntArray, p: int) -> tuple[float, float]:
    # sum(alpha_m * c_m) and sum(alpha_m) over the rules _expand_fired listed (eq. 3).
    singletons = 2 * ints[0] + 4 * ints[1]
    numerator = 0.0
    denominator = 0.0
    for a in range(fired):
        alpha = alphas[a]
        numerator += alpha * floats[singletons + tables[p, rules[a]]]
        denominator += alpha
    return numerator, denominator


@_jit
def _state_outputs(floats: FloatArray, ints: IntArray, scratch: IntArray, mus: FloatArray,
                   tables: IntArray, sums: FloatArray, rules: IntArray,
                   alphas: FloatArray) -> None:
    """Eq. 2-3 sums of the state :func:`_state_sets` wrote, for every table: into ``sums``
    (P, 2) numerator and denominator. Two inputs use the odometer; more use ``rules`` /
    ``alphas``, which hold at least :func:`_state_capacity` entries (callers grow them:
    returning grown arrays from here would cost reference counting on every state)."""
    if ints[0] <= 2:
        for p in range(tables.shape[0]):
            sums[p, 0], sums[p, 1] = _state_sums(floats, ints, scratch, mus, tables, p)
        return
    fired = _expand_fired(ints, scratch, mus, rules, alphas)
    for p in range(tables.shape[0]):
        sums[p, 0], sums[p, 1] = _listed_sums(floats, ints, rules, alphas, fired, tables, p)


@_jit
def _singleton_bounds(floats: FloatArray, ints: IntArray) -> tuple[float, float]:
    first = 2 * ints[0] + 4 * ints[1]
    low = high = floats[first]
    for k in range(first + 1, floats.shape[0]):
        low = min(low, floats[k])
        high = max(high, floats[k])
    return low, high


# Batches up to this size are inferred state by state (_state_sets, _state_sums): the block
# walks' set-up costs more than they save on a few states.
SMALL_BATCH = 8
# ... except when the blocks walk every rule of a small base (M x N rule-inputs at most this):
# that walk costs a few ns per state, so blocks are cheaper from about 5 states (measured:
# ballchase, 2 x 3, 2 x 5, 3 x 2 and 4 x 2 sets; with M x N = 81 or more, from 6-8 states).
SMALL_DENSE_BATCH = 4
CHEAP_DENSE_RULE_INPUTS = 64
# infer_own's switch: its state-by-state walk (one table, its work arrays made once) costs
# about 15 ns a state for one input, 45 for two, 80 for three and 200 for four (fired rules
# grow as 2^N), the blocks' set-up about 1 us, then 5-50 ns a state. Measured on ballchase
# and random 1-4 input controllers, state by state is cheaper up to 14-16 states for one or
# two inputs and 8-10 for more.
OWN_SMALL_BATCH_FEW_INPUTS = 16  # N <= 2, and any N walked every rule in blocks
OWN_SMALL_BATCH = 8
# (Walked every rule, blocks of 9 states cost about what 16 do: 4 x 4 and 5 x 3 sets were
# 0.90-0.94x the naive kernel at 9 states through the blocks, 1.4x at 16 and 1.7x at 8.)
# ... except for a small rule base walked every rule, which goes through _interleaved_states
# (the naive loop over every rule, four states at a time) where that costs less than finding
# each state's fired rules or setting up the blocks:
# - with one or two inputs (fired rules found in 15-45 ns a state), bases of at most
#   TINY_RULES_FEW_INPUTS rules from TINY_FROM to TINY_BATCH states, and of at most
#   FEW_RULES_FEW_INPUTS rules from TINY_FROM to OWN_SMALL_BATCH_FEW_INPUTS (state by state
#   was the cheaper at 1-2 states, level at 4 and 1.1-1.7x the cost at 8-16 on 1 x 2 to
#   2 x 7 sets; at 2 x 9 level at 8-16; December 2026);
# - with more inputs, up to INTERLEAVED_STATES states (INTERLEAVED_HALVES_STATES walked as two
#   halves: _halves_sums), where the layout found it cheaper (interleaves_states; against the
#   blocks, measured on 3 x 2 to 8 x 2 and 4 x 3 sets at 17-48 states, December 2026: 1.1-1.4x
#   cheaper at 17-24 states, level at 32 and dearer at 48, except as halves, still cheaper at 32
#   and, with every rule firing, at 48): the interleaved walk costs about INTERLEAVED_NS_PER_STATE +
#   INTERLEAVED_NS_PER_RULE_INPUT x M x N a state, the state-by-state walk of the fired rules about
#   FIRED_NS_PER_INPUT x N + FIRED_NS_PER_RULE x F, F the most rules that can fire at once
#   (fired_rules_bound: 2^N for overlapping neighbours, M when every set of every input fires, as
#   with 2 sets an input). Measured at 4, 8 and 16 states on every N = 3-8 and L <= 9 whose blocks
#   walk every rule (a loaded 2-core Xeon, December 2026): with every rule firing (6-8 inputs x 2
#   sets) the fired walk was 0.4-0.8x the naive kernel and the interleaved 1.5-2.5x; with few of
#   many rules firing (3 x 6, 4 x 4) the fired walk is the cheaper.
TINY_BATCH = 2 * _BLOCK
# ... but one or two states of a base where a few of its rules fire walk those (3 x 3, 4 x 3
# sets: 1.1-1.2x cheaper at one state, level at two), where every rule fires, every rule.
FEW_STATES_FIRED = 2
EVERY_RULE_FIRES = 2
INTERLEAVED_STATES = 24
INTERLEAVED_HALVES_STATES = 32
TINY_FROM = 4
TINY_RULES_FEW_INPUTS = 16
FEW_RULES_FEW_INPUTS = 49
INTERLEAVED_NS_PER_STATE = 100.0
INTERLEAVED_NS_PER_RULE_INPUT = 0.4
FIRED_NS_PER_INPUT = 60.0
FIRED_NS_PER_RULE = 10.0


def interleaves_states(n_rules: int, n_inputs: int, fired_bound: int) -> bool:
    """Whether a few states of a base whose blocks walk every rule are walked every rule
    four at a time (else each state's fired rules): the estimated cheaper, for M rules, N
    inputs and at most ``fired_bound`` rules firing at once (see the constants above)."""
    interleaved = INTERLEAVED_NS_PER_STATE + INTERLEAVED_NS_PER_RULE_INPUT * n_rules * n_inputs
    fired = FIRED_NS_PER_INPUT * n_inputs + FIRED_NS_PER_RULE * min(fired_bound, n_rules)
    return n_inputs > 2 and interleaved <= fired


def fired_rules_bound(ranges: FloatArray, quadruples: tuple[FloatArray, ...],
                      kinds: tuple[tuple[int, ...], ...] | None) -> int:
    """The most rules that can fire for one state: the product over the inputs of the most
    sets with a non-zero membership at one point of the input's range.

    Where a trapezoid's membership turns non-zero or zero is one of its corners, so the
    count at every corner and midway between consecutive corners finds each input's most
    (for the other shapes, whose parameters are not where they start, it is a good
    estimate: a cost model reads it, never the arithmetic).
    """
    from flctool.membership import memberships

    bound = 1
    for i, quads in enumerate(quadruples):
        low, high = float(ranges[i, 0]), float(ranges[i, 1])
        corners = np.unique(np.clip(np.concatenate([quads.ravel(), [low, high]]), low, high))
        points = np.concatenate([corners, (corners[:-1] + corners[1:]) / 2])
        mu = memberships(points, quads, None if kinds is None else kinds[i])
        bound *= max(1, int((mu > 0.0).sum(axis=1).max()))
    return bound


@_jit
def _infer_small(states: FloatArray, floats: FloatArray, ints: IntArray, tables: IntArray,
                 out: FloatArray, start: int, stop: int) -> int:
    # infer() for a few states (see SMALL_BATCH).
    n, max_sets = ints[0], ints[2]
    scratch = np.empty(n * max_sets + 2 * n, np.intp)
    mus = np.empty(n * max_sets)
    low, high = _singleton_bounds(floats, ints)
    batch = states.shape[0]
    sums = np.empty((tables.shape[0], 2))
    rules = np.empty(0 if n <= 2 else 64, np.intp)  # grown when more rules fire
    alphas = np.empty(rules.shape[0])
    for b in range(start, stop):
        if _state_sets(floats, ints, states[b], scratch, mus) >= 0:
            return b
        if n > 2 and _state_capacity(ints, scratch) > rules.shape[0]:
            rules = np.empty(_state_capacity(ints, scratch), np.intp)
            alphas = np.empty(rules.shape[0])
        _state_outputs(floats, ints, scratch, mus, tables, sums, rules, alphas)
        for p in range(tables.shape[0]):
            out[p * batch + b] = _within(sums[p, 0] / sums[p, 1], low, high)
    return -1


@_jit
def _own_table(ints: IntArray) -> IntArray:
    # The consequents that follow the layout's ints in infer_one's / infer_own's ``ints``,
    # as the (1, M) table the shared walks take.
    table = _HEADER + 1 + 2 * ints[0] + ints[1] + ints[3] * ints[0]
    return ints[table:].reshape((1, ints.shape[0] - table))


@_jit
def infer_one(floats: FloatArray, ints: IntArray, state: FloatArray) -> float:
    """Eq. 3 for one ``state (N,)``; NaN if an input is NaN or no rule fires (every
    activation underflowed to 0: see :func:`infer`).

    ``floats`` is :class:`Layout`'s, ``ints`` its ints followed by the consequents ``(M,)``
    (three arguments to unbox rather than four).
    """
    n, max_sets = ints[0], ints[2]
    scratch = np.empty(n * max_sets + 2 * n, np.intp)
    mus = np.empty(n * max_sets)
    if _state_sets(floats, ints, state, scratch, mus) >= 0:
        return np.nan
    tables = _own_table(ints)
    if n <= 2:
        numerator, denominator = _state_sums(floats, ints, scratch, mus, tables, 0)
    else:
        capacity = _state_capacity(ints, scratch)
        rules = np.empty(capacity, np.intp)
        alphas = np.empty(capacity)
        fired = _expand_fired(ints, scratch, mus, rules, alphas)
        numerator, denominator = _listed_sums(floats, ints, rules, alphas, fired, tables, 0)
    low, high = _singleton_bounds(floats, ints)
    return _within(numerator / denominator, low, high)


@_jit
def _own_states(floats: FloatArray, ints: IntArray, states: FloatArray, out: FloatArray,
                tables: IntArray) -> int:
    # infer_own state by state: infer_one's walk for each state, the work arrays made once.
    n, max_sets = ints[0], ints[2]
    scratch = np.empty(n * max_sets + 2 * n, np.intp)
    mus = np.empty(n * max_sets)
    rules = np.empty(0 if n <= 2 else 64, np.intp)  # grown when more rules fire
    alphas = np.empty(rules.shape[0])
    low, high = _singleton_bounds(floats, ints)
    for b in range(states.shape[0]):
        if _state_sets(floats, ints, states[b], scratch, mus) >= 0:
            return b
        if n <= 2:
            numerator, denominator = _state_sums(floats, ints, scratch, mus, tables, 0)
        else:
            capacity = _state_capacity(ints, scratch)
            if capacity > rules.shape[0]:
                rules = np.empty(capacity, np.intp)
                alphas = np.empty(capacity)
            fired = _expand_fired(ints, scratch, mus, rules, alphas)
            numerator, denominator = _listed_sums(floats, ints, rules, alphas, fired, tables, 0)
        out[b] = _within(numerator / denominator, low, high)
    return -1


@_jit
def _partial_mins(mu: FloatArray, lanes: int, first: int, stop: int, offsets: IntArray,
                  table: FloatArray) -> int:
    """min(mu) over inputs ``first..stop-1`` (eq. 2's min over part of a rule) for every
    combination of their sets, in rule order (the last input fastest), into ``table[:, k]``
    for the states in lanes ``k < lanes`` of ``mu (S, 4)``; returns how many combinations.

    Built input by input from inf (min(inf, x) is x), each entry split into one per set of
    the next input, from the back so that it happens in place: one min an entry.
    """
    size = 1
    for k in range(lanes):
        table[0, k] = np.inf
    for i in range(first, stop):
        start = offsets[i]
        count = offsets[i + 1] - start
        for entry in range(size - 1, -1, -1):
            for slot in range(count - 1, -1, -1):
                for k in range(lanes):
                    table[entry * count + slot, k] = min(table[entry, k], mu[start + slot, k])
        size *= count
    return size


# A few states of a base with at least this many rule-inputs (M x N) are walked as two
# halves: each rule's alpha is min(alpha of its first N // 2 inputs, alpha of the others),
# both tabulated once a state (_partial_mins), so a rule costs one min rather than N - 1.
# Below it, making the two tables costs more than it saves (measured on 2 x 4 to 8 x 2 sets:
# the halves 1.3-3.3x faster from 4 x 3 and 6 x 2 sets, slower for 3 x 3 and 5 x 2).
SPLIT_RULE_INPUTS = 256


@_jit
def _halves_sums(mu: FloatArray, lanes: int, n: int, offsets: IntArray, values: FloatArray,
                 head: FloatArray, tail: FloatArray, sums: FloatArray) -> None:
    """Eq. 2-3 over every rule, in rule order, for the states in lanes ``k < lanes`` (1 or
    4) of ``mu (S, 4)``: numerators into ``sums[0, k]``, denominators into ``sums[1, k]``.

    Rule m = r * T + t (T combinations of the last inputs, eq. 1's order) has alpha_m =
    min(head[r], tail[t]). min returns one of its operands, and memberships are never NaN
    here (NaN inputs are refused first), so this is the reference's alpha_m, however the
    mins nest: the same bits. The sums run in rule order, as the reference's.
    """
    half = n // 2
    heads = _partial_mins(mu, lanes, 0, half, offsets, head)
    tails = _partial_mins(mu, lanes, half, n, offsets, tail)
    if lanes == 1:
        numerator = denominator = 0.0
        m = 0
        for r in range(heads):
            first = head[r, 0]
            for t in range(tails):
                alpha = min(first, tail[t, 0])  # eq. 2
                numerator += alpha * values[m]
                denominator += alpha
                m += 1
        sums[0, 0], sums[1, 0] = numerator, denominator
        return
    n0 = n1 = n2 = n3 = d0 = d1 = d2 = d3 = 0.0
    m = 0
    for r in range(heads):
        h0, h1, h2, h3 = head[r, 0], head[r, 1], head[r, 2], head[r, 3]
        for t in range(tails):
            a0 = min(h0, tail[t, 0])  # eq. 2
            a1 = min(h1, tail[t, 1])
            a2 = min(h2, tail[t, 2])
            a3 = min(h3, tail[t, 3])
            value = values[m]
            n0 += a0 * value
            n1 += a1 * value
            n2 += a2 * value
            n3 += a3 * value
            d0 += a0
            d1 += a1
            d2 += a2
            d3 += a3
            m += 1
    sums[0, 0], sums[0, 1], sums[0, 2], sums[0, 3] = n0, n1, n2, n3
    sums[1, 0], sums[1, 1], sums[1, 2], sums[1, 3] = d0, d1, d2, d3


@_jit
def _interleaved_states(floats: FloatArray, ints: IntArray, states: FloatArray,
                        out: FloatArray, tables: IntArray) -> int:
    """infer_own for a few states of a small base (see TINY_BATCH): every rule of each state
    in rule order, the naive loop, but four states at a time; from
    :data:`SPLIT_RULE_INPUTS` rule-inputs, as two halves (:func:`_halves_sums`).

    Each state's eq. 2 mins and eq. 3 sums are its own chain, in rule order as the
    reference's (zeros add nothing: module doc), so the bits are the same; four independent
    chains keep the processor busy while one waits on its additions, and each rule's row of
    the grid is read once for the four. A last odd state is walked alone.
    """
    lo, hi, quads, singletons, _, offsets, _, grid, kinds = _unpack(floats, ints)
    n, sets = ints[0], ints[1]
    product = bool(ints[_PRODUCT])
    count = states.shape[0]
    for b in range(count):  # NaN inputs first: the first state that has one is reported
        for i in range(n):
            if states[b, i] != states[b, i]:
                return b
    rules = grid.shape[0]
    # the halves' min(head, tail) is the min over the rule in any order; a product split in
    # two would round differently from the reference's input-order product
    halves = not product and rules * n >= SPLIT_RULE_INPUTS
    values = np.empty(rules)  # each rule's c_m
    for m in range(rules):
        values[m] = singletons[tables[0, m]]
    mu = np.empty((sets, 4))  # the memberships of the four states, side by side
    heads = 1  # the combinations of the first N // 2 inputs' sets, and of the others
    for i in range(n // 2):
        heads *= offsets[i + 1] - offsets[i]
    head = np.empty((heads if halves else 0, 4))
    tail = np.empty((rules // heads if halves else 0, 4))
    sums = np.empty((2, 4))
    low, high = _singleton_bounds(floats, ints)
    first = 0
    while first < count:
        lanes = 1 if count - first == 1 else 4
        for k in range(lanes):
            b = min(first + k, count - 1)  # past the last state: it again, never written
            for i in range(n):
                s = min(max(states[b, i], lo[i]), hi[i])  # clipped, as np.clip does
                for j in range(offsets[i], offsets[i + 1]):
                    if kinds[j]:  # a shape other than the trapezoid (behaviour.shapes)
                        mu[j, k] = _shaped(kinds[j], quads[j, 0], quads[j, 1], quads[j, 2],
                                           quads[j, 3], s)
                    else:
                        mu[j, k] = _membership_free(s, quads[j, 0], quads[j, 1],
                                                    quads[j, 2], quads[j, 3])
        if halves:
            _halves_sums(mu, lanes, n, offsets, values, head, tail, sums)
            for k in range(min(lanes, count - first)):
                if sums[1, k] == 0.0:  # no rule fires (see infer)
                    return first + k
                out[first + k] = _within(sums[0, k] / sums[1, k], low, high)
            first += lanes
            continue
        if lanes == 1:
            numerator = denominator = 0.0
            for m in range(rules):
                alpha = mu[grid[m, 0], 0]
                for i in range(1, n):
                    alpha = _and(product, alpha, mu[grid[m, i], 0])  # eq. 2
                numerator += alpha * values[m]
                denominator += alpha
            if denominator == 0.0:  # no rule fires (see infer)
                return first
            out[first] = _within(numerator / denominator, low, high)
            return -1
        n0 = n1 = n2 = n3 = d0 = d1 = d2 = d3 = 0.0
        for m in range(rules):
            row = grid[m, 0]
            a0, a1, a2, a3 = mu[row, 0], mu[row, 1], mu[row, 2], mu[row, 3]
            for i in range(1, n):  # eq. 2
                row = grid[m, i]
                a0 = _and(product, a0, mu[row, 0])
                a1 = _and(product, a1, mu[row, 1])
                a2 = _and(product, a2, mu[row, 2])
                a3 = _and(product, a3, mu[row, 3])
            value = values[m]
            n0 += a0 * value
            n1 += a1 * value
            n2 += a2 * value
            n3 += a3 * value
            d0 += a0
            d1 += a1
            d2 += a2
            d3 += a3
        numerators = (n0, n1, n2, n3)
        denominators = (d0, d1, d2, d3)
        for k in range(min(4, count - first)):
            if denominators[k] == 0.0:  # no rule fires (see infer)
                return first + k
            out[first + k] = _within(numerators[k] / denominators[k], low, high)
        first += 4
    return -1


@_jit
def _tiny(ints: IntArray, count: int) -> bool:
    # Whether infer_own takes _interleaved_states (see TINY_BATCH).
    n, rules = ints[0], ints[3]
    if rules == 0:
        return False
    if n <= 2:
        if count < TINY_FROM:
            return False
        if rules <= TINY_RULES_FEW_INPUTS:
            return count <= TINY_BATCH
        return rules <= FEW_RULES_FEW_INPUTS and count <= OWN_SMALL_BATCH_FEW_INPUTS
    if not ints[4]:
        return False
    if count <= FEW_STATES_FIRED and ints[4] != EVERY_RULE_FIRES:
        return False  # a state or two of a base where few of its rules fire: those only
    if rules * n >= SPLIT_RULE_INPUTS and not ints[_PRODUCT]:
        return count <= INTERLEAVED_HALVES_STATES
    return count <= INTERLEAVED_STATES


@_jit
def infer_own(floats: FloatArray, ints: IntArray, states: FloatArray, out: FloatArray) -> int:
    """Eq. 3 for ``states (B, N)`` into ``out (B,)`` with the controller's own consequents,
    which follow the layout's ints in ``ints`` as for :func:`infer_one`; returns what
    :func:`infer` returns.

    The entry point of ``Controller.output`` without a population: four arrays to unbox and
    nothing to pass that the kernel can find itself, so a call on a few states costs little
    more than its arithmetic. Up to :data:`OWN_SMALL_BATCH` states
    (:data:`OWN_SMALL_BATCH_FEW_INPUTS` for one or two inputs) go state by state, more in
    blocks -- the walks of :func:`infer_one` and :func:`infer`, so the same bits.
    """
    tables = _own_table(ints)
    count = states.shape[0]
    if _tiny(ints, count):
        return _interleaved_states(floats, ints, states, out, tables)
    # the blocks' walk of every rule costs M x N loops however few states: from more states
    small = OWN_SMALL_BATCH_FEW_INPUTS if ints[0] <= 2 or ints[3] > 0 else OWN_SMALL_BATCH
    if count <= small:
        return _own_states(floats, ints, states, out, tables)
    dense = ints[3] > 0  # the layout keeps the rule grid only for the walk of every rule
    return _infer_blocks(states, floats, ints, tables, out, 0, count, dense)


@_jit
def active_one(floats: FloatArray, ints: IntArray,
               state: FloatArray) -> tuple[IntArray, FloatArray, int]:
    """The fired rules of one ``state (N,)`` in increasing order and their activations
    (eq. 2): ``(rules (A,), alpha (A,), nan_input)``, ``nan_input`` -1 unless an input is NaN.
    """
    lo, hi, quads, _, max_sets, offsets, strides, _, kinds = _unpack(floats, ints)
    sets, mus, counts = _work(state.shape[0], max_sets)
    nan_input = _fired_sets(state.reshape((1, state.shape[0])), 0, lo, hi, quads, kinds,
                            offsets, sets, mus, counts)
    if nan_input >= 0:
        return np.empty(0, np.intp), np.empty(0), nan_input
    capacity = _capacity(counts)
    rules = np.empty(capacity, np.intp)
    alphas = np.empty(capacity)
    # Fewer than the capacity only if an input has no non-zero set (memberships underflowed).
    fired = _fired_rules(sets, mus, counts, strides, rules, alphas, bool(ints[_PRODUCT]))
    return rules[:fired], alphas[:fired], -1


@_jit
def activations(states: FloatArray, floats: FloatArray, ints: IntArray, out: FloatArray) -> int:
    """Dense eq. 2 for ``states (B, N)`` into a zeroed ``out (B, M)``; returns -1 or the
    first state with a NaN input."""
    lo, hi, quads, _, max_sets, offsets, strides, _, kinds = _unpack(floats, ints)
    sets, mus, counts = _work(states.shape[1], max_sets)
    rules = np.empty(16, np.intp)
    alphas = np.empty(16)
    for b in range(states.shape[0]):
        if _fired_sets(states, b, lo, hi, quads, kinds, offsets, sets, mus, counts) >= 0:
            return b
        capacity = _capacity(counts)
        if capacity > rules.shape[0]:
            rules = np.empty(capacity, np.intp)
            alphas = np.empty(capacity)
        fired = _fired_rules(sets, mus, counts, strides, rules, alphas, bool(ints[_PRODUCT]))
        for a in range(fired):
            out[b, rules[a]] = alphas[a]
    return -1


def _array(dtype: Any, ndim: int) -> Any:
    return numba.types.Array(dtype, ndim, "C")


_F1, _F2 = _array(numba.types.float64, 1), _array(numba.types.float64, 2)
# States of any strides: read as they are, no copy needed.
_STATES = numba.types.Array(numba.types.float64, 2, "A")
_STATE = numba.types.Array(numba.types.float64, 1, "A")
_I1, _I2 = _array(numba.types.intp, 1), _array(numba.types.intp, 2)
# The one signature each kernel is used with (writable C arrays): entry() compiles it, or
# loads it from numba's cache, ahead of the first call.
SIGNATURES: dict[str, tuple[Any, ...]] = {
    "infer": (_STATES, _F1, _I1, _I2, _F1, numba.types.intp, numba.types.intp,
              numba.types.boolean),
    "infer_one": (_F1, _I1, _STATE),
    "infer_own": (_F1, _I1, _STATES, _F1),
    "active_one": (_F1, _I1, _F1),
    "activations": (_F2, _F1, _I1, _F2),
}


def cached(name: str) -> bool:
    """Whether numba's cache holds kernel ``name``'s machine code for its signature, this
    source and this machine: loading it then costs a fraction of a second, where compiling
    it costs seconds. Reads the cache's index only (numba's own key, through its cache
    object); if numba's internals are not as expected, says True, i.e. load as before."""
    dispatcher = globals()[name]
    try:
        cache = dispatcher._cache
        key = cache._index_key(SIGNATURES[name], dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # a private API: any surprise means "as before"
        return True


def entry(name: str) -> Callable[..., Any]:
    """Kernel ``name``'s compiled entry point for its one signature (:data:`SIGNATURES`).

    Calling it skips numba's dispatch (finding the argument types and the matching
    compilation), about a third of a one-state call. It trusts its arguments' types: callers
    pass exactly the signature's arrays (float64 or intp, C-contiguous) and Python
    ints/bools, never anything else.
    """
    dispatcher = globals()[name]
    return cast(Callable[..., Any], dispatcher.compile(SIGNATURES[name]))


class Layout(NamedTuple):
    """A controller's sets laid out for the kernels, packed in two arrays so that a call
    unboxes two arguments instead of eight (S = sum L_i sets in all, M rules)."""

    floats: FloatArray  # lo (N,), hi (N,), quads (S, 4) input after input, singletons (K,)
    # N, S, max L_i, M if the grid is kept (else 0), whether a few states are walked every
    # rule four at a time (0, 1 or EVERY_RULE_FIRES: see _HEADER), whether eq. 2 is the
    # product (activation: product), offsets (N + 1,): input i's sets are
    # quads[offsets[i]:offsets[i + 1]], strides (N,): rule index = sum(set index * stride),
    # last input fastest; kinds (S,): each set's shape code (0 the trapezoid, whose quad
    # holds its corners; else its parameters, flctool.behaviour.shapes); grid (M, N): each
    # rule's rows of quads, if walks_every_rule
    ints: IntArray
    dense: bool  # whether batched inference walks every rule (walks_every_rule)


def layout(ranges: FloatArray, quadruples: tuple[FloatArray, ...], rule_grid: IntArray,
           singletons: FloatArray, kinds: tuple[tuple[int, ...], ...] | None = None,
           product: bool = False) -> Layout:
    """Lay out ``ranges (N, 2)``, ``quadruples`` (N arrays (L_i, 4)), ``rule_grid (M, N)`` and
    ``singletons (K,)`` for the kernels: writable C arrays, so that each kernel is compiled
    for one signature only. ``product``: eq. 2 is the product (activation: product)."""
    sizes = [len(q) for q in quadruples]
    strides = np.ones(len(sizes), dtype=np.intp)
    for i in range(len(sizes) - 2, -1, -1):
        strides[i] = strides[i + 1] * sizes[i + 1]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
    dense = walks_every_rule(rule_grid.shape[0], len(sizes), sum(sizes))
    grid = rule_grid + offsets[:-1] if dense else np.empty((0, len(sizes)), dtype=np.intp)
    quads = np.concatenate(quadruples).astype(np.float64)
    bound = fired_rules_bound(ranges, quadruples, kinds)
    interleaves = 0
    if dense and interleaves_states(rule_grid.shape[0], len(sizes), bound):
        interleaves = EVERY_RULE_FIRES if bound >= rule_grid.shape[0] else 1
    header = [len(sizes), len(quads), max(sizes), grid.shape[0], interleaves, int(product)]
    floats = np.concatenate([ranges[:, 0], ranges[:, 1], quads.ravel(), singletons])
    codes = (np.zeros(len(quads), dtype=np.intp) if kinds is None
             else np.array([k for input_kinds in kinds for k in input_kinds], dtype=np.intp))
    ints = np.concatenate([header, offsets, strides, codes, grid.ravel()])
    return Layout(floats=np.array(floats, dtype=np.float64), ints=np.array(ints, dtype=np.intp),
                  dense=dense)


def keep_grid(layout: Layout, rule_grid: IntArray) -> Layout:
    """``layout`` with the rule grid kept, so that the walk of every rule can run whatever M
    is (for benchmarks and tests that compare the walks; the choice stays ``layout``'s)."""
    if layout.dense:
        return layout
    n = rule_grid.shape[1]
    offsets = layout.ints[_HEADER : _HEADER + n]
    ints = np.concatenate([layout.ints[:3], [len(rule_grid), 0, layout.ints[_PRODUCT]],
                           layout.ints[_HEADER:],
                           (rule_grid + offsets).ravel()]).astype(np.intp)
    return Layout(layout.floats, ints, True)
