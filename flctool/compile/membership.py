"""Trapezoid membership of paper Sec. II: the one Python coding, vectorised and scalar.

For a set (pa, pb, pc, pd)::

    mu(s) = max(0, (pd - s) / (pd - pc))   if s > pc
            max(0, (s - pa) / (pb - pa))   if s < pb
            1                              otherwise

``pb == pc`` is a triangle. A vertical edge (``pa == pb`` or ``pc == pd``) jumps: with
``pa == pb`` the membership is 0 for ``s < pa`` and 1 from ``pa`` on, so no division by zero
happens. Because inputs are clipped to their range first, a shoulder ending at the range's end
(``pc == pd == high``) has membership 1 at and beyond that end. This is exactly
``skfuzzy.trapmf`` (tests compare them).

Two forms of the one formula, and nothing else in flctool's Python codes it again (the
compiled kernels and the C export have their own, which the tests compare with these):
:func:`trapezoid` for arrays of values (any float dtype: float32 reproduces the float C
export), and :func:`firing_sets` for one value, in plain Python floats for the learners' hot
loop, where numpy's per-call overhead would cost more than the arithmetic. Both do the same
operations in the same order, so they give the same bits (a test checks it over many random
sets and values).

This module imports numpy only inside :func:`trapezoid`: ``flctool infer`` on a small table
uses :func:`firing_sets` in a process that never loads numpy.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from numpy.typing import NDArray


def trapezoid(x: NDArray[Any], quads: NDArray[Any]) -> NDArray[Any]:
    """Membership of every value in every set: ``x (B,)``, ``quads (L, 4)`` -> ``(B, L)``.

    Computed in the dtype of ``x`` and ``quads`` (float64 unless both are float32), each
    operation rounded in it.
    """
    import numpy as np  # here, so that firing_sets (the plain-Python path) never loads it

    s = np.asarray(x)
    if s.dtype != np.float32:
        s = s.astype(np.float64)
    quads = np.asarray(quads, dtype=s.dtype)
    s = s[:, None]
    pa, pb, pc, pd = (quads[:, k] for k in range(4))
    zero, one = s.dtype.type(0), s.dtype.type(1)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        falling = np.where(pd > pc, (pd - s) / (pd - pc), zero)
        rising = np.where(pb > pa, (s - pa) / (pb - pa), zero)
    mu = np.where(s > pc, falling, np.where(s < pb, rising, one))
    result: NDArray[Any] = np.maximum(mu, zero)
    return result


def firing_sets(s: float, sets: Sequence[Sequence[float]]) -> list[tuple[int, float]]:
    """The sets a clipped value ``s`` belongs to: ``(index, membership)`` in set order, for
    the sets whose membership is above 0 (the same operations as :func:`trapezoid`)."""
    fired = []
    for j, (pa, pb, pc, pd) in enumerate(sets):
        if s > pc:
            mu = (pd - s) / (pd - pc) if pd > pc else 0.0
        elif s < pb:
            mu = (s - pa) / (pb - pa) if pb > pa else 0.0
        else:
            mu = 1.0
        if mu > 0.0:
            fired.append((j, mu))
    return fired


def trapezoid_scalar(s: float, pa: float, pb: float, pc: float, pd: float) -> float:
    """The membership of one value in one set (:func:`firing_sets` of that set alone)."""
    fired = firing_sets(s, ((pa, pb, pc, pd),))
    return fired[0][1] if fired else 0.0
