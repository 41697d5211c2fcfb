"""Inference in numpy, without compiling anything: eq. 1-3 with the kernels' bits.

For work too small to pay for the compiled kernels: importing numba and loading the kernels
costs about 0.3 s of CPU in every process (compiling them, on a machine's first run, several
seconds), while a call here costs a few microseconds of numpy per operation. The controller
(:mod:`flctool.compile.controller`) runs inference here until a process has spent about as
much as loading the kernels would cost, then loads them (see ``Controller.output``).

The arithmetic is the kernels' (and the reference loop's), so the results are the same bits:
each input's memberships by :func:`~flctool.membership.memberships` (trapezoids
vectorised, other shapes value by value), then, vectorised
over the states, the rules that combine each state's fired sets, enumerated in increasing
rule order (each input's fired sets in set order, the last input fastest): for each, eq. 2's
min (or with ``product`` the memberships' product, multiplied in input order as the kernels
do), then eq. 3's sums accumulated from 0.0 in that order and one division, kept within the
commands. Where a state fires fewer sets of an input than another state of the batch, its
missing slots have activation 0, which adds nothing to either sum (x + 0.0 is x; the sums
never hold -0.0), so every state's sums are those of its own fired rules.

Everything here takes the clipped states of :func:`fired_sets`; NaN inputs are the caller's
to refuse first.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import NDArray

from flctool.membership import memberships

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


#: One input's fired sets: per slot k, ``(set (B,), mu (B,))``, each state's k-th non-zero
#: membership in set order (set 0 and mu 0 where a state fires fewer than k + 1 sets).
Slots = list[tuple[IntArray, FloatArray]]


#: Each input's set shape codes, or None when every set is a trapezoid (Controller.kinds).
Kinds = tuple[tuple[int, ...], ...] | None


def fired_sets(states: FloatArray, ranges: FloatArray, quadruples: Sequence[FloatArray],
               kinds: Kinds) -> list[Slots]:
    """Each input's fired sets for ``states (B, N)`` (no NaN), as many slots as the most
    any state fires."""
    clipped = np.minimum(np.maximum(states, ranges[:, 0]), ranges[:, 1])  # as np.clip does
    rows = np.arange(states.shape[0])
    fired = []
    for i, quads in enumerate(quadruples):
        mu = memberships(clipped[:, i], quads, None if kinds is None else kinds[i])  # (B, L_i)
        nonzero = mu > 0.0
        rank = np.cumsum(nonzero, axis=1, dtype=np.intp)  # k-th fired set: rank k, non-zero
        counts = rank[:, -1]
        slots = []
        for k in range(1, int(counts.max(initial=0)) + 1):
            sets = (nonzero & (rank == k)).argmax(axis=1)
            slots.append((sets, np.where(counts >= k, mu[rows, sets], 0.0)))
        fired.append(slots)
    return fired


def fired_rules(fired: list[Slots], strides: Sequence[int], product: bool = False,
                ) -> Iterator[tuple[IntArray, FloatArray]]:
    """``(rule (B,), alpha (B,))`` of every combination of the fired slots, in increasing
    rule order for each state (eq. 1), alpha their min (eq. 2), or with ``product`` their
    product in input order; 0 where a slot is empty."""
    for combination in itertools.product(*fired):
        rule, alpha = combination[0]
        rule = rule * strides[0]
        for i in range(1, len(combination)):
            sets, mu = combination[i]
            rule = rule + sets * strides[i]
            alpha = alpha * mu if product else np.minimum(alpha, mu)
        yield rule, alpha


def output(states: FloatArray, ranges: FloatArray, quadruples: Sequence[FloatArray],
           kinds: Kinds, strides: Sequence[int], singletons: FloatArray, tables: IntArray,
           product: bool = False) -> tuple[FloatArray, int]:
    """Eq. 3 of ``states (B, N)`` (no NaN) with consequents ``tables (P, M)``: ``(out (P, B),
    failed)``, ``failed`` -1 or the first state where no rule fires (its output is then NaN;
    the caller raises, as for the kernels)."""
    count = states.shape[0]
    numerators = np.zeros((tables.shape[0], count))
    denominators = np.zeros(count)
    for rule, alpha in fired_rules(fired_sets(states, ranges, quadruples, kinds), strides,
                                   product):
        numerators += alpha * singletons[tables[:, rule]]
        denominators += alpha
    empty = np.flatnonzero(denominators == 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.minimum(np.maximum(numerators / denominators, singletons.min()),
                         singletons.max())  # kept within the commands, as the kernels keep it
    return out, int(empty[0]) if empty.shape[0] else -1


def activations(states: FloatArray, ranges: FloatArray, quadruples: Sequence[FloatArray],
                kinds: Kinds, strides: Sequence[int], n_rules: int,
                product: bool = False) -> FloatArray:
    """Dense eq. 2 of ``states (B, N)`` (no NaN): ``(B, M)``."""
    alphas = np.zeros((states.shape[0], n_rules))
    rows = np.arange(states.shape[0])
    for rule, alpha in fired_rules(fired_sets(states, ranges, quadruples, kinds), strides,
                                   product):
        fired = alpha > 0.0
        alphas[rows[fired], rule[fired]] = alpha[fired]
    return alphas


def active_rules(state: FloatArray, ranges: FloatArray, quadruples: Sequence[FloatArray],
                 kinds: Kinds, strides: Sequence[int],
                 product: bool = False) -> tuple[IntArray, FloatArray]:
    """The fired rules of one ``state (N,)`` (no NaN) in increasing order, and their
    activations (eq. 2)."""
    pairs = list(fired_rules(fired_sets(state[None, :], ranges, quadruples, kinds),
                             strides, product))
    if not pairs:
        return np.empty(0, np.intp), np.empty(0)
    return (np.concatenate([rule for rule, _ in pairs]).astype(np.intp),
            np.concatenate([alpha for _, alpha in pairs]))
