"""Genes to fuzzy sets and back: the codec of ``learning.sets`` (docs/learning.md).

A *set genome* is a flat vector of genes, each in [-1, 1], for the learned inputs in file
order; the zero genome is the file's sets. The codec knows sets, not learners: a learner
breeds genomes (:mod:`flctool.learners.set_genes`) and asks the codec for the sets they
stand for. Decoding gives an ordinary :class:`~flctool.behaviour.models.Behaviour`, validated
exactly as a hand-written file is, so compiling, exporting and the reference engines'
checks need nothing new.

``partition`` (one gene per gap between consecutive breakpoints of a strong partition).
The breakpoints of L sets are ``lo = P_0 < P_1 <= ... <= P_{2L-2} < P_{2L-1} = hi``: set j is
``(P_{2j-1}, P_{2j}, P_{2j+1}, P_{2j+2})`` (the first ``(lo, lo, P_1, P_2)``, the last ``(...,
hi, hi)``). Gene u scales its gap g to ``g * r ** u`` (``r = 1 + bound`` with ``bound_in:
spacing``, ``r = 1 + bound / g`` with ``units``); the scaled gaps are laid end to end and
stretched to fill the stretch between the pinned points again (the range's ends and the
corners of fixed sets). Gaps stay positive, so the order of breakpoints, the crossing of
neighbours and the sum of memberships (1 everywhere) hold for every genome; a gap of zero (a
triangle's peak) stays zero.

``lateral`` (one gene per set that is not fixed). Set j shifts by ``u * B_j`` (``B_j = bound``
in units, or ``bound`` times the distance from its centre to the nearest neighbour's); a
corner at an end of the range stays there and the others are clipped to it. If the shifts
change the order of the sets (any corner passing the same corner of the next set) or let the
coverage fall below ``floor``, all that input's shifts are halved until neither happens (after
40 halvings the file's sets, which reach the floor, are kept).

Decoded corners are rounded to nine significant digits of the stretch they lie in, so that
the zero genome gives the file's numbers back and learned files read well.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import SupportsFloat

from flctool.behaviour.fuzzy import InputVariable
from flctool.behaviour.models import Behaviour
from flctool.behaviour.set_learning import InputSetting, Quad, SetLearningConfig, coverage
from flctool.behaviour.shapes import trapezoids
from flctool.errors import LearnError

#: Halvings of a lateral genome's shifts before the file's sets are kept.
MAX_HALVINGS = 40
#: Significant digits of a decoded corner, relative to the stretch it lies in.
DIGITS = 9


def _rounded(value: float, span: float) -> float:
    places = DIGITS - math.floor(math.log10(span)) if span > 0 else DIGITS
    return round(value, places)


class InputCodec:
    """The codec of one input's sets: ``size`` genes -> its quadruples in set order."""

    def __init__(self, name: str, variable: InputVariable, setting: InputSetting) -> None:
        self.name = name
        self.setting = setting
        self.low, self.high = (float(v) for v in variable.range)
        self.set_names = tuple(variable.sets)
        self.quads: tuple[Quad, ...] = tuple(
            (float(pa), float(pb), float(pc), float(pd))
            for pa, pb, pc, pd in trapezoids(variable.sets.values()))
        self._layout = (_PartitionLayout.of(self) if setting.mode == "partition"
                        else _LateralLayout.of(self))
        self.size = self._layout.size

    def decode(self, genes: Sequence[float]) -> list[Quad]:
        """The quadruples (L,) of ``genes (size,)``, each gene clipped to [-1, 1]."""
        if len(genes) != self.size:
            raise ValueError(f"input '{self.name}' takes {self.size} set genes, not "
                             f"{len(genes)}")
        return self._layout.decode([min(1.0, max(-1.0, float(g))) for g in genes])


@dataclass(frozen=True)
class _PartitionLayout:
    codec: InputCodec
    points: tuple[float, ...]  # P_0 .. P_{2L-1}
    #: (first, last) pinned breakpoint indices of each stretch with genes, and the gap
    #: indices (i: the gap P_i .. P_{i+1}) in it that have one, in order.
    stretches: tuple[tuple[int, int, tuple[int, ...]], ...]

    @classmethod
    def of(cls, codec: InputCodec) -> _PartitionLayout:
        quads = codec.quads
        points = [codec.low]
        for _, _, pc, pd in quads[:-1]:
            points += [pc, pd]
        points.append(codec.high)
        names = codec.setting.fixed
        pinned = {0, len(points) - 1}
        for j, name in enumerate(codec.set_names):
            if name in names:
                pinned.update(_corner_indices(j, len(quads)))
        order = sorted(pinned)
        stretches = []
        for first, last in itertools.pairwise(order):
            gaps = tuple(i for i in range(first, last) if points[i + 1] > points[i])
            if last - first >= 2 and len(gaps) >= 2:
                stretches.append((first, last, gaps))
        return cls(codec, tuple(points), tuple(stretches))

    @property
    def size(self) -> int:
        return sum(len(gaps) for _, _, gaps in self.stretches)

    def decode(self, genes: list[float]) -> list[Quad]:
        points = list(self.points)
        setting = self.codec.setting
        used = 0
        for first, last, gaps in self.stretches:
            start, end = self.points[first], self.points[last]
            scaled = {}
            for i in gaps:
                gap = self.points[i + 1] - self.points[i]
                ratio = 1.0 + (setting.bound if setting.bound_in == "spacing"
                               else setting.bound / gap)
                scaled[i] = gap * ratio ** genes[used]
                used += 1
            total = math.fsum(scaled.values())
            reach = 0.0
            for i in range(first, last - 1):
                reach += scaled.get(i, 0.0)
                # rounding may not step past a neighbour: a pinned point is not rounded, and a
                # closed gap (a triangle's peak) must stay closed
                point = _rounded(start + (end - start) * (reach / total), end - start)
                points[i + 1] = min(end, max(points[i], point))
        count = len(self.codec.quads)
        return [(points[a], points[b], points[c], points[d])
                for a, b, c, d in (_corner_indices(j, count) for j in range(count))]


def _corner_indices(j: int, count: int) -> tuple[int, int, int, int]:
    """The breakpoint indices of set j's corners (P_0 twice for the first, P_{2L-1} for the
    last)."""
    top = 2 * count - 1
    return (max(0, 2 * j - 1), max(0, 2 * j), min(top, 2 * j + 1), min(top, 2 * j + 2))


@dataclass(frozen=True)
class _LateralLayout:
    codec: InputCodec
    moving: tuple[int, ...]  # the sets with a gene, in order
    reach: tuple[float, ...]  # the largest shift B_j of each of them

    @classmethod
    def of(cls, codec: InputCodec) -> _LateralLayout:
        names = codec.set_names
        moving = tuple(j for j, n in enumerate(names) if n not in codec.setting.fixed)
        centres = [(pb + pc) / 2 for _, pb, pc, _ in codec.quads]
        setting = codec.setting
        reach = []
        for j in moving:
            if setting.bound_in == "units":
                reach.append(setting.bound)
                continue
            near = [abs(centres[j] - centres[k]) for k in (j - 1, j + 1)
                    if 0 <= k < len(centres) and centres[k] != centres[j]]
            spacing = min(near) if near else codec.high - codec.low
            reach.append(setting.bound * spacing)
        return cls(codec, moving, tuple(reach))

    @property
    def size(self) -> int:
        return len(self.moving)

    def decode(self, genes: list[float]) -> list[Quad]:
        codec = self.codec
        scale = 1.0
        for _ in range(MAX_HALVINGS):
            quads = self._shifted(genes, scale)
            if self._keeps_order(quads) and coverage((codec.low, codec.high),
                                                     quads)[0] >= codec.setting.floor:
                return quads
            scale /= 2
        return list(codec.quads)

    def _shifted(self, genes: list[float], scale: float) -> list[Quad]:
        codec = self.codec
        lo, hi = codec.low, codec.high
        span = hi - lo
        quads = list(codec.quads)
        for j, reach, gene in zip(self.moving, self.reach, genes, strict=True):
            shift = gene * reach * scale
            quads[j] = tuple(  # type: ignore[assignment]
                v if v in (lo, hi) else _rounded(min(hi, max(lo, v + shift)), span)
                for v in codec.quads[j])
        return quads

    def _keeps_order(self, quads: list[Quad]) -> bool:
        original = self.codec.quads
        for j in range(len(quads) - 1):
            for k in range(4):
                if original[j][k] <= original[j + 1][k] and not quads[j][k] <= quads[j + 1][k]:
                    return False
        return True


class SetCodec:
    """The set genome of a behaviour whose ``learning.sets`` is given: ``size`` genes for
    the learned inputs, in file order (see the module docstring)."""

    def __init__(self, behaviour: Behaviour) -> None:
        config: SetLearningConfig | None = getattr(behaviour.learning, "sets", None)
        if config is None:
            raise LearnError(f"behaviour '{behaviour.name}' learns no sets",
                             hint="add learning.sets to learn its fuzzy sets")
        self.behaviour = behaviour
        self.config = config
        self.inputs: list[InputCodec] = []
        self.slices: list[tuple[int, int]] = []
        start = 0
        for name, setting in config.settings(behaviour.input_names).items():
            codec = InputCodec(name, behaviour.inputs[name], setting)
            self.inputs.append(codec)
            self.slices.append((start, start + codec.size))
            start += codec.size
        self.size = start

    def zeros(self) -> list[float]:
        """The genome of the file's sets."""
        return [0.0] * self.size

    def decode_sets(self, genes: Sequence[float]) -> dict[str, dict[str, Quad]]:
        """Each learned input's sets (name -> quadruple, in file order) for ``genes (G,)``."""
        if len(genes) != self.size:
            raise ValueError(f"the set genome has {self.size} genes, not {len(genes)}")
        return {codec.name: dict(zip(codec.set_names, codec.decode(genes[a:b]), strict=True))
                for codec, (a, b) in zip(self.inputs, self.slices, strict=True)}

    def decode(self, genes: Sequence[float]) -> Behaviour:
        """The behaviour with the sets of ``genes (G,)``, validated as a file is."""
        return with_sets(self.behaviour, self.decode_sets(genes))


def with_sets(behaviour: Behaviour, sets: dict[str, dict[str, Quad]]) -> Behaviour:
    """``behaviour`` with the given inputs' sets replaced, through the validation every
    behaviour file passes (names, order and ranges are kept)."""
    from flctool.behaviour.dump import behaviour_to_data
    from flctool.behaviour.load import behaviour_from_data

    data = behaviour_to_data(behaviour)
    for name, quads in sets.items():
        data["inputs"][name]["sets"] = {s: list(q) for s, q in quads.items()}
    return behaviour_from_data(data)


def set_gene_count(behaviour: Behaviour) -> int:
    """The length G of ``behaviour``'s set genome (0 when it learns no sets)."""
    return 0 if getattr(behaviour.learning, "sets", None) is None else SetCodec(behaviour).size


def with_set_genes(behaviour: Behaviour, genes: Iterable[SupportsFloat] | None) -> Behaviour:
    """``behaviour`` with the sets of the set genome ``genes`` (None: as it is)."""
    if genes is None:
        return behaviour
    return SetCodec(behaviour).decode([float(g) for g in genes])
