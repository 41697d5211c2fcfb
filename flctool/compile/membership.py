"""Trapezoid membership of paper Sec. II, vectorised.

For a set (pa, pb, pc, pd)::

    mu(s) = max(0, (pd - s) / (pd - pc))   if s > pc
            max(0, (s - pa) / (pb - pa))   if s < pb
            1                              otherwise

``pb == pc`` is a triangle. A vertical edge (``pa == pb`` or ``pc == pd``) jumps: with
``pa == pb`` the membership is 0 for ``s < pa`` and 1 from ``pa`` on, so no division by zero
happens. Because inputs are clipped to their range first, a shoulder ending at the range's end
(``pc == pd == high``) has membership 1 at and beyond that end. This is exactly
``skfuzzy.trapmf`` (tests compare them).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def trapezoid(x: FloatArray, quads: FloatArray) -> FloatArray:
    """Membership of every value in every set: ``x (B,)``, ``quads (L, 4)`` -> ``(B, L)``."""
    s = np.asarray(x, dtype=np.float64)[:, None]
    pa, pb, pc, pd = (quads[:, k] for k in range(4))
    with np.errstate(divide="ignore", invalid="ignore"):
        falling = np.where(pd > pc, (pd - s) / (pd - pc), 0.0)
        rising = np.where(pb > pa, (s - pa) / (pb - pa), 0.0)
    mu = np.where(s > pc, falling, np.where(s < pb, rising, 1.0))
    return np.maximum(mu, 0.0)


def trapezoid_scalar(s: float, pa: float, pb: float, pc: float, pd: float) -> float:
    """The same membership for one value, in plain Python (the reference of the tests)."""
    if s > pc:
        return max(0.0, (pd - s) / (pd - pc)) if pd > pc else 0.0
    if s < pb:
        return max(0.0, (s - pa) / (pb - pa)) if pb > pa else 0.0
    return 1.0
