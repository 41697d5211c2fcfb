"""Learners of rule consequents: ``pitt``, ``fuzzy_q``, the paper's ``hybrid``, and ``credit``.

Each is registered by the name that ``learning.learner`` takes in a behaviour file; all run
the same training loop (:func:`train`) with callbacks, and know environments only through
the adapter protocol.
"""

from __future__ import annotations

from flctool.behaviour.located import located
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv
from flctool.learners.base import Learner
from flctool.learners.callbacks import Callback, CallbackList, FunctionCallback, StopAtFitness
from flctool.learners.loop import train
from flctool.learners.metrics import GenerationMetrics, GenerationResult
from flctool.plugins import blamed, registry
from flctool.registry import Registry
from flctool.rollout import TRAIN_SEED_LOW

#: Built from :mod:`flctool.plugins` (the built-ins and installed ``flctool.learners`` entries).
LEARNERS: Registry[type[Learner]] = registry("learner", "learner")


def make_learner(behaviour: Behaviour, env: BatchEnv | None = None) -> Learner:
    """The learner ``behaviour.learning.learner``, on ``env`` or on a batch-of-one
    environment built from the behaviour's ``environment:`` section."""
    learner_class = LEARNERS.get(behaviour.learning.learner)
    built = env is None
    if env is None:
        from flctool.envs import make_env

        env = make_env(behaviour, 1)
    try:
        # the learner's checks name fields; located adds file and line
        with located(behaviour), blamed("learner", behaviour.learning.learner):
            return learner_class(behaviour, env)
    except BaseException:
        if built:
            env.close()  # built here for this learner: nobody else will close it
        raise


__all__ = [
    "LEARNERS",
    "TRAIN_SEED_LOW",
    "Callback",
    "CallbackList",
    "FunctionCallback",
    "GenerationMetrics",
    "GenerationResult",
    "Learner",
    "StopAtFitness",
    "make_learner",
    "train",
]
