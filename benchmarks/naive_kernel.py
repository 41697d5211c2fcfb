"""The anchor the inference goals are measured against: a naive numba kernel of eq. 1-3.

A plain loop, as one would first write it: for each state, the membership of every set
(paper Sec. II, the reference's branches), then the Mamdani min of every rule (eq. 1-2), then
the centre of area over singletons (eq. 3), clipped to the smallest and largest command as
flctool's output is. Compiled with numba like flctool's kernels (``error_model="numpy"``, no
fastmath), so it computes bit for bit what flctool computes and the benchmarks check that.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

from flctool import Controller


@numba.njit(cache=True, error_model="numpy")
def _membership(s: float, pa: float, pb: float, pc: float, pd: float) -> float:
    if s > pc:
        return max(0.0, (pd - s) / (pd - pc)) if pd > pc else 0.0
    if s < pb:
        return max(0.0, (s - pa) / (pb - pa)) if pb > pa else 0.0
    return 1.0


@numba.njit(cache=True, error_model="numpy")
def naive_infer(states: Any, lo: Any, hi: Any, quads: Any, offsets: Any, grid: Any,
                consequents: Any, singletons: Any) -> Any:
    """``states (B, N)`` -> ``(B,)``; ``grid (M, N)`` holds each rule's rows of ``quads``."""
    out = np.empty(states.shape[0])
    mu = np.empty(quads.shape[0])
    low, high = singletons.min(), singletons.max()
    for b in range(states.shape[0]):
        for i in range(states.shape[1]):
            s = min(max(states[b, i], lo[i]), hi[i])
            for j in range(offsets[i], offsets[i + 1]):
                mu[j] = _membership(s, quads[j, 0], quads[j, 1], quads[j, 2], quads[j, 3])
        numerator = 0.0
        denominator = 0.0
        for m in range(grid.shape[0]):
            alpha = mu[grid[m, 0]]
            for i in range(1, grid.shape[1]):
                alpha = min(alpha, mu[grid[m, i]])
            numerator += alpha * singletons[consequents[m]]
            denominator += alpha
        value = numerator / denominator
        out[b] = low if value < low else high if value > high else value
    return out


def naive_arrays(controller: Controller) -> tuple[Any, ...]:
    """The controller's arrays as :func:`naive_infer` takes them (after ``states``)."""
    offsets = np.concatenate([[0], np.cumsum(controller.shape)]).astype(np.intp)
    grid = np.ascontiguousarray(controller.rule_grid + offsets[:-1], dtype=np.intp)
    assert controller.consequents is not None
    return (np.ascontiguousarray(controller.ranges[:, 0]),
            np.ascontiguousarray(controller.ranges[:, 1]),
            np.concatenate(controller.quadruples).astype(np.float64), offsets, grid,
            np.array(controller.consequents, dtype=np.intp),
            np.array(controller.singletons, dtype=np.float64))


def naive_output(controller: Controller) -> Any:
    """A callable ``states (B, N) -> (B,)`` with the controller's arrays bound."""
    arrays = naive_arrays(controller)

    def output(states: Any) -> Any:
        return naive_infer(states, *arrays)
    return output
