"""Bounds on the numbers of an ``environment:`` section, so a simulation cannot overflow.

A simulator multiplies and squares what the file gives (a step of ``forward`` mm, a pitch
``length``, a noise's standard deviation); a value such as ``1e308`` validates as a float,
yet its square is infinite and the next difference NaN -- which would surface steps later as
"the environment observed NaN" with no word of the file. Every number of the section is
therefore bounded by :data:`MAX_MAGNITUDE` in size, and so are the items of its lists and
maps (integers count steps or episodes, and are bounded where they are defined): the
product of two such numbers is at most 1e18, and a million steps of them at most 1e24, far
below float64's 1.8e308, so no sum, product or square a simulator forms of them overflows.
The bound is a billion millimetres (1,000 km), degrees or seconds, beyond any robot's world.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel

from flctool.errors import PathPart, Problem

MAX_MAGNITUDE = 1e9


def magnitude_problems(value: Any, path: tuple[PathPart, ...] = ("environment",)
                       ) -> list[Problem]:
    """A problem at each number of ``value`` (a validated section, or its raw data) whose
    size exceeds :data:`MAX_MAGNITUDE`."""
    problems: list[Problem] = []
    stack: list[tuple[Any, tuple[PathPart, ...]]] = [(value, path)]
    while stack:
        item, where = stack.pop()
        if isinstance(item, BaseModel):
            stack.extend((getattr(item, name), (*where, info.alias or name))
                         for name, info in type(item).model_fields.items())
        elif isinstance(item, Mapping):
            stack.extend((v, (*where, str(k))) for k, v in item.items())
        elif isinstance(item, (list, tuple)):
            stack.extend((v, (*where, i)) for i, v in enumerate(item))
        elif isinstance(item, float) and not math.isinf(item) and abs(item) > MAX_MAGNITUDE:
            problems.append(Problem(where, f"{item!r} is too large for a simulation: a "
                                    "value here may be at most "
                                    f"{MAX_MAGNITUDE:g} in size (its square would "
                                    "overflow)", f"write a value within ±{MAX_MAGNITUDE:g}"))
    return sorted(problems, key=lambda p: str(p.path))
