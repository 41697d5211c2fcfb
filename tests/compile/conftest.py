"""Every test of this package runs on both inference paths: the compiled kernels and numpy
(``flctool.compile.vectorised``), which must give the same bits."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from flctool.compile import controller


@pytest.fixture(autouse=True, params=["kernels", "numpy"])
def inference_path(request: pytest.FixtureRequest) -> Iterator[str]:
    controller.set_inference(request.param)
    yield request.param
    controller.set_inference("auto")
