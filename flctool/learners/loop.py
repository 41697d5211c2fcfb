"""The one training loop every learner runs: advance, evaluate, the run's parts, report.

A learner (:class:`~flctool.learners.base.Learner`) supplies a generation's two steps; this
loop times them, lets the run callbacks act (model selection, the budget, confirmation),
turns each generation into its metrics and hands them to the callbacks that watch the run
(:mod:`flctool.learners.callbacks`), the same way for every learner.
"""

from __future__ import annotations

import time
from collections.abc import Iterable

from flctool.learners.base import Learner
from flctool.learners.callbacks import Callback, CallbackList
from flctool.learners.metrics import GenerationMetrics


def train(learner: Learner, callbacks: Iterable[Callback] = ()) -> list[GenerationMetrics]:
    """Run generations from the learner's current one until the run ends: at
    ``learning.generations``, or when a run callback (a ``learning.stop`` budget or target)
    ends it.

    A fresh learner starts at generation 0; one restored from a checkpoint continues after
    it. Each generation is advance (breed), evaluate (the trials), then the run callbacks
    (:attr:`Learner.run_callbacks`: model selection validates, the budget decides whether to
    stop; when the run ends, selection validates its remaining candidates), then the report:
    the generation's metrics to ``callbacks``. So the metrics -- and the checkpoint a run
    directory writes of them -- already hold the run's final choice. Returns this session's
    metrics, one per generation.
    """
    callback = CallbackList(callbacks)
    history: list[GenerationMetrics] = []
    usage = learner.usage
    # on_end runs however training ends -- finished, stopped early, an error or Ctrl-C -- so
    # that a run directory never claims to be running after its process has gone.
    try:
        callback.on_start(learner)
        started = time.perf_counter()
        before = learner.elapsed

        def clock() -> None:
            learner.elapsed = before + time.perf_counter() - started

        generation = learner.generation + 1
        while not learner.finished:
            spent = (usage.selection_episodes, usage.selection_steps,
                     usage.confirmation_episodes, usage.confirmation_steps)
            if generation > 0:
                learner.advance()
            result = learner.evaluate(generation)
            learner.generation = generation
            usage.training_episodes += result.episodes
            usage.training_steps += result.steps
            for part in learner.run_callbacks:
                part.on_trials(learner, result)
                clock()
            if learner.finished:
                for part in learner.run_callbacks:
                    part.on_finish(learner)
                clock()
            best = learner.selection.best
            metrics = GenerationMetrics.from_fitness(
                generation, result.fitness, result.episodes, result.steps, learner.elapsed,
                usage.selection_episodes - spent[0], usage.selection_steps - spent[1],
                best.validation_value() if best else float("nan"),
                usage.confirmation_episodes - spent[2], usage.confirmation_steps - spent[3])
            history.append(metrics)
            generation += 1
            if not callback.on_generation(metrics):
                break
    finally:
        callback.on_end()
    return history
