"""How readable a partition still is, and how far its sets moved: the interpretability
measures a run records for learned sets, and what ``flctool show --compare`` lists.

Per input:

- **coverage**: the least, over the range, of the largest membership of any set
  (``min_s max_j mu_j(s)``); 1 means every value fully belongs to some set, 0 a gap. A strong
  partition has at least 0.5.
- **overlap** of neighbours: for each pair of adjacent sets (in file order) the height at
  which they cross, ``max_s min(mu_j(s), mu_{j+1}(s))``; 0 means they do not meet (the
  rules of one never blend with the other's), 1 that one covers the other's core.
- **movement**: per set, the largest change of a corner from the reference (the file's
  sets), in the input's units and as a fraction of the range.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from flctool.behaviour.fuzzy import FuzzySet
from flctool.behaviour.models import Behaviour
from flctool.behaviour.set_learning import Quad, coverage, membership
from flctool.behaviour.shapes import is_trapezoid, trapezoids


def crossing_height(left: Sequence[float], right: Sequence[float]) -> float:
    """``max_s min(mu_left(s), mu_right(s))``: where the two trapezoids' edges cross, or 1
    where their cores meet."""
    lo = max(left[0], right[0])
    hi = min(left[3], right[3])
    if lo > hi:
        return 0.0
    points = {lo, hi, *(v for v in (*left, *right) if lo <= v <= hi)}
    # the crossing of left's falling edge with right's rising edge, where both are sloped
    pc, pd = left[2], left[3]
    pa, pb = right[0], right[1]
    if pd > pc and pb > pa:
        s = (pa * (pd - pc) + pd * (pb - pa)) / ((pd - pc) + (pb - pa))
        if lo <= s <= hi:
            points.add(s)
    return max(min(membership(s, left), membership(s, right)) for s in points)


@dataclass(frozen=True)
class SetMovement:
    """How far one set moved from its reference."""

    input: str
    set: str
    before: Quad
    after: Quad
    largest: float  # the largest change of a corner, in the input's units
    fraction: float  # that as a fraction of the input's range

    def to_dict(self) -> dict[str, Any]:
        return {"input": self.input, "set": self.set, "before": list(self.before),
                "after": list(self.after), "moved": self.largest,
                "moved_fraction_of_range": self.fraction}


def movements(reference: Behaviour, learned: Behaviour) -> list[SetMovement]:
    """Each set's movement from ``reference`` to ``learned`` (inputs and sets in file order;
    both must have the same inputs and set names: a learned behaviour does)."""
    found = []
    for name, variable in reference.inputs.items():
        other = learned.inputs.get(name)
        if other is None:
            continue
        lo, hi = variable.range
        for set_name, before in variable.sets.items():
            after = other.sets.get(set_name)
            if after is None or not (is_trapezoid(before) and is_trapezoid(after)):
                continue  # (a set of another shape is never learned: it does not move)
            largest = max(abs(a - b) for a, b in zip(after, before, strict=True))
            found.append(SetMovement(name, set_name, tuple(before), tuple(after),  # type: ignore[arg-type]
                                     largest, largest / (hi - lo)))
    return found


def trapezoid_sets(sets: Mapping[str, FuzzySet]) -> dict[str, Quad]:
    """``sets`` as quadruples: every set must be a trapezoid (learned sets are)."""
    return dict(zip(sets, trapezoids(sets.values()), strict=True))


def partition_measures(bounds: Sequence[float],
                       sets: Mapping[str, Sequence[float]]) -> dict[str, Any]:
    """Coverage and neighbour overlaps of one input's partition."""
    quads = list(sets.values())
    least, where = coverage(bounds, quads)
    names = list(sets)
    overlaps = {f"{a}|{b}": crossing_height(quads[i], quads[i + 1])
                for i, (a, b) in enumerate(itertools.pairwise(names))}
    return {"coverage": least, "least_covered_at": where, "overlaps": overlaps,
            "least_overlap": min(overlaps.values(), default=None),
            "greatest_overlap": max(overlaps.values(), default=None)}


def interpretability(reference: Behaviour, learned: Behaviour,
                     inputs: Sequence[str] | None = None) -> dict[str, Any]:
    """The run record's measures of the learned sets: per input (the learned ones, or
    ``inputs``) coverage, overlaps and each set's movement from ``reference``."""
    chosen = list(inputs) if inputs is not None else list(learned.inputs)
    moved = movements(reference, learned)
    record: dict[str, Any] = {}
    for name in chosen:
        variable = learned.inputs[name]
        record[name] = {
            **partition_measures(variable.range, trapezoid_sets(variable.sets)),
            "movement": {m.set: {"moved": m.largest, "moved_fraction_of_range": m.fraction}
                         for m in moved if m.input == name},
        }
    return record
