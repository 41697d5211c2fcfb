"""``new``: scaffold a behaviour file from inputs, commands and an environment."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from flctool.cli.app import Force, app, console, example, say, user_errors, write_output


@app.command(epilog=example(
    "flctool new chase --input ball_size:0:1:3 --input pan:-90:90:5 "
    "--command turn_right:-1 --command forward_right:-0.5 --command forward:0 "
    "--command forward_left:0.5 --command turn_left:1 --env pitch -o chase.yaml"))
def new(
    name: Annotated[str, typer.Argument(help="The behaviour's name (letters, digits, _).")],
    inputs: Annotated[list[str], typer.Option(
        "--input", "-i", help="NAME:LO:HI:SETS, SETS a count (1-9) or names low to high, "
        "e.g. pan:-90:90:5 or ball_size:0:1:small,medium,large. Repeat per input.")],
    commands: Annotated[list[str], typer.Option(
        "--command", "-c", help="NAME:VALUE, a command and its singleton, e.g. turn_left:1. "
        "Repeat per command (at least two).")],
    env: Annotated[str | None, typer.Option(
        "--env", help="Environment adapter: ballchase-sim, pitch or gymnasium:ID "
        "(e.g. gymnasium:CartPole-v1); none: add it later.")] = None,
    sensors: Annotated[list[str] | None, typer.Option(
        "--sensor", help="INPUT:CHANNEL, the pitch-world channel an input reads when it is "
        "not named after it, e.g. target:goal_bearing.")] = None,
    output: Annotated[str, typer.Option(help="Name of the output variable.")] = "action",
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="Write the file here (default: print it).")] = None,
    force: Force = False,
) -> None:
    """Scaffold a valid behaviour file: evenly spaced, overlapping sets over each input's
    range (shoulders at the ends), the commands, and rules left to learn."""
    from flctool.behaviour.scaffold import (
        parse_command,
        parse_input,
        parse_sensor,
        scaffold_behaviour,
    )

    with user_errors():
        sensor_map = dict(parse_sensor(s) for s in sensors or [])
        text = scaffold_behaviour(name, [parse_input(s) for s in inputs],
                                  [parse_command(c) for c in commands], output=output,
                                  adapter=env, sensors=sensor_map)
        if out is None:
            console.print(text, end="", markup=False, highlight=False)
            return
        write_output(out, text, "behaviour file", force=force)
    say(f"{out}; next: flctool validate {out}", "wrote")
