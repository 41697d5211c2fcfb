"""Eq. 3's one Python coding: left-to-right sums, for floats and for float32 arrays."""

from __future__ import annotations

import math

import numpy as np

from flctool.compile.defuzzify import centre_of_area


def test_sums_run_left_to_right_not_compensated() -> None:
    # Left to right, 1 + 1e-16 + 1e-16 rounds to 1 at each step; a compensated sum (the
    # builtin sum() from Python 3.12, math.fsum) gives the next float up. Eq. 3 must round
    # as the kernels do, whatever the Python version.
    alphas = [1.0, 1e-16, 1e-16]
    singletons = [0.0, 1.0, 1.0]
    got = centre_of_area(zip(alphas, singletons, strict=True), 0.0)
    assert got == 2e-16
    assert got != math.fsum(a * y for a, y in zip(alphas, singletons, strict=True)) / math.fsum(
        alphas)


def test_arrays_keep_their_dtype() -> None:
    rng = np.random.default_rng(0)
    alphas = rng.uniform(0, 1, size=(4, 100)).astype(np.float32)
    singletons = np.array([-1.0, 0.25, 0.5, 2.0], dtype=np.float32)
    got = centre_of_area(zip(alphas, singletons, strict=True), np.zeros(100, dtype=np.float32))
    assert got.dtype == np.float32
    weighted = np.zeros(100, dtype=np.float32)
    total = np.zeros(100, dtype=np.float32)
    for a, y in zip(alphas, singletons, strict=True):
        weighted += a * y
        total += a
    np.testing.assert_array_equal(got, weighted / total)
