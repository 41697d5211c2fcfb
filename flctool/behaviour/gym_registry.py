"""Gymnasium's registry as a behaviour file reaches it, without stepping an environment.

Reading a ``gymnasium`` section needs a few facts of the registered environment: whether its id
would import a module the user did not name (``--import-module``), the options its constructor
takes, and the bounds of its observation space, from which an input's ``range`` defaults
(:func:`flctool.behaviour.environment.default_gymnasium_ranges`). They are here, below the
adapter (:mod:`flctool.envs.gym_adapter`), which checks the same facts before it makes its
environments. gymnasium is an optional extra: ``pip install 'flctool[gym]'``.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from flctool.errors import EnvError, MissingDependencyError, Problem, SpecError
from flctool.registry import did_you_mean


def import_gymnasium() -> Any:
    """The gymnasium module, or :class:`MissingDependencyError` with the install hint."""
    try:
        import gymnasium
    except ImportError:
        raise MissingDependencyError("gymnasium", "gym", "the gymnasium adapter") from None
    return gymnasium


#: Modules the user imported on the command line (``--import-module``). Gymnasium imports the
#: module of an id ``module:Env-v0`` itself; a behaviour file alone must not run code, so such
#: an id is refused unless its module is one of these.
_USER_MODULES: set[str] = set()


def import_user_modules(names: Iterable[str]) -> None:
    """Import the modules the user named (they register their Gymnasium environments) and
    allow ids ``module:Env-v0`` to name them. Raises :class:`EnvError` if one fails."""
    for name in names:
        try:
            importlib.import_module(name)
        except Exception as error:  # any failure of the user's module is theirs to fix
            raise EnvError(f"cannot import the module '{name}' (--import-module): "
                           f"{type(error).__name__}: {error}",
                           hint="check the module name and that it is importable") from None
        _USER_MODULES.add(name)


def id_module_problem(env_id: str) -> Problem | None:
    """A Gymnasium id that would import a module the user did not name, or None."""
    module, colon, _ = env_id.rpartition(":")
    if not colon or module in _USER_MODULES:
        return None
    return Problem(("environment", "id"), f"the id '{env_id}' names the Python module "
                   f"'{module}' to import, and reading a behaviour file never runs code",
                   f"if you trust the module, pass --import-module {module} on the command "
                   "line, or use the id without the module")


#: Keyword arguments gymnasium.make takes itself, whatever the environment.
_MAKE_OPTIONS = frozenset({"max_episode_steps", "disable_env_checker"})


def option_problems(gym: Any, env_id: str, options: Mapping[str, Any]) -> list[Problem]:
    """``environment.options`` of the id ``env_id`` checked against what the registered
    environment accepts, before it is made: ``render_mode`` against its
    ``metadata['render_modes']``, every other key against its constructor's parameters
    (unless it takes ``**kwargs``). Only the module
    the id is registered from is imported (as making it would); an id that names another
    module, or no registered id, is left to :func:`id_module_problem` and ``gym.make``."""
    if not options or id_module_problem(env_id) is not None:
        return []
    try:
        spec = gym.spec(env_id)
        creator = (gym.envs.registration.load_env_creator(spec.entry_point)
                   if isinstance(spec.entry_point, str) else spec.entry_point)
        parameters = inspect.signature(creator).parameters
    except Exception:  # an unknown id or an entry point that cannot be inspected: make says
        return []
    problems: list[Problem] = []
    modes = (getattr(creator, "metadata", None) or {}).get("render_modes")
    mode = options.get("render_mode")
    if mode is not None and isinstance(modes, (list, tuple)) and mode not in modes:
        problems.append(Problem(("environment", "options", "render_mode"),
                                f"'{mode}' is not a render mode of '{env_id}'."
                                f"{did_you_mean(str(mode), [str(m) for m in modes])}",
                                f"use one of: {', '.join(map(str, modes)) or '(none)'}, or "
                                "leave render_mode out"))
    if not any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values()):
        accepted = [name for name, p in parameters.items()
                    if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                  inspect.Parameter.KEYWORD_ONLY)]
        for key in options:
            if key not in accepted and key not in _MAKE_OPTIONS:
                problems.append(Problem(("environment", "options", key),
                                        f"'{env_id}' takes no option '{key}'."
                                        f"{did_you_mean(key, accepted)}",
                                        f"its options: {', '.join(accepted) or '(none)'}"))
    return problems


def observation_space_bounds(env_id: str, options: Mapping[str, Any],
                             ) -> tuple[list[float], list[float]]:
    """The low and high bounds ``(D,)`` of the one-dimensional Box observation space of the
    environment ``env_id`` made with ``options``, each the shortest decimal of its dtype
    (entries may be infinite). Makes the environment once, then closes it."""
    gym = import_gymnasium()
    problems = option_problems(gym, env_id, options)
    if problems:
        raise SpecError(problems)
    with _made(gym, env_id, options) as env:
        space = env.observation_space
        if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1:
            raise SpecError([Problem(("environment", "id"), f"'{env_id}' observes {space}; "
                                     "the gymnasium adapter needs a one-dimensional Box "
                                     "observation space")])
        # Bounds as the space's dtype prints them: float32 4.8 is 4.800000190734863 as a
        # double, and sets written up to 4.8 would leave a sliver uncovered.
        return ([float(str(v)) for v in space.low], [float(str(v)) for v in space.high])


def discrete_actions(env_id: str) -> int | None:
    """The number of actions of ``env_id``'s Discrete action space, or None for a Box one
    (the adapter checks the rest when it makes its environments). Makes the environment
    once, with its default options, then closes it; raises :class:`SpecError` if it cannot."""
    gym = import_gymnasium()
    with _made(gym, env_id, {}) as env:
        space = env.action_space
        return int(space.n) if isinstance(space, gym.spaces.Discrete) else None


#: The hint for an environment whose id Gymnasium knows but whose package is not installed.
MISSING_PACKAGE_HINT = ("the id is known but its environment needs a package that is not "
                        "installed: install what Gymnasium names, in the Python flctool runs in")


def missing_package(env_id: str, error: Exception) -> SpecError:
    """The error at ``environment.id`` for an id Gymnasium knows whose environment needs a
    package that is not installed (its message names the package)."""
    return SpecError([Problem(("environment", "id"), f"Gymnasium cannot make '{env_id}': "
                              f"{error}", MISSING_PACKAGE_HINT)])


@contextmanager
def _made(gym: Any, env_id: str, options: Mapping[str, Any]) -> Iterator[Any]:
    """The environment ``env_id`` made with ``options`` (a :class:`SpecError` at
    ``environment.id`` if Gymnasium cannot; make_env reports it in full), closed after."""
    try:
        env = gym.make(env_id, disable_env_checker=True, **dict(options))
    except gym.error.DependencyNotInstalled as error:
        raise missing_package(env_id, error) from None
    except (gym.error.Error, TypeError) as error:
        raise SpecError([Problem(("environment", "id"), f"Gymnasium cannot make "
                                 f"'{env_id}': {error}")]) from None
    try:
        yield env
    finally:
        env.close()
