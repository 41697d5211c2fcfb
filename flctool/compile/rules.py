"""The rule base of a behaviour in plain Python: its consequents in rule order (eq. 1).

Used by :func:`flctool.compile.compile_behaviour` (which makes arrays of it) and by the
plain-Python path of ``flctool infer`` (which must not load numpy). Rule order itself is coded
once, in :mod:`flctool.behaviour.rule_order`; its two functions are named here too, for the
compiled side.
"""

from __future__ import annotations

import math

from flctool.behaviour.models import Behaviour
from flctool.behaviour.rule_order import rule_grid, rule_index

__all__ = ["rule_consequents", "rule_grid", "rule_index"]


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
