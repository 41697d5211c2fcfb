"""Environment adapters, found by name: learners and the CLI never import a concrete one.

    env = make_env(behaviour, batch_size=1000)   # the adapter named by environment.adapter
    obs, info = env.reset(seeds)                 # (B,) -> (B, N)

The protocol is :class:`flctool.envs.base.BatchEnv`; :func:`check_env` checks an adapter
against it.

The protocol and the checker (which need numpy) load on first use (PEP 562 module
``__getattr__``), so that importing a module of this package, e.g. ``flctool validate``'s
preflight, does not import numpy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from flctool.behaviour.located import located
from flctool.behaviour.models import Behaviour
from flctool.errors import EnvError
from flctool.lazy import lazy_attributes
from flctool.plugins import blamed, registry
from flctool.registry import Registry

if TYPE_CHECKING:
    from flctool.envs.base import BatchEnv, SingleEnv, Step
    from flctool.envs.checker import check_env

_LAZY = {"BatchEnv": "flctool.envs.base", "SingleEnv": "flctool.envs.base",
         "Step": "flctool.envs.base", "check_env": "flctool.envs.checker"}


class EnvFactory(Protocol):
    """What the registry holds: builds an adapter for a behaviour."""

    def from_behaviour(self, behaviour: Behaviour, batch_size: int = 1) -> BatchEnv: ...


#: Found from :mod:`flctool.plugins` (the built-ins and installed ``flctool.environments``
#: entries), each imported when first used.
ENVIRONMENTS: Registry[EnvFactory] = registry("environment", "environment adapter")


def make_env(behaviour: Behaviour, batch_size: int = 1) -> BatchEnv:
    """The adapter named by ``behaviour.environment.adapter``, built for this behaviour.

    ``batch_size`` is a hint (adapters that hold one world per episode build that many up
    front); the number of seeds given to ``reset`` decides B. Raises :class:`SpecError`
    naming the field (at its line in the behaviour's file) when the environment does not fit
    the behaviour, :class:`MissingDependencyError` when the adapter's optional package is
    missing.
    """
    if behaviour.environment is None:
        raise EnvError(f"behaviour '{behaviour.name}' has no 'environment' section",
                       hint="add e.g. 'environment: {adapter: ballchase-sim}'")
    if batch_size < 1:
        raise EnvError(f"batch_size must be at least 1, got {batch_size}")
    factory = ENVIRONMENTS.get(behaviour.environment.adapter)
    with located(behaviour), blamed("environment", behaviour.environment.adapter):
        # the adapter's checks name fields; located adds file and line
        return factory.from_behaviour(behaviour, batch_size)


__getattr__ = lazy_attributes(__name__, _LAZY)

__all__ = ["ENVIRONMENTS", "BatchEnv", "EnvFactory", "SingleEnv", "Step", "check_env",
           "make_env"]
