"""Centre-of-area defuzzification over singletons (paper eq. 3): the one Python coding.

    a = sum_m alpha_m * y_(k_m) / sum_m alpha_m

Both sums run left to right in rule order, starting from zero, exactly as the compiled
kernels and the C export accumulate them, so every path gives the same bits. The builtin
``sum()`` is not used: from Python 3.12 it compensates float sums and rounds differently,
which would make runs differ between Python versions. The same code serves Python floats
(the learners' one-state path) and numpy arrays of one dtype (the float export's error, in
float32), because it uses only ``+``, ``*`` and ``/``.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TypeVar

Number = TypeVar("Number")


def centre_of_area(terms: Iterable[tuple[Number, Number]], zero: Number) -> Number:
    """Eq. 3 over ``(alpha_m, y_(k_m))`` pairs in rule order; ``zero`` starts both sums (0.0,
    or an array of zeros of the result's shape and dtype). The caller handles a zero total
    (no rule fires) and keeps the result within the commands (rounding may step an ulp
    past them)."""
    weighted = total = zero
    for alpha, singleton in terms:
        weighted = weighted + alpha * singleton  # type: ignore[operator]
        total = total + alpha  # type: ignore[operator]
    return weighted / total  # type: ignore[operator, no-any-return]
