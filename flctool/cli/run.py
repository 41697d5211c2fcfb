"""``flctool run CONTROLLER --ros2``: deploy a controller as a ROS 2 node (docs/ros2.md).

The node logs on stderr: when it starts driving, every watchdog stop and recovery, each
episode's end (with a status topic), and the stop it publishes before it leaves.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from flctool.cli.app import app, example, load_controller, report_interrupted, user_errors
from flctool.errors import FlcError

if TYPE_CHECKING:
    from flctool.behaviour import Behaviour


def _log(text: str) -> None:
    print(f"flctool run: {text}", file=sys.stderr, flush=True)


@app.command(epilog=example(
    "flctool run runs/robot --ros2",
    "flctool run runs/sim/best.yaml --ros2 --robot behaviours/ballchase-ros2.yaml",
    "flctool run behaviours/ballchase-handmade.yaml --ros2 --robot "
    "behaviours/ballchase-ros2.yaml --episodes 20",
    "flctool run bundle/ --ros2"))
def run(
    file: Annotated[Path, typer.Argument(
        metavar="CONTROLLER", help="A behaviour file (YAML), a run directory (its best.yaml) "
        "or an export bundle (its controller.yaml).")],
    ros2: Annotated[bool, typer.Option("--ros2", help="Run as a ROS 2 node, with the topics "
                                       "of the environment: {adapter: ros2} section.")]
    = False,
    robot: Annotated[Path | None, typer.Option(help="A behaviour file whose environment: "
                                               "section (adapter: ros2) says the topics, when "
                                               "the controller's own is a simulator's.")]
    = None,
    episodes: Annotated[int | None, typer.Option(min=1, help="Stop after this many episodes "
                                                 "have ended (needs an episode status "
                                                 "topic).")] = None,
    duration: Annotated[float | None, typer.Option(min=0.001, help="Stop after this many "
                                                   "seconds.")] = None,
    rate: Annotated[float | None, typer.Option(min=0.001, max=1000, help="Control rate in Hz "
                                               "(default: the environment's rate).")] = None,
) -> None:
    """Deploy a controller on a robot: publish its command at the control rate from the
    latest inputs, with a watchdog that publishes stop at once on a stale, NaN or
    out-of-range input or a lost publisher, and again on Ctrl-C."""
    with user_errors():
        # an export bundle (flctool export --format bundle) deploys its controller.yaml
        bundled = file / "controller.yaml"
        if file.is_dir() and bundled.is_file() and (file / "wiring.json").is_file():
            file = bundled
        behaviour, source = load_controller(file)
        if getattr(behaviour.environment, "compose", None):
            raise FlcError(f"{behaviour.name} is a composed behaviour: flctool run deploys "
                           "one controller", hint="deploy the composition with its bundle's "
                           "flc_composed_step (flctool export --format bundle, "
                           "docs/formats/bundle.md)")
        if not ros2:
            raise FlcError("flctool run deploys over ROS 2 only: add --ros2",
                           hint="for the robot link or a simulator, use flctool evaluate")
        _run_ros2(behaviour, source, robot, episodes, duration, rate)


def _run_ros2(behaviour: Behaviour, source: Path, robot: Path | None, episodes: int | None,
              duration: float | None, rate: float | None) -> None:
    from flctool.compile import compile_behaviour
    from flctool.ros2.section import ros2_section

    config, where = ros2_section(behaviour, str(source), robot)
    if rate is not None:
        config = config.model_copy(update={"rate": rate})
    if episodes is not None and config.episode.status is None:
        raise FlcError("--episodes needs an episode status topic to count episodes",
                       hint=f"add environment.episode.status to {where}, or use --duration")
    import numpy as np

    from flctool.ros2.deploy import ControllerNode

    flc = compile_behaviour(behaviour)
    # Load (or compile) the kernels now: the first tick must not stall the node for seconds.
    flc.output_one(np.array([sum(spec.range) / 2 for spec in behaviour.inputs.values()]))

    def act(values: list[float]) -> float:
        return flc.output_one(np.array(values, dtype=np.float64))

    node = ControllerNode(config, behaviour.input_names, dict(behaviour.output.commands), act,
                          _log)
    try:
        _log(f"{behaviour.name} at {config.rate:g} Hz: {', '.join(s.topic for s in node.sources)}"
             f" -> {config.command.topic}")
        try:
            node.run(episodes, duration)
        except KeyboardInterrupt:
            report_interrupted(f"{behaviour.name} stopped (the stop command was published)")
            raise
        if node.status is not None:
            outcomes = ", ".join(f"{k} {v}" for k, v in node.outcomes.items())
            typer.echo(f"{node.episodes} episodes ended: {outcomes}")
            if node.episodes:
                typer.echo(f"success rate {node.outcomes['success'] / node.episodes:.3f}")
        typer.echo(f"{node.commands_sent} commands published, watchdog stops "
                   f"{node.deployment.stops}")
    finally:
        node.close()
