"""Rule order (eq. 1), coded once: rule ``m`` is one combination of sets, enumerated with the
**last input varying fastest** -- the order of ``itertools.product``. For inputs with
L = (3, 5) sets, rule 0 is (set 0, set 0), rule 1 is (set 0, set 1), ..., rule 5 is
(set 1, set 0). Chromosomes, q tables, the compiled controller and every export index rules
this way.

It sits with the behaviour models, the lowest layer that needs it (a behaviour lists its
antecedents and missing rules in this order); :mod:`flctool.compile.rules` builds the rule
base on it. Plain Python: the behaviour models and ``flctool infer``'s small path load no
numpy.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence


def rule_grid(shape: Sequence[int]) -> list[tuple[int, ...]]:
    """Each rule's set index of each input, in rule order: ``M = prod(shape)`` tuples."""
    return list(itertools.product(*(range(sets) for sets in shape)))


def rule_index(sets: Sequence[int], shape: Sequence[int]) -> int:
    """The rule number of one combination of set indices (the inverse of :func:`rule_grid`)."""
    index = 0
    for j, width in zip(sets, shape, strict=True):
        index = index * width + j
    return index
