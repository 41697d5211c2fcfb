"""A composed behaviour in the pitch world: the arbiter's output chooses a part, the part's
controller chooses the walk.

Each step, the command whose singleton is nearest the arbiter's crisp output names the part
that runs (with ``action: vote`` the arbiter's output already is the strongest command's
singleton); that part's controller reads its own inputs from the same world (their readings
before the step, with the world's noise) and its crisp output drives the robot through the
part's commands, blended or nearest as the part's ``environment.action`` says, each command
walking by the composing world's motion table. The parts are fixed: learning a composition
learns the arbiter's consequents, i.e. which part runs when.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flctool.behaviour.environment import PitchConfig
from flctool.behaviour.models import Behaviour
from flctool.compile import Controller, compile_behaviour
from flctool.envs.base import FloatArray
from flctool.envs.pitch_drive import CommandDrive, Drive
from flctool.errors import Problem, SpecError


@dataclass(frozen=True)
class Part:
    name: str
    controller: Controller
    indices: tuple[int, ...]  # where each of its inputs' channels is among the readings
    drive: CommandDrive


class ComposedDrive:
    """Arbiter output -> part -> the part's controller -> the part's walk."""

    reads = True

    def __init__(self, commands: dict[str, float], parts: dict[str, Part]) -> None:
        self.order = tuple(sorted(commands, key=lambda name: commands[name]))
        self.values = np.array([commands[n] for n in self.order], dtype=np.float64)
        self.values_list: list[float] = self.values.tolist()
        self.parts = [parts[name] for name in self.order]

    def chosen(self, action: float) -> int:
        """Index (in singleton order) of the part the arbiter's output names."""
        values = self.values_list
        return min(range(len(values)), key=lambda i: abs(action - values[i]))

    def one(self, action: float, readings: Sequence[float] = (),
            ) -> tuple[list[float], list[float]]:
        part = self.parts[self.chosen(float(action))]
        state = np.array([readings[i] for i in part.indices], dtype=np.float64)
        return part.drive.one(part.controller.output_one(state))

    def batch(self, actions: FloatArray, readings: Sequence[FloatArray] = (),
              ) -> tuple[list[FloatArray], list[FloatArray]]:
        values = self.values
        chosen = np.argmin(np.abs(actions[:, None] - values[None, :]), axis=1)
        batch = actions.shape[0]
        mean = [np.zeros(batch) for _ in range(3)]
        std = [np.zeros(batch) for _ in range(3)]
        for k, part in enumerate(self.parts):
            rows = chosen == k
            if not rows.any():
                continue
            states = np.stack([readings[i][rows] for i in part.indices], axis=1)
            part_mean, part_std = part.drive.batch(part.controller.output(states))
            for column, value in zip(mean + std, part_mean + part_std, strict=True):
                column[rows] = value
        return mean, std


def composed_drive(behaviour: Behaviour, config: PitchConfig, channels: tuple[str, ...],
                   ) -> tuple[Drive, tuple[str, ...]]:
    """The drive of a composition, and the channels its parts read beyond the arbiter's."""
    from flctool.behaviour.load import behaviour_from_data

    problems: list[Problem] = []
    read = list(channels)
    parts = {}
    for name, data in config.compose.items():
        where = ("environment", "compose", name)
        if not isinstance(data, dict):
            problems.append(Problem(where, f"the part '{data}' was not loaded",
                                    "load the behaviour from its file"))
            continue
        part = behaviour_from_data(data)
        part_env = part.environment
        if not isinstance(part_env, PitchConfig):
            problems.append(Problem(where, "a part must be a pitch-world behaviour",
                                    "give it 'environment: {adapter: pitch}'"))
            continue
        if not part.is_deployable:
            problems.append(Problem(where, f"the part '{part.name}' has rules without "
                                    "consequents", "compose learned or hand-made behaviours: "
                                    "learn the part first and name its best.yaml"))
            continue
        if part_env.action == "vote":
            problems.append(Problem(where, "a part with action: vote cannot be composed",
                                    "set the part's environment.action to crisp or nearest"))
            continue
        indices = []
        for input_name in part.input_names:
            channel = part_env.channel_of(input_name)
            if channel not in read:
                read.append(channel)
            indices.append(read.index(channel))
        parts[name] = Part(name, compile_behaviour(part), tuple(indices),
                           CommandDrive(dict(part.output.commands), config.motion, config.noise,
                                  part_env.action == "nearest"))
    if problems:
        raise SpecError(problems)
    drive = ComposedDrive(dict(behaviour.output.commands), parts)
    return drive, tuple(read[len(channels):])


def composition_parts(behaviour: Behaviour) -> tuple[PitchConfig, tuple[str, ...],
                                                     ComposedDrive, tuple[str, ...]]:
    """The composition's config, the arbiter's channels, its drive and every channel read."""
    config = behaviour.environment
    assert isinstance(config, PitchConfig)
    channels = tuple(config.channel_of(name) for name in behaviour.input_names)
    drive, extra = composed_drive(behaviour, config, channels)
    assert isinstance(drive, ComposedDrive)
    return config, channels, drive, (*channels, *extra)


def common_commands(drive: ComposedDrive) -> dict[str, float]:
    """The parts' common command table: what the robot of a composition executes (a
    :class:`SpecError` if the parts' tables differ)."""
    tables = {part.name: dict(zip(part.drive.order, part.drive.values_list, strict=True))
              for part in drive.parts}
    first_name, first = next(iter(tables.items()))
    problems = [Problem(("environment", "compose", name),
                        f"the part's commands {table} differ from part '{first_name}''s "
                        f"{first}", "deploying a composition needs parts with one command "
                        "table (the robot executes it): give every part the same commands "
                        "and singletons")
                for name, table in tables.items() if table != first]
    if problems:
        raise SpecError(problems)
    return first
