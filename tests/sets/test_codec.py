"""The set codec: every genome of every mode decodes to a partition that validates."""

from __future__ import annotations

import itertools
import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flctool.behaviour.load import behaviour_from_data
from flctool.behaviour.models import Behaviour
from flctool.behaviour.set_learning import coverage
from flctool.membership import trapezoid_scalar
from flctool.sets.codec import SetCodec


def _behaviour(sets: dict[str, list[float]], low: float, high: float,
               learning: dict[str, Any]) -> Behaviour:
    return behaviour_from_data({
        "flctool": 1, "name": "codec",
        "inputs": {"x": {"range": [low, high], "sets": sets},
                   "y": {"range": [0, 1], "sets": {"a": [0, 0, 0.4, 0.6], "b": [0.4, 0.6, 1, 1]}}},
        "output": {"name": "a", "commands": {"l": -1.0, "r": 1.0}},
        "learning": {"sets": learning}})


@st.composite
def strong_partitions(draw: st.DrawFn) -> tuple[dict[str, list[float]], float, float]:
    """A strong partition of L sets on a random range, with triangles now and then."""
    low = draw(st.floats(-1e3, 1e3))
    width = draw(st.floats(1e-2, 1e3))
    high = low + width
    count = draw(st.integers(1, 7))
    cuts = sorted(draw(st.lists(st.floats(0.001, 0.999), min_size=2 * (count - 1),
                                max_size=2 * (count - 1), unique=True)))
    points = [low, *(round(low + c * width, 6) for c in cuts), high]
    if len(set(points)) != len(points) or points != sorted(points):
        points = [low + width * i / (2 * count - 1) for i in range(2 * count)]
        points[-1] = high  # width * n / n may miss width by an ulp
    # a triangle: a set whose shoulders meet (gap between P_2j and P_2j+1 closed)
    for j in range(1, count - 1):
        if draw(st.booleans()):
            points[2 * j + 1] = points[2 * j]
    sets = {}
    for j in range(count):
        top = 2 * count - 1
        a, b, c, d = (max(0, 2 * j - 1), max(0, 2 * j), min(top, 2 * j + 1), min(top, 2 * j + 2))
        sets[f"s{j}"] = [points[a], points[b], points[c], points[d]]
    return sets, low, high


def _genome(size: int) -> st.SearchStrategy[list[float]]:
    return st.lists(st.floats(-1.5, 1.5), min_size=size, max_size=size)


@settings(max_examples=150, deadline=None)
@given(strong_partitions(), st.sampled_from(["spacing", "units"]), st.floats(0.01, 3.0),
       st.data())
@pytest.mark.slow
def test_every_partition_genome_decodes_to_a_strong_partition(
        partition: tuple[dict[str, list[float]], float, float], bound_in: str, bound: float,
        data: st.DataObject) -> None:
    sets, low, high = partition
    names = list(sets)
    fixed = data.draw(st.lists(st.sampled_from(names), unique=True, max_size=len(names)))
    if bound_in == "units":
        bound = min(bound, high - low)
    original = _behaviour(sets, low, high, {
        "mode": "partition", "inputs": {"x": {"fixed": fixed, "bound": bound,
                                              "bound_in": bound_in}}})
    codec = SetCodec(original)
    genes = data.draw(_genome(codec.size))
    learned = codec.decode(genes)  # validated as a file is: raises if not
    variable = learned.inputs["x"]
    assert list(variable.sets) == names and variable.range == (low, high)
    for name in fixed:
        assert variable.sets[name] == tuple(sets[name])
    quads = list(variable.sets.values())
    assert quads[0][:2] == (low, low) and quads[-1][2:] == (high, high)
    for left, right in itertools.pairwise(quads):
        assert right[:2] == left[2:] and left[2] < left[3]  # adjacent sets cross on a slope
    for i in range(41):
        s = min(high, low + (high - low) * i / 40)  # inputs are clipped to the range
        total = math.fsum(trapezoid_scalar(s, *q) for q in quads)
        assert abs(total - 1.0) <= 1e-12


@st.composite
def covering_partitions(draw: st.DrawFn) -> tuple[dict[str, list[float]], float]:
    """Trapezoids evenly spread with random overlap and widths, covering [0, 10]."""
    count = draw(st.integers(1, 6))
    step = 10.0 / count
    sets = {}
    for j in range(count):
        centre = step * (j + 0.5)
        core = draw(st.floats(0.0, 0.4)) * step
        foot = draw(st.floats(0.6, 1.5)) * step
        quad = [centre - foot, centre - core, centre + core, centre + foot]
        if j == 0:
            quad[:2] = [0.0, 0.0]
        if j == count - 1:
            quad[2:] = [10.0, 10.0]
        sets[f"s{j}"] = [min(10.0, max(0.0, round(v, 6))) for v in quad]
    floor = min(0.9, coverage((0.0, 10.0), list(sets.values()))[0])
    return sets, floor


@settings(max_examples=150, deadline=None)
@given(covering_partitions(), st.sampled_from(["spacing", "units"]), st.floats(0.01, 5.0),
       st.data())
@pytest.mark.slow
def test_every_lateral_genome_keeps_order_and_the_coverage_floor(
        partition: tuple[dict[str, list[float]], float], bound_in: str, bound: float,
        data: st.DataObject) -> None:
    sets, floor = partition
    names = list(sets)
    fixed = data.draw(st.lists(st.sampled_from(names), unique=True, max_size=len(names)))
    original = _behaviour(sets, 0.0, 10.0, {
        "mode": "lateral", "floor": floor,
        "inputs": {"x": {"fixed": fixed, "bound": bound, "bound_in": bound_in}}})
    codec = SetCodec(original)
    learned = codec.decode(data.draw(_genome(codec.size)))
    variable = learned.inputs["x"]
    assert list(variable.sets) == names and variable.range == (0.0, 10.0)
    for name in fixed:
        assert variable.sets[name] == tuple(sets[name])
    quads = list(variable.sets.values())
    before = list(sets.values())
    for j in range(len(quads) - 1):
        for k in range(4):
            if before[j][k] <= before[j + 1][k]:
                assert quads[j][k] <= quads[j + 1][k]
    assert coverage((0.0, 10.0), quads)[0] >= floor
    if bound_in == "units":
        for quad, old in zip(quads, before, strict=True):
            # corners are rounded to 9 digits of the range
            assert max(abs(a - b) for a, b in zip(quad, old, strict=True)) <= bound + 1e-7


@pytest.mark.parametrize("mode", ["partition", "lateral"])
def test_the_zero_genome_is_the_files_sets(mode: str) -> None:
    sets = {"a": [0, 0, 0.2, 0.45], "b": [0.2, 0.45, 0.5, 0.7], "c": [0.5, 0.7, 1, 1]}
    original = _behaviour(sets, 0.0, 1.0, {"mode": mode})
    codec = SetCodec(original)
    # partition: one gene per gap between breakpoints (x: 5, y: 3); lateral: one per set
    assert codec.size == (5 + 3 if mode == "partition" else 3 + 2)
    assert codec.decode(codec.zeros()).inputs == original.inputs


def test_only_the_chosen_inputs_get_genes() -> None:
    sets = {"a": [0, 0, 0.2, 0.45], "b": [0.2, 0.45, 1, 1]}
    original = _behaviour(sets, 0.0, 1.0, {"inputs": ["y"]})
    codec = SetCodec(original)
    genes = [1.0, -1.0, 0.5][: codec.size]  # scaling every gap alike would change nothing
    learned = codec.decode(genes)
    assert learned.inputs["x"] == original.inputs["x"]
    assert learned.inputs["y"] != original.inputs["y"]
    assert list(codec.decode_sets(genes)) == ["y"]


def test_a_genome_of_the_wrong_length_is_refused() -> None:
    codec = SetCodec(_behaviour({"a": [0, 0, 0.2, 0.45], "b": [0.2, 0.45, 1, 1]}, 0, 1, {}))
    with pytest.raises(ValueError, match="genes"):
        codec.decode([0.0])
