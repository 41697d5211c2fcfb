"""``flctool serve`` in its own process, and ``flctool evaluate`` / ``learn`` over the link to
it giving exactly what they give on the simulator directly."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

import pytest
from typer.testing import CliRunner

from flctool import load_behaviour
from flctool.behaviour import behaviour_from_data, behaviour_to_data, behaviour_to_yaml
from flctool.cli import app

from ..conftest import BEHAVIOURS, ROOT, restore_sigint

runner = CliRunner()
HANDMADE = BEHAVIOURS / "ballchase-handmade.yaml"


def spawn_server(file: Path, *options: str) -> tuple[subprocess.Popen[str], int]:
    """``flctool serve FILE --port 0`` in a subprocess; returns it and the port it printed."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(
        [sys.executable, "-m", "flctool", "serve", str(file), "--port", "0", *options],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
        preexec_fn=restore_sigint)
    assert process.stdout is not None
    line = process.stdout.readline()
    assert line.startswith("listening on 127.0.0.1:"), _failure(process, line)
    return process, int(line.rsplit(":", 1)[1])


def _failure(process: subprocess.Popen[str], line: str) -> str:
    process.kill()
    stderr: IO[str] | None = process.stderr
    return f"server printed {line!r}; stderr: {stderr.read() if stderr else ''}"


def link_file(tmp_path: Path, source: Path, port: int) -> Path:
    """A copy of ``source`` whose environment is a robot link to 127.0.0.1:port."""
    data = behaviour_to_data(load_behaviour(source))
    data["environment"] = {"adapter": "robot-link", "port": port, "connect_timeout": 5,
                           "reset_timeout": 5, "step_timeout": 5, "retries": 0}
    path = tmp_path / f"{source.stem}-link.yaml"
    path.write_text(behaviour_to_yaml(behaviour_from_data(data)), encoding="utf-8")
    return path


@contextmanager
def server_process(file: Path, *options: str) -> Iterator[tuple[subprocess.Popen[str], int]]:
    """:func:`spawn_server`, killed at the end if it is still running (a failed assert
    included), its pipes closed."""
    process, port = spawn_server(file, *options)
    try:
        yield process, port
    finally:
        if process.poll() is None:
            process.kill()
        process.wait(timeout=5)
        for pipe in (process.stdout, process.stderr):
            if pipe is not None:
                pipe.close()


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[subprocess.Popen[str], int]]:
    with server_process(HANDMADE, "--idle-timeout", "10") as started:
        yield started


def evaluate_json(file: Path, *options: str) -> dict[str, object]:
    result = runner.invoke(app, ["evaluate", str(file), "--episodes", "30", "--seed", "2",
                                 "--json", *options])
    assert result.exit_code == 0, result.output
    summary: dict[str, object] = json.loads(result.stdout)
    summary.pop("file")
    return summary


def test_evaluate_over_the_link_equals_the_simulator(tmp_path: Path) -> None:
    with server_process(HANDMADE, "--once", "--idle-timeout", "10") as (process, port):
        remote = evaluate_json(link_file(tmp_path, HANDMADE, port))
        assert process.wait(timeout=60) == 0  # --once: it exits when evaluate disconnects
        assert process.stderr is not None
        log = process.stderr.read()
    assert remote == evaluate_json(HANDMADE)
    assert "client 127.0.0.1:" in log and "safe stop: the client sent stop (close)" in log


@pytest.mark.slow
def test_trace_over_the_link_has_the_simulator_s_state(
        tmp_path: Path, served: tuple[subprocess.Popen[str], int]) -> None:
    process, port = served
    remote, local = tmp_path / "remote.csv", tmp_path / "local.csv"
    evaluate_json(link_file(tmp_path, HANDMADE, port), "--trace", str(remote))
    evaluate_json(HANDMADE, "--trace", str(local))
    assert remote.read_text(encoding="utf-8") == local.read_text(encoding="utf-8")
    process.send_signal(signal.SIGINT)  # Ctrl-C ends the server
    assert process.wait(timeout=60) == 130


def _metrics(run: Path) -> list[dict[str, str]]:
    with (run / "metrics.csv").open(encoding="utf-8") as handle:
        return [{k: v for k, v in row.items() if k != "wall_time"}
                for row in csv.DictReader(handle)]


@pytest.mark.slow
def test_learning_over_the_link_equals_learning_on_the_simulator(
        tmp_path: Path, served: tuple[subprocess.Popen[str], int]) -> None:
    _, port = served
    source = BEHAVIOURS / "ballchase.yaml"
    options = ["--generations", "2", "--population", "4", "--seed", "3", "--json"]
    for file, out in ((link_file(tmp_path, source, port), "remote"), (source, "local")):
        result = runner.invoke(app, ["learn", str(file), *options, "--out",
                                     str(tmp_path / out)])
        assert result.exit_code == 0, result.output
    assert _metrics(tmp_path / "remote") == _metrics(tmp_path / "local")
    assert (tmp_path / "remote" / "best.yaml").read_text(encoding="utf-8").split("rules:")[1] \
        .split("environment:")[0] == (tmp_path / "local" / "best.yaml").read_text(
            encoding="utf-8").split("rules:")[1].split("environment:")[0]


def test_serving_a_robot_link_is_an_error(tmp_path: Path) -> None:
    file = link_file(tmp_path, HANDMADE, 9)
    result = runner.invoke(app, ["serve", str(file)])
    assert result.exit_code == 1
    assert "needs a simulator to serve" in result.stderr


@pytest.mark.slow
def test_evaluate_without_a_server_says_how_to_start_one(tmp_path: Path) -> None:
    with server_process(HANDMADE, "--once") as (process, port):
        process.kill()  # the port is free again, and nobody listens
    result = runner.invoke(app, ["evaluate", str(link_file(tmp_path, HANDMADE, port))])
    assert result.exit_code == 1
    assert "connection refused" in result.stderr and "flctool serve" in result.stderr
