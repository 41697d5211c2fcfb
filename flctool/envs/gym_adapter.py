"""The gymnasium adapter: any registered Gymnasium environment with a Box observation space and
a Discrete or one-component Box action space, as a :class:`~flctool.envs.base.BatchEnv`.

* Observations: each behaviour input reads one component of the observation vector, by the
  index declared in ``environment.observations`` (default: the inputs in order read 0, 1, ...),
  or a feature computed from it (:class:`~flctool.behaviour.environment.ObservationFeature`: an
  angle from its cosine and sine, a difference, abs, scale and offset).
* Discrete actions: ``environment.actions`` maps every command to an action; the crisp output
  ``a`` (eq. 3) executes the action of the command whose singleton is nearest ``a``.
* Box actions: the singletons are action values and ``a`` itself is the action (clipped to
  the space's bounds).
* ``environment.action: vote``: the controller's output is the singleton of the command
  whose firing rules have the largest summed activation (see docs/learning.md), so a
  Discrete space executes exactly that command.

Episode ``b`` runs in its own Gymnasium environment, reset with ``seed=seeds[b]``, so batched
and one-at-a-time runs agree. gymnasium is an optional extra: ``pip install 'flctool[gym]'``.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.environment import GymnasiumConfig, ObservationFeature
from flctool.behaviour.gym_registry import (
    id_module_problem,
    import_gymnasium,
    missing_package,
    option_problems,
)
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.errors import EnvError, Problem, SpecError
from flctool.registry import did_you_mean

_GYM_SUGGESTION = re.compile(r"\s*Did you mean: `[^`]*`\?")


def _spec_error(path: tuple[str | int, ...], message: str, hint: str = "") -> SpecError:
    return SpecError([Problem(path, message, hint)])


class GymnasiumEnv(BatchEnv):
    """B episodes of one Gymnasium environment id (one environment object per episode)."""

    def __init__(self, config: GymnasiumConfig, input_names: tuple[str, ...],
                 commands: dict[str, float], batch_size: int = 1) -> None:
        self.gym = import_gymnasium()
        self.config = config
        self.observation_names = input_names
        self._commands = commands
        self.votes = config.action == "vote"
        self._envs: list[Any] = [self._make()]
        try:
            first = self._envs[0]
            self._features = self._observation_features(first.observation_space, input_names)
            self._discrete, self._action_of = self._action_mapping(first.action_space,
                                                                   commands)
            limit = getattr(first.spec, "max_episode_steps", None)
            max_steps = config.max_steps or limit
            if max_steps is None:
                raise _spec_error(("environment", "max_steps"),
                                  f"'{config.id}' has no time limit of its own",
                                  "set environment.max_steps")
            self.max_steps = int(max_steps)
            values = sorted(commands.values())
            self.action_bounds = (float(values[0]), float(values[-1]))
            self._grow(batch_size)
        except BaseException:  # nobody else holds the environments made so far
            self.close()
            raise
        self._reset_state(0)
        self._started = False

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, batch_size: int = 1) -> GymnasiumEnv:
        config = behaviour.environment
        if not isinstance(config, GymnasiumConfig):
            raise EnvError("the gymnasium adapter needs 'environment: {adapter: gymnasium}'")
        return cls(config, behaviour.input_names, dict(behaviour.output.commands), batch_size)

    # -- building ------------------------------------------------------------------------
    def _make(self) -> Any:
        gym, config = self.gym, self.config
        problem = id_module_problem(config.id)
        if problem is not None:
            raise SpecError([problem])
        problems = option_problems(gym, config.id, config.options)
        if problems:
            raise SpecError(problems)
        try:
            return gym.make(config.id, disable_env_checker=True, **config.options)
        except gym.error.DependencyNotInstalled as error:
            raise missing_package(config.id, error) from None
        except gym.error.Error as error:
            raise _spec_error(
                ("environment", "id"),
                f"Gymnasium cannot make '{config.id}': {self._unknown_id(str(error))}",
                "use a registered id (python -c 'import gymnasium; "
                "gymnasium.pprint_registry()'), and import the package that registers it") \
                from None
        except TypeError as error:
            raise _spec_error(("environment", "options"),
                              f"'{config.id}' does not accept these options: {error}") from None

    def _unknown_id(self, message: str) -> str:
        """Gymnasium's message with one suggestion: ours, of a whole registered id, in place
        of Gymnasium's guess at the name part (kept when we have none)."""
        suggestion = did_you_mean(self.config.id, [str(k) for k in self.gym.envs.registry])
        if suggestion:
            message = _GYM_SUGGESTION.sub("", message)
        message = message.rstrip()
        if not message.endswith((".", "?")):
            message += "."
        return message + suggestion

    def _observation_features(self, space: Any,
                              inputs: tuple[str, ...]) -> list[ObservationFeature]:
        box = self.gym.spaces.Box
        if not isinstance(space, box) or len(space.shape) != 1:
            raise _spec_error(("environment", "id"),
                              f"'{self.config.id}' observes {space}; the gymnasium adapter "
                              "needs a one-dimensional Box observation space",
                              "flatten the observation with a wrapper registered as a new id")
        size = int(space.shape[0])
        if not self.config.observations and len(inputs) > size:
            raise _spec_error(("inputs",), f"the behaviour has {len(inputs)} inputs but "
                              f"'{self.config.id}' observes only {size} components",
                              "map inputs to components with environment.observations")
        mapping = self.config.features(inputs)
        problems = [Problem(("environment", "observations", name),
                            f"'{name}' is not an input of this behaviour."
                            f"{did_you_mean(name, inputs)}", f"inputs: {', '.join(inputs)}")
                    for name in mapping if name not in inputs]
        problems += [Problem(("environment", "observations"),
                             f"input '{name}' reads no observation component",
                             f"add '{name}: <index 0..{size - 1}>'")
                     for name in inputs if name not in mapping]
        problems += [Problem(("environment", "observations", name),
                             f"index {index} is out of range: the observation space {space} "
                             f"has components 0..{size - 1}")
                     for name, feature in mapping.items() if name in inputs
                     for index in feature.indices if index >= size]
        if problems:
            raise SpecError(problems)
        return [mapping[name] for name in inputs]

    def _action_mapping(self, space: Any, commands: dict[str, float]) -> tuple[bool, Any]:
        spaces = self.gym.spaces
        actions = self.config.actions
        if isinstance(space, spaces.Discrete):
            first, count = int(space.start), int(space.n)
            problems = [Problem(("environment", "actions", name),
                                f"'{name}' is not a command of this behaviour."
                                f"{did_you_mean(name, list(commands))}")
                        for name in actions if name not in commands]
            problems += [Problem(("environment", "actions"), f"command '{name}' has no action",
                                 f"add '{name}: <action {first}..{first + count - 1}>'")
                         for name in commands if name not in actions]
            problems += [Problem(("environment", "actions", name),
                                 f"action {index} is not in the action space {space}")
                         for name, index in actions.items()
                         if name in commands and not first <= index < first + count]
            if problems:
                raise SpecError(problems)
            order = sorted(commands, key=lambda name: commands[name])
            values = np.array([commands[n] for n in order], dtype=np.float64)
            return True, (values, [actions[n] for n in order])
        if isinstance(space, spaces.Box) and int(np.prod(space.shape)) == 1:
            if actions:
                raise _spec_error(("environment", "actions"), f"'{self.config.id}' has a Box "
                                  "action space: the crisp output is the action itself",
                                  "remove environment.actions")
            low, high = float(space.low.reshape(-1)[0]), float(space.high.reshape(-1)[0])
            outside = [Problem(("output", "commands", name),
                               f"singleton {value:g} is outside the action space [{low:g}, "
                               f"{high:g}] of '{self.config.id}'")
                       for name, value in commands.items() if not low <= value <= high]
            if outside:
                raise SpecError(outside)
            return False, space
        raise _spec_error(("environment", "id"),
                          f"'{self.config.id}' acts in {space}; the gymnasium adapter needs a "
                          "Discrete or a one-component Box action space")

    def _grow(self, batch: int) -> None:
        while len(self._envs) < batch:
            self._envs.append(self._make())

    def _reset_state(self, batch: int) -> None:
        self.obs: FloatArray = np.zeros((batch, len(self.observation_names)))
        self.raw: list[NDArray[Any]] = []
        self.t: NDArray[np.int64] = np.zeros(batch, dtype=np.int64)
        self.terminated: BoolArray = np.zeros(batch, dtype=bool)
        self.truncated: BoolArray = np.zeros(batch, dtype=bool)

    # -- the protocol ----------------------------------------------------------------------
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Reset one environment per seed: (B,) -> observations (B, N), info {}."""
        seeds = np.asarray(seeds, dtype=np.int64).reshape(-1)
        batch = seeds.shape[0]
        if batch < 1:
            raise EnvError("reset needs at least one seed")
        if (seeds < 0).any():
            raise EnvError("Gymnasium seeds must be non-negative integers")
        self._grow(batch)
        self._reset_state(batch)
        for b, seed in enumerate(seeds.tolist()):
            raw, _ = self._envs[b].reset(seed=seed)
            self._observe(b, raw)
        self._started = True
        return self.obs.copy(), {}

    def _observe(self, b: int, raw: Any) -> None:
        array = np.asarray(raw, dtype=np.float64).reshape(-1)
        if b < len(self.raw):
            self.raw[b] = array
        else:
            self.raw.append(array)
        values = array.tolist()
        self.obs[b] = [feature.value(values) for feature in self._features]

    def _action(self, a: float) -> Any:
        if self._discrete:
            values, actions = self._action_of
            return actions[int(np.argmin(np.abs(values - a)))]
        space = self._action_of
        clipped = np.clip(np.full(space.shape, a), space.low, space.high)
        return clipped.astype(space.dtype)

    def step(self, actions: FloatArray) -> Step:
        """Apply crisp outputs ``actions (B,)``; finished episodes stay as they are."""
        actions = np.asarray(actions, dtype=np.float64).reshape(-1)
        batch = self.obs.shape[0]
        if not self._started:
            raise EnvError("step before reset", hint="call reset(seeds) first")
        if actions.shape[0] != batch:
            raise EnvError(f"step got {actions.shape[0]} actions for {batch} episodes")
        if np.isnan(actions).any():
            raise EnvError("an action is NaN", hint="check the controller's output")
        rewards = np.zeros(batch)
        for b in np.flatnonzero(~(self.terminated | self.truncated)).tolist():
            raw, reward, terminated, truncated, _ = self._envs[b].step(
                self._action(float(actions[b])))
            self._observe(b, raw)
            rewards[b] = float(reward)
            self.t[b] += 1
            self.terminated[b] = bool(terminated)
            self.truncated[b] = not terminated and (bool(truncated)
                                                    or self.t[b] >= self.max_steps)
        return Step(self.obs.copy(), rewards, self.terminated.copy(), self.truncated.copy())

    def success(self) -> BoolArray:
        """(B,) success as declared by ``environment.success``."""
        rule = self.config.success
        if rule == "terminated":
            return np.array(self.terminated)
        if rule == "truncated":
            return np.array(self.truncated)
        return np.zeros_like(self.terminated)

    def trace_state(self) -> dict[str, FloatArray]:
        """Every component of the raw observation, as ``obs_0``, ``obs_1``, ... each (B,)."""
        if not self.raw:
            return {}
        raw = np.array(self.raw)
        return {f"obs_{i}": raw[:, i] for i in range(raw.shape[1])}

    def close(self) -> None:
        for env in self._envs:
            env.close()
