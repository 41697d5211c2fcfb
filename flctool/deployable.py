"""What a deployment runs: observations in, one crisp value out, for one behaviour or a
composition.

A single behaviour deploys its controller: it reads its inputs and its crisp output (eq. 3)
is interpreted by the robot through the behaviour's commands. A **composition** deploys the
whole tree on the controller's side, so the robot only ever walks: each step the arbiter
chooses a part (the command nearest its output, or the vote), the part's controller reads its
own channels and its output is the value sent, in the parts' common command table (a part
whose ``environment.action`` is ``nearest`` sends its nearest command's singleton, which the
robot's blend executes exactly). The robot side of a composition is its world with those
walking commands and every channel the tree reads
(:func:`flctool.envs.robot_server.composition_world`): what ``flctool serve`` serves for a
composed file. The choices are made by the same compiled controllers and
the same rules as the pitch world's composition (:mod:`flctool.envs.pitch_compose`), so a
deployment commands step for step what evaluation commands.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flctool.errors import FlcError

if TYPE_CHECKING:
    from flctool.behaviour.models import Behaviour
    from flctool.envs.base import BatchEnv


@dataclass(frozen=True)
class Deployable:
    """A controller ready to drive a robot: ``act(observations) -> crisp value``."""

    name: str
    observations: tuple[str, ...]  # what it reads, in the order ``act`` takes them
    commands: dict[str, float]  # the robot's commands, by which it interprets the value
    act: Callable[[Sequence[float]], float]
    composed: bool = False


def is_composed(behaviour: Behaviour) -> bool:
    return bool(getattr(behaviour.environment, "compose", None))


def deployable(behaviour: Behaviour) -> Deployable:
    """The deployment of a deployable behaviour (every rule has a consequent)."""
    if is_composed(behaviour):
        return _composition(behaviour)
    from flctool.compile import compile_behaviour

    flc = compile_behaviour(behaviour)
    votes = behaviour.acts_by_vote
    return Deployable(behaviour.name, behaviour.input_names, dict(behaviour.output.commands),
                      _controller_act(flc, votes))


def _controller_act(flc: object, votes: bool) -> Callable[[Sequence[float]], float]:
    from flctool.compile import Controller
    from flctool.rollout import vote_output

    assert isinstance(flc, Controller)
    # Load (or compile) the kernels now: the first step must not stall the robot for seconds.
    flc.output_one(np.array([sum(r) / 2 for r in flc.ranges.tolist()]))

    def act(values: Sequence[float]) -> float:
        state = np.array(values, dtype=np.float64)
        if votes:  # the rollout's vote, on one state
            return float(vote_output(flc, state[None, :])[0])
        return flc.output_one(state)

    return act


def _composition(behaviour: Behaviour) -> Deployable:
    from flctool.envs.pitch_compose import common_commands, composition_parts

    config, channels, drive, read = composition_parts(behaviour)
    commands = common_commands(drive)
    names = tuple(dict.fromkeys(read))  # a channel read twice is observed once
    arbiter_columns = [names.index(c) for c in channels]
    part_columns = [[names.index(read[i]) for i in part.indices] for part in drive.parts]
    from flctool.compile import compile_behaviour

    arbiter = _controller_act(compile_behaviour(behaviour), config.action == "vote")
    for part in drive.parts:  # warm every part's kernels too
        part.controller.output_one(np.array([sum(r) / 2 for r in
                                             part.controller.ranges.tolist()]))

    def act(values: Sequence[float]) -> float:
        k = drive.chosen(arbiter([values[i] for i in arbiter_columns]))
        part = drive.parts[k]
        state = np.array([values[i] for i in part_columns[k]], dtype=np.float64)
        value = part.controller.output_one(state)
        if part.drive.nearest:  # CommandDrive's nearest, as the composition walks it
            singletons = part.drive.values_list
            a = min(max(value, singletons[0]), singletons[-1])
            value = singletons[min(range(len(singletons)), key=lambda i: abs(a - singletons[i]))]
        return value

    return Deployable(behaviour.name, names, commands, act, composed=True)


@dataclass(frozen=True)
class Episode:
    seed: int
    steps: int
    total_reward: float
    success: bool


def run_episodes(deployment: Deployable, env: BatchEnv, seeds: Sequence[int],
                 on_step: Callable[[float], None] | None = None) -> list[Episode]:
    """Drive ``env`` (a robot over the link, or its simulator) one episode per seed, one at a
    time as a robot runs: each step ``act`` on the latest observations (columns in
    ``deployment.observations`` order), the value sent as the step's action (and passed to
    ``on_step``)."""
    episodes = []
    for seed in seeds:
        obs = env.reset_one(int(seed))
        total, steps = 0.0, 0
        for _ in range(env.max_steps):
            value = deployment.act(obs.tolist())
            if on_step is not None:
                on_step(value)
            obs, reward, terminated, truncated = env.step_one(value)
            total += reward
            steps += 1
            if terminated or truncated:
                break
        else:
            raise FlcError(f"episode {seed} still running after max_steps = {env.max_steps}",
                           hint="the robot side must end every episode by its max_steps")
        episodes.append(Episode(int(seed), steps, total, bool(env.success()[0])))
    return episodes
