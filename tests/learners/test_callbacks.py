"""Callbacks of the training loop."""

from __future__ import annotations

import pytest

from flctool.learners import (
    Callback,
    CallbackList,
    FunctionCallback,
    GenerationMetrics,
    StopAtFitness,
)


def metrics(mean: float, best: float) -> GenerationMetrics:
    return GenerationMetrics(0, mean, 0.0, best, mean, 10, 100, 0.1)


def test_function_callback_sees_every_generation() -> None:
    seen: list[int] = []
    callback = FunctionCallback(lambda m: seen.append(m.generation))
    assert callback.on_generation(metrics(0.5, 1.0))
    assert seen == [0]


def test_stop_at_fitness_on_mean_or_best() -> None:
    assert StopAtFitness(1.0).on_generation(metrics(0.5, 1.5))
    assert not StopAtFitness(1.0, "best").on_generation(metrics(0.5, 1.5))
    with pytest.raises(ValueError, match="mean' or 'best"):
        StopAtFitness(1.0, "median")


def test_a_callback_list_stops_if_any_member_asks_and_still_calls_all() -> None:
    seen: list[int] = []
    callbacks = CallbackList([StopAtFitness(0.0), FunctionCallback(lambda m: seen.append(1))])
    assert not callbacks.on_generation(metrics(0.5, 1.0))
    assert seen == [1]


def test_a_callback_list_ends_every_member_even_if_one_fails() -> None:
    ended: list[str] = []

    class Failing(Callback):
        def on_end(self) -> None:
            ended.append("failing")
            raise RuntimeError("progress bar broke")

    class Closing(Callback):
        def on_end(self) -> None:
            ended.append("closing")

    with pytest.raises(RuntimeError, match="progress bar broke"):
        CallbackList([Failing(), Closing()]).on_end()
    assert ended == ["failing", "closing"]
