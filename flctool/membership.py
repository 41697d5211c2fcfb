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

The other shapes (:mod:`flctool.behaviour.shapes`: Gaussian, bell, sigmoids, S, Z, Pi) are coded
once too, in :func:`shape_membership` (plain Python floats and ``math.exp`` / ``**``, which are
the C library's ``exp`` and ``pow``, as the compiled kernels', the C export's and fuzzylite's
are: numpy's own ``exp`` differs from them in the last bit of a few percent of values, so
the array form :func:`memberships` calls the scalar one value by value for those shapes).
Their formulas are scikit-fuzzy's and fuzzylite's:

- ``gauss`` (m, s): ``exp(-((x - m) * (x - m)) / (2 * s * s))``
- ``gauss2`` (m1, s1, m2, s2): the left Gaussian below m1, the right one above m2, 1 between
- ``bell`` (w, b, c): ``1 / (1 + |(x - c) / w| ** (2 * b))``
- ``sigmoid`` (c, a): ``1 / (1 + exp(-a * (x - c)))``
- ``sigmoid_difference``: ``|sigmoid(c1, a1) - sigmoid(c2, a2)|`` (fuzzylite and MATLAB take
  the absolute value; scikit-fuzzy's ``dsigmf`` does not, which differs only where the second
  sigmoid is above the first)
- ``sigmoid_product``: ``sigmoid(c1, a1) * sigmoid(c2, a2)``
- ``s_shape`` (a, b): 0 up to a, ``2 t * t`` with ``t = (x - a) / (b - a)`` up to the
  midpoint, ``1 - 2 u * u`` with ``u = (x - b) / (b - a)`` below b, then 1; ``z_shape`` is
  its mirror, and ``pi_shape`` (a, b, c, d) is ``s_shape(a, b) * z_shape(c, d)``.
- ``cosine`` (c, w): ``0.5 * (1 + cos(2 / w * pi * (x - c)))`` from ``c - 0.5 * w`` to
  ``c + 0.5 * w``, 0 elsewhere (fuzzylite's Cosine; ``math.cos`` is the C library's ``cos``)
- ``concave`` (i, e): rising (``i < e``) ``(e - i) / (2 * e - i - x)`` below e, then 1;
  falling (``i > e``) ``(i - e) / (i - 2 * e + x)`` above e, and 1 up to it (fuzzylite's
  Concave)
- ``spike`` (c, w): ``exp(-|10 / w * (x - c)|)`` (fuzzylite's Spike)

This module imports numpy only inside :func:`trapezoid` and :func:`memberships`: ``flctool
infer`` on a small table uses :func:`firing_sets` in a process that never loads numpy.
"""

from __future__ import annotations

import math
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


def memberships(x: NDArray[Any], rows: NDArray[Any], kinds: Sequence[int] | None
                ) -> NDArray[Any]:
    """:func:`trapezoid` for sets of any shape: ``rows (L, 4)`` are trapezoid corners or a
    shape's parameters (padded with 0), ``kinds`` their codes (:data:`flctool.behaviour.shapes.
    CODES`; None: all trapezoids). Shapes other than the trapezoid are computed in float64
    by :func:`shape_membership`, value by value, and then cast to the dtype of ``x``."""
    import numpy as np

    result = trapezoid(x, rows)
    if kinds is None or not any(kinds):
        return result
    values = np.asarray(x, dtype=np.float64).tolist()
    rows = np.asarray(rows, dtype=np.float64)
    for j, kind in enumerate(kinds):
        if kind:
            p = rows[j].tolist()
            result[:, j] = [shape_membership(kind, p[0], p[1], p[2], p[3], v) for v in values]
    return result


def _exp(v: float) -> float:
    # math.exp raises where C's exp returns inf (what every other engine computes with)
    try:
        return math.exp(v)
    except OverflowError:
        return math.inf


def _power(base: float, exponent: float) -> float:
    try:
        return float(base ** exponent)
    except OverflowError:
        return math.inf


def _sigmoid(x: float, centre: float, slope: float) -> float:
    return 1.0 / (1.0 + _exp(-slope * (x - centre)))


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


def _gauss(x: float, mean: float, sigma: float) -> float:
    return _exp(-((x - mean) * (x - mean)) / (2.0 * sigma * sigma))


def shape_membership(kind: int, p0: float, p1: float, p2: float, p3: float, x: float) -> float:
    """The membership of ``x`` in the set of shape code ``kind`` (1-12, the shapes of
    :mod:`flctool.behaviour.shapes` in order) with parameters ``p0..p3`` (the formulas above)."""
    if kind == 1:
        return _gauss(x, p0, p1)
    if kind == 2:
        left = _gauss(x, p0, p1) if x < p0 else 1.0
        right = _gauss(x, p2, p3) if x > p2 else 1.0
        return left * right
    if kind == 3:
        return 1.0 / (1.0 + _power(abs((x - p2) / p0), 2.0 * p1))
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
        return _concave(x, p0, p1)
    return _exp(-abs(10.0 / p1 * (x - p0)))


def _concave(x: float, inflection: float, end: float) -> float:
    if inflection <= end:
        if x < end:
            return (end - inflection) / (2.0 * end - inflection - x)
    elif x > end:
        return (inflection - end) / (inflection - 2.0 * end + x)
    return 1.0


def firing_sets(s: float, sets: Sequence[Sequence[float]],
                kinds: Sequence[int] | None = None) -> list[tuple[int, float]]:
    """The sets a clipped value ``s`` belongs to: ``(index, membership)`` in set order, for
    the sets whose membership is above 0 (the same operations as :func:`trapezoid`, or
    :func:`shape_membership` for a set whose code in ``kinds`` is not 0)."""
    fired = []
    for j, (pa, pb, pc, pd) in enumerate(sets):
        if kinds is not None and kinds[j]:
            mu = shape_membership(kinds[j], pa, pb, pc, pd, s)
        elif s > pc:
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
