"""The rule base of a behaviour in plain Python: rule order (eq. 1) and consequents.

The one coding of rule order, used by :func:`flctool.compile.compile_behaviour` (which makes
arrays of it) and by the plain-Python path of ``flctool infer`` (which must not load numpy).
Rule ``m`` is one combination of sets, enumerated with the **last input varying fastest**,
the order of ``itertools.product`` (see :mod:`flctool.compile.controller`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

from flctool.spec.models import Behaviour


def rule_grid(shape: Sequence[int]) -> list[tuple[int, ...]]:
    """Each rule's set index of each input, in rule order: ``M = prod(shape)`` tuples."""
    return list(itertools.product(*(range(sets) for sets in shape)))


def rule_index(sets: Sequence[int], shape: Sequence[int]) -> int:
    """The rule number of one combination of set indices (the inverse of :func:`rule_grid`)."""
    index = 0
    for j, width in zip(sets, shape, strict=True):
        index = index * width + j
    return index


def rule_consequents(behaviour: Behaviour) -> list[int] | None:
    """Each rule's command index, in rule order; None if the behaviour is not deployable."""
    if not behaviour.is_deployable:
        return None
    names = list(behaviour.inputs)
    set_names = [list(v.sets) for v in behaviour.inputs.values()]
    shape = [len(sets) for sets in set_names]
    command = {name: k for k, name in enumerate(behaviour.output.commands)}
    consequents = [0] * math.prod(shape)
    for rule in behaviour.rules:
        sets = [set_names[i].index(rule.if_[name]) for i, name in enumerate(names)]
        consequents[rule_index(sets, shape)] = command[rule.then]
    return consequents
