"""Inference without the JIT: numpy until the kernels pay for themselves, then the kernels,
with the same bits whichever runs (the other test modules here run on both paths)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.compile import controller as controller_module


def test_auto_starts_in_numpy_and_moves_to_the_kernels_once_they_pay(
        handmade_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    states = np.random.default_rng(3).uniform(controller.ranges[:, 0], controller.ranges[:, 1],
                                              size=(300, 2))
    monkeypatch.setattr(controller_module._Inference, "numpy_seconds", 0.0)
    monkeypatch.setattr(controller_module, "KERNELS_PAY_AFTER", float("inf"))
    monkeypatch.setattr(controller_module, "_kernels_cached", lambda: True)
    controller_module.set_inference("auto")
    assert not controller_module._kernels_on
    in_numpy = controller.output(states)
    one_in_python = controller.output_one(states[0])
    assert controller_module._Inference.numpy_seconds > 0.0  # its CPU is counted
    monkeypatch.setattr(controller_module, "KERNELS_PAY_AFTER", 0.0)
    controller.output(states[:1])  # the rent now exceeds the price: the next call buys
    assert controller_module._kernels_on
    np.testing.assert_array_equal(controller.output(states), in_numpy)
    assert controller.output_one(states[0]) == one_in_python


def test_kernels_not_in_the_cache_are_bought_at_the_price_of_compiling_them(
        handmade_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    controller = compile_behaviour(load_behaviour(handmade_path))
    states = np.random.default_rng(4).uniform(controller.ranges[:, 0], controller.ranges[:, 1],
                                              size=(50, 2))
    monkeypatch.setattr(controller_module._Inference, "numpy_seconds", 0.0)
    monkeypatch.setattr(controller_module, "KERNELS_PAY_AFTER", 0.0)
    monkeypatch.setattr(controller_module, "KERNELS_COMPILE_PAY_AFTER", float("inf"))
    monkeypatch.setattr(controller_module, "_kernels_cached", lambda: False)
    controller_module.set_inference("auto")
    in_numpy = controller.output(states)
    assert not controller_module._kernels_on  # past the loading price, short of compiling's
    monkeypatch.setattr(controller_module, "KERNELS_COMPILE_PAY_AFTER", 0.0)
    controller.output(states[:1])
    assert controller_module._kernels_on
    np.testing.assert_array_equal(controller.output(states), in_numpy)


def test_the_cache_check_finds_a_kernel_once_it_is_compiled() -> None:
    from flctool.compile import kernels

    kernels.entry("infer_own")  # compiled, or loaded from the cache
    assert kernels.cached("infer_own")


def test_an_unknown_mode_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown inference mode 'jit'; use one of: auto"):
        controller_module.set_inference("jit")


@pytest.mark.slow
def test_a_small_evaluation_never_loads_numba(handmade_path: Path) -> None:
    # In a fresh process, as a user runs it: numpy is enough, numba is never imported (so it
    # neither loads nor, on a machine's first run, compiles the kernels).
    probe = ("import sys\n"
             f"sys.argv = ['flctool', 'evaluate', {str(handmade_path)!r}, '--episodes', '200']\n"
             "from flctool.cli import run\n"
             "try:\n    run()\nexcept SystemExit:\n    pass\n"
             "print('numba' in sys.modules, file=sys.stderr)\n")
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                            timeout=300, env={**os.environ, "FLCTOOL_INFERENCE": "auto"})
    assert result.stderr.split()[-1] == "False", result.stderr
    assert "success rate" in result.stdout
