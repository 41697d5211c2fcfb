"""How the pitch world's crisp output becomes the robot's walk: the command table's motions,
blended or nearest (:class:`CommandDrive`), or a composition's parts (:mod:`.pitch_compose`),
behind one protocol (:class:`Drive`) that both engines of :mod:`.pitch` call.

A module of its own so that the composition builds on the walk without importing the engines
that run it.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from flctool.behaviour.environment import Motion, MotionNoise
from flctool.envs.base import FloatArray

_RAD = math.pi / 180.0


class Drive(Protocol):
    """How the crisp output becomes the robot's motion (mean and std of forward, sideways,
    rotation), for one episode or B."""

    order: tuple[str, ...]
    values: FloatArray
    reads: bool  # whether it reads the channels' readings (a composition's parts do)

    def one(self, action: float, readings: Sequence[float] = (),
            ) -> tuple[list[float], list[float]]: ...

    def batch(self, actions: FloatArray, readings: Sequence[FloatArray] = (),
              ) -> tuple[list[FloatArray], list[FloatArray]]: ...


class CommandDrive:
    """How the crisp output ``a`` becomes the robot's motion: the sorted singletons' motions
    blended piecewise linearly (crisp), or the nearest one's."""

    def __init__(self, commands: dict[str, float], motion: dict[str, Motion],
                 noise: dict[str, MotionNoise], nearest: bool) -> None:
        order = sorted(commands, key=lambda name: commands[name])
        self.order = tuple(order)  # commands by increasing singleton
        self.values = np.array([commands[n] for n in order], dtype=np.float64)
        self.values_list: list[float] = self.values.tolist()
        # Columns of the motion table by increasing singleton, the last row repeated so that
        # "nearest" (weight 0 on the row above) blends like "crisp" without a special case.
        rows = [*order, order[-1]]
        self.mean = [[motion[n].forward for n in rows], [motion[n].sideways for n in rows],
                     [motion[n].rotation * _RAD for n in rows]]
        self.std = [[noise[n].forward for n in rows], [noise[n].sideways for n in rows],
                    [noise[n].rotation * _RAD for n in rows]]
        self.mean_arrays = [np.array(column) for column in self.mean]
        self.std_arrays = [np.array(column) for column in self.std]
        self.nearest = nearest or len(order) == 1
        self.reads = False

    def batch(self, actions: FloatArray, readings: Sequence[FloatArray] = (),
              ) -> tuple[list[FloatArray], list[FloatArray]]:
        """Mean and std columns, each (B,), for actions (B,) (a composition's parts read
        ``readings``, the channels' readings before the step)."""
        values = self.values
        a = np.clip(actions, values[0], values[-1])
        if self.nearest:
            j = np.argmin(np.abs(a[:, None] - values[None, :]), axis=1)
            w = np.zeros_like(a)
        else:
            j = np.clip(np.searchsorted(values, a, side="right") - 1, 0, values.shape[0] - 2)
            gap = values[j + 1] - values[j]
            w = np.where(gap > 0, (a - values[j]) / np.where(gap > 0, gap, 1.0), 0.0)
        return _blend(self.mean_arrays, self.std_arrays, j, w)

    def one(self, action: float, readings: Sequence[float] = (),
            ) -> tuple[list[float], list[float]]:
        values = self.values_list
        count = len(values)
        # a Python float: numpy scalars would make every operation below several times slower
        a = min(max(float(action), values[0]), values[-1])
        if self.nearest:
            j, w = min(range(count), key=lambda i: abs(a - values[i])), 0.0
        else:
            j = min(max(bisect.bisect_right(values, a) - 1, 0), count - 2)
            gap = values[j + 1] - values[j]
            w = (a - values[j]) / gap if gap > 0 else 0.0
        return _blend(self.mean, self.std, j, w)


def _blend(mean: Sequence[Any], std: Sequence[Any], j: Any, w: Any,
           ) -> tuple[list[Any], list[Any]]:
    """Rows j and j + 1 of the motion table's columns, weighted (1 - w, w): crisp blending;
    nearest passes w = 0, which gives row j exactly."""
    keep = 1.0 - w
    return ([keep * c[j] + w * c[j + 1] for c in mean], [keep * c[j] + w * c[j + 1] for c in std])
