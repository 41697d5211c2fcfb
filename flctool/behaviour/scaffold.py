"""Scaffolding a new behaviour file from a few declarations (``flctool new``).

    text = scaffold_behaviour("chase", [parse_input("pan:-90:90:5")],
                              [parse_command("left:-1"), parse_command("right:1")])

Each input's range is covered by evenly spaced, overlapping trapezoids: the range is cut into
``2 n - 1`` equal segments; set ``i`` is 1 on segment ``2 i`` and slopes over the segments on
either side, so neighbours cross at membership 0.5 and the first and last sets are shoulders
(membership 1 up to the range's ends). The text returned is a valid behaviour file (it is
checked before it is returned); the rules are left to learn.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from flctool.behaviour.environment import DEFAULT_MOTION
from flctool.behaviour.gym_registry import discrete_actions
from flctool.behaviour.load import parse_behaviour
from flctool.errors import FlcError, MissingDependencyError, SpecError, format_path

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: Set names for a count of sets, from the low end of the range to the high end.
SET_NAMES = {
    1: ("all",), 2: ("low", "high"), 3: ("low", "medium", "high"),
    4: ("very_low", "low", "high", "very_high"),
    5: ("very_low", "low", "medium", "high", "very_high"),
}
MAX_SETS = 9
ADAPTERS = ("ballchase-sim", "pitch", "gymnasium:ID")


@dataclass(frozen=True)
class InputDeclaration:
    """An input of the new behaviour: its range and the names of its sets, low to high."""

    name: str
    low: float
    high: float
    sets: tuple[str, ...]


def _name(text: str, what: str, spec: str) -> str:
    if not _NAME.match(text) or len(text) > 64:
        raise FlcError(f"{what} '{text}' in '{spec}' is not a valid name",
                       hint="use letters, digits and _, starting with a letter or _")
    return text


def _number(text: str, what: str, spec: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise FlcError(f"{what} '{text}' in '{spec}' is not a number",
                       hint="write it like -90, 0.5 or 1e3") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise FlcError(f"{what} '{text}' in '{spec}' must be a finite number")
    return value


def parse_input(spec: str) -> InputDeclaration:
    """``NAME:LO:HI:SETS`` with SETS a count (1-9) or comma-separated set names, low to high:
    ``pan:-90:90:5``, ``ball_size:0:1:small,medium,large``."""
    parts = spec.split(":")
    if len(parts) != 4:
        raise FlcError(f"--input '{spec}' must be NAME:LO:HI:SETS",
                       hint="e.g. --input pan:-90:90:5 or --input ball_size:0:1:small,medium,large")
    name = _name(parts[0], "input name", spec)
    low, high = (_number(parts[1], "LO", spec), _number(parts[2], "HI", spec))
    if not low < high:
        raise FlcError(f"--input '{spec}': LO {low:g} must be below HI {high:g}",
                       hint=f"e.g. {name}:{high:g}:{low:g}:{parts[3]}" if low > high else
                       f"widen the range, e.g. {name}:{low:g}:{low + 1:g}:{parts[3]}")
    sets_text = parts[3]
    if sets_text.isdigit():
        count = int(sets_text)
        if not 1 <= count <= MAX_SETS:
            raise FlcError(f"--input '{spec}': {count} sets; give 1 to {MAX_SETS}",
                           hint="each set multiplies the number of rules to learn")
        sets = SET_NAMES.get(count) or tuple(f"s{i + 1}" for i in range(count))
    else:
        sets = tuple(_name(s, "set name", spec) for s in sets_text.split(","))
        if len(set(sets)) != len(sets):
            raise FlcError(f"--input '{spec}': a set name is given twice")
        if len(sets) > MAX_SETS:
            raise FlcError(f"--input '{spec}': {len(sets)} sets; give at most {MAX_SETS}")
    return InputDeclaration(name, low, high, sets)


def parse_command(spec: str) -> tuple[str, float]:
    """``NAME:VALUE``: a command and its singleton, e.g. ``turn_left:1``."""
    name, sep, value = spec.partition(":")
    if not sep:
        raise FlcError(f"--command '{spec}' must be NAME:VALUE", hint="e.g. --command turn_left:1")
    return _name(name, "command name", spec), _number(value, "VALUE", spec)


def parse_sensor(spec: str) -> tuple[str, str]:
    """``INPUT:CHANNEL``: which pitch-world channel an input reads, e.g. ``where:goal_bearing``."""
    name, sep, channel = spec.partition(":")
    if not sep:
        raise FlcError(f"--sensor '{spec}' must be INPUT:CHANNEL",
                       hint="e.g. --sensor target:goal_bearing")
    return _name(name, "input name", spec), _name(channel, "channel", spec)


def even_partition(low: float, high: float, count: int) -> list[tuple[float, ...]]:
    """``count`` overlapping trapezoids over [low, high], shoulders at the ends; see the
    module docstring. Points are rounded to 10 significant digits (shared by neighbours, so
    the coverage stays exact)."""
    if count == 1:
        return [(low, low, high, high)]
    segments = 2 * count - 1
    points = [float(f"{low + k * (high - low) / segments:.10g}") for k in range(segments)]
    points.append(high)
    sets: list[tuple[float, ...]] = []
    for i in range(count):
        left = points[max(2 * i - 1, 0)]
        right = points[min(2 * i + 2, segments)]
        sets.append((left, points[2 * i], points[2 * i + 1], right))
    return sets


def _gymnasium_actions(env_id: str) -> int | None:
    """How many discrete actions ``env_id`` has, None for a Box action space, 0 when that
    cannot be told here: gymnasium is not installed, or the id would import a module (a new
    file never runs code) -- validation checks the file against the environment then."""
    if ":" in env_id:
        return 0
    try:
        return discrete_actions(env_id)
    except MissingDependencyError:
        return 0
    except SpecError as error:
        problem = error.problems[0]
        hint = problem.hint or "check the id: flctool new --env gymnasium:ID"
        raise FlcError(problem.message, hint=hint) from None


def _pitch_things_read(channels: list[str]) -> list[str]:
    """An obstacle or an opponent for inputs that read one (the pitch world has none unless
    the file places them), so that the new file validates and says where to edit."""
    lines = []
    if any(c.startswith("obstacle_") for c in channels):
        lines += ["  # a standing robot in the middle of the pitch: place the obstacles the "
                  "task needs", "  obstacles:", "    - {x: [-200, 200], y: [-200, 200]}"]
    if any(c.startswith("opponent_") for c in channels):
        lines += ["  # a player that walks at the ball: place the opponents the task needs "
                  "(behaviour: stand, track or chase)", "  opponents:",
                  "    - {x: [500, 1000], y: [-500, 500], behaviour: chase, speed: 30}"]
    return lines


def _number_text(value: float) -> str:
    return repr(float(value))


def _environment_text(adapter: str | None, inputs: list[InputDeclaration],
                      commands: list[tuple[str, float]], sensors: dict[str, str]) -> str:
    if adapter is None:
        if sensors:
            raise FlcError("--sensor maps inputs to pitch-world channels",
                           hint="add --env pitch")
        return ""
    if sensors and adapter != "pitch":
        raise FlcError(f"--sensor is for the pitch world, not '{adapter}'",
                       hint="use --env pitch, or name the inputs after the adapter's observations")
    if adapter in ("ballchase-sim", "pitch"):
        unknown = [name for name, _ in commands if name not in DEFAULT_MOTION]
        if unknown:
            raise FlcError(
                f"the {adapter} adapter has no default motion for command "
                f"{', '.join(repr(n) for n in unknown)}",
                hint="scaffold with the walking commands (" + ", ".join(DEFAULT_MOTION)
                + "), then add others to environment.motion and environment.noise")
        lines = ["environment:", f"  adapter: {adapter}"]
        if sensors:
            lines.append("  sensors:")
            lines += [f"    {name}: {channel}" for name, channel in sensors.items()]
        if adapter == "pitch":
            lines += _pitch_things_read([sensors.get(i.name, i.name) for i in inputs])
        return "\n".join(lines) + "\n"
    kind, _, env_id = adapter.partition(":")
    if kind == "gymnasium" and env_id:
        lines = ["environment:", "  adapter: gymnasium", f"  id: {env_id}",
                 "  # the observation component each input reads",
                 "  observations:"]
        lines += [f"    {spec.name}: {i}" for i, spec in enumerate(inputs)]
        actions = _gymnasium_actions(env_id)
        if actions is None:
            lines += ["  # a Box action space: the crisp output is the action, so the commands'",
                      "  # values are actions"]
            return "\n".join(lines) + "\n"
        if actions and len(commands) > actions:
            raise FlcError(f"'{env_id}' has {actions} actions, fewer than the {len(commands)} "
                           "commands", hint=f"declare at most {actions} commands, one per action")
        lines += ["  # the action index of each command" + (
            "" if actions else " (a Box action space: delete this mapping, the crisp output "
            "is the action)"), "  actions:"]
        lines += [f"    {name}: {i}" for i, (name, _) in enumerate(commands)]
        return "\n".join(lines) + "\n"
    raise FlcError(f"unknown environment '{adapter}'",
                   hint="use one of: " + ", ".join(ADAPTERS))


def scaffold_behaviour(name: str, inputs: list[InputDeclaration],
                       commands: list[tuple[str, float]], *, output: str = "action",
                       adapter: str | None = None, sensors: dict[str, str] | None = None,
                       description: str = "") -> str:
    """The text of a new, valid behaviour file; raises :class:`FlcError` on a bad declaration,
    including one that would not validate (e.g. an input the adapter cannot observe)."""
    _name(name, "behaviour name", name)
    _name(output, "output name", output)
    if not inputs:
        raise FlcError("a behaviour needs at least one input", hint="add --input NAME:LO:HI:SETS")
    if len(commands) < 2:
        raise FlcError("a behaviour needs at least two commands to choose between",
                       hint="add --command NAME:VALUE for each")
    for what, names in (("input", [i.name for i in inputs]), ("command", [c for c, _ in commands])):
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise FlcError(f"{what} '{twice[0]}' is declared twice")
    sensors = sensors or {}
    stray = [s for s in sensors if s not in {i.name for i in inputs}]
    if stray:
        raise FlcError(f"--sensor names '{stray[0]}', which is not an --input")
    lines = [
        f"# {name}: scaffolded by `flctool new`. Adjust the sets to what the robot needs to",
        "# tell apart, then `flctool validate` and `flctool learn` this file.",
        "flctool: 1",
        f"name: {name}",
        f"description: {description or name.replace('_', ' ').capitalize()}",
        "inputs:",
    ]
    for spec in inputs:
        lines += [f"  {spec.name}:",
                  f"    range: [{_number_text(spec.low)}, {_number_text(spec.high)}]",
                  "    sets:"]
        width = max(len(s) for s in spec.sets)
        for set_name, quad in zip(spec.sets, even_partition(spec.low, spec.high, len(spec.sets)),
                                  strict=True):
            points = ", ".join(_number_text(p) for p in quad)
            lines.append(f"      {set_name + ':':<{width + 1}} [{points}]")
    lines += ["output:", f"  name: {output}", "  commands:"]
    lines += [f"    {command}: {_number_text(value)}" for command, value in commands]
    rule_count = 1
    for spec in inputs:
        rule_count *= len(spec.sets)
    lines += [f"# {rule_count} rules, one per combination of sets: learned by `flctool learn`",
              "rules: []", "learning:", "  learner: hybrid", "  seed: 0"]
    text = "\n".join(lines) + "\n" + _environment_text(adapter, inputs, commands, sensors)
    try:  # never hand out a file that is invalid
        parse_behaviour(text, "<scaffold>")
    except SpecError as error:
        raise FlcError("the behaviour would not validate: " + "; ".join(
            f"{format_path(p.path)}: {p.message}" + (f" (fix: {p.hint})" if p.hint else "")
            for p in error.problems)) from None
    return text
