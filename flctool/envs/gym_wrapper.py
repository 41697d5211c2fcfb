"""The pitch world (and its ballchase preset) as a ``gymnasium.Env``, registered by id, for
other reinforcement-learning libraries.

    import gymnasium as gym
    import flctool.envs.gym_wrapper                     # registers the ids below
    env = gym.make("flctool/Pitch-v0", behaviour="behaviours/dribble.yaml")
    env = gym.make("flctool/dribble-discrete-v0")       # a shipped behaviour, by name
    obs, info = env.reset(seed=0)

Ids: ``flctool/Pitch-v0`` (Box action: the crisp output ``a``, spanning the commands'
singletons) and ``flctool/PitchDiscrete-v0`` (Discrete action: command ``k`` in order of
increasing singleton runs, its singleton as ``a``) for any pitch or ballchase behaviour, given
as ``behaviour=`` (a path or a loaded :class:`Behaviour`); and ``flctool/NAME-v0``,
``flctool/NAME-discrete-v0`` for each shipped pitch behaviour in the checkout's
``behaviours/`` folder. Observations are the behaviour's inputs clipped to their ranges (as
the controller reads them), or mapped to [-1, 1] with ``normalise=True`` (the default of the
registered ids). ``reset(seed=s)`` is the simulator's episode ``s``. Needs the optional
gymnasium package (``pip install 'flctool[gym]'``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from flctool.behaviour.models import Behaviour
from flctool.envs.base import FloatArray
from flctool.envs.pitch import PitchSim
from flctool.errors import EnvError, MissingDependencyError

try:
    import gymnasium as gym
except ImportError:
    raise MissingDependencyError("gymnasium", "gym", "the Gymnasium wrapper") from None

#: The shipped behaviours of a checkout, beside the package (absent from an installed wheel).
SHIPPED = Path(__file__).resolve().parents[2] / "behaviours"


class PitchGymEnv(gym.Env[FloatArray, Any]):
    """One pitch-world episode at a time behind Gymnasium's ``Env`` API."""

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012 (Gymnasium's convention)

    def __init__(self, behaviour: Behaviour | str | Path, *, discrete: bool = False,
                 normalise: bool = False) -> None:
        super().__init__()
        if not isinstance(behaviour, Behaviour):
            from flctool.behaviour.load import load_behaviour

            behaviour = load_behaviour(behaviour)
        from flctool.envs import make_env

        sim = make_env(behaviour)
        if not isinstance(sim, PitchSim):
            raise EnvError(f"behaviour '{behaviour.name}' is not a pitch-world or ballchase "
                           "behaviour", hint="use environment.adapter pitch or ballchase-sim")
        self.sim = sim
        self.normalise = normalise
        self._low = np.array([v.range[0] for v in behaviour.inputs.values()], dtype=np.float64)
        self._high = np.array([v.range[1] for v in behaviour.inputs.values()], dtype=np.float64)
        if normalise:
            ones = np.ones_like(self._low)
            self.observation_space = gym.spaces.Box(-ones, ones, dtype=np.float64)
        else:
            self.observation_space = gym.spaces.Box(self._low, self._high, dtype=np.float64)
        self._singletons = sim.drive.values
        if discrete:
            self.action_space: gym.spaces.Space[Any] = gym.spaces.Discrete(
                len(self._singletons))
        else:
            a_low, a_high = sim.action_bounds
            self.action_space = gym.spaces.Box(a_low, a_high, shape=(1,), dtype=np.float32)
        self.discrete = discrete

    def _observation(self, readings: FloatArray) -> FloatArray:
        clipped = np.clip(readings, self._low, self._high)
        if not self.normalise:
            return clipped
        return np.clip(2.0 * (clipped - self._low) / (self._high - self._low) - 1.0, -1.0, 1.0)

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[FloatArray, dict[str, Any]]:
        super().reset(seed=seed)
        # An explicit seed is the simulator's episode seed, so seed s here is episode s there.
        episode = seed if seed is not None else int(self.np_random.integers(2**62))
        return self._observation(self.sim.reset_one(episode)), {}

    def step(self, action: Any) -> tuple[FloatArray, float, bool, bool, dict[str, Any]]:
        if self.discrete:
            a = float(self._singletons[int(np.asarray(action).reshape(-1)[0])])
        else:
            a = float(np.asarray(action, dtype=np.float64).reshape(-1)[0])
        obs, reward, terminated, truncated = self.sim.step_one(a)
        info = {"success": bool(self.sim.success()[0])} if terminated or truncated else {}
        return self._observation(obs), float(reward), terminated, truncated, info


class BallchaseGymEnv(PitchGymEnv):
    """The ballchase simulator behind Gymnasium's API (Box action, raw observations)."""

    def __init__(self, behaviour: Behaviour) -> None:
        super().__init__(behaviour)


def shipped_pitch_behaviours() -> dict[str, Path]:
    """Name -> file of each learnable pitch behaviour shipped in the checkout."""
    if not SHIPPED.is_dir():
        return {}
    found = {}
    for path in sorted(SHIPPED.glob("*.yaml")):
        if path.stem.endswith("-handmade"):
            continue
        text = path.read_text(encoding="utf-8")
        if "adapter: pitch" in text:
            found[path.stem] = path
    return found


def register_envs() -> None:
    """Register the ids (idempotent)."""
    entry = f"{__name__}:PitchGymEnv"
    registry = gym.envs.registration.registry
    ids: dict[str, dict[str, Any]] = {"flctool/Pitch-v0": {"normalise": True},
                                      "flctool/PitchDiscrete-v0": {"normalise": True,
                                                                   "discrete": True}}
    for name, path in shipped_pitch_behaviours().items():
        ids[f"flctool/{name}-v0"] = {"behaviour": str(path), "normalise": True}
        ids[f"flctool/{name}-discrete-v0"] = {"behaviour": str(path), "normalise": True,
                                              "discrete": True}
    for env_id, kwargs in ids.items():
        if env_id not in registry:
            gym.register(id=env_id, entry_point=entry, kwargs=kwargs)


register_envs()

__all__ = ["BallchaseGymEnv", "PitchGymEnv", "register_envs", "shipped_pitch_behaviours"]
