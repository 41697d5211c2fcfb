"""Robot-side faults, end to end: ``flctool learn`` over a real loopback socket to a robot side
that misbehaves once, on purpose.

The faulty robot is a proxy in front of the reference server (a simulator behind a socket):
it relays every line faithfully except that, on its first connection, it injects one fault
(in the welcome, or at the Nth step). Each fault must give a clear error (no traceback), a
non-zero exit within the link's timeouts, a ``stop`` sent to the robot where the link still
works, and -- after ``learn --resume`` against the now healthy robot -- exactly the run an
uninterrupted one would have been.
"""

from __future__ import annotations

import contextlib
import csv
import json
import socket
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from flctool.behaviour import (
    behaviour_from_data,
    behaviour_to_data,
    behaviour_to_yaml,
    load_behaviour,
)
from flctool.cli import app
from flctool.envs.robot_server import RobotServer

from ..conftest import BEHAVIOURS

runner = CliRunner()
SIM = load_behaviour(BEHAVIOURS / "ballchase.yaml")
STEP_TIMEOUT = 0.5
#: The longest a fault may take to end the run: the reply timeout, plus the best-effort stop.
WITHIN = 4 * STEP_TIMEOUT + 3.0

Fault = Callable[[dict[str, Any], bytes], bytes | None]


def _json(message: dict[str, Any]) -> bytes:
    return (json.dumps(message) + "\n").encode()


def _reply_with(line: bytes) -> Fault:
    return lambda request, reply: line


def _never_ending(request: dict[str, Any], reply: bytes) -> bytes:
    """Answers every step itself (the simulator behind is not asked): nothing ever ends."""
    batch = len(request["actions"])
    return _json({"type": "step", "observations": [[0.1, 0.0]] * batch, "rewards": [0.0] * batch,
                  "terminated": [False] * batch, "truncated": [False] * batch,
                  "success": [False] * batch})


_never_ending.local = True  # type: ignore[attr-defined]


def _welcome_with(**fields: Any) -> Fault:
    def change(request: dict[str, Any], reply: bytes) -> bytes:
        message = json.loads(reply)
        message.update(fields)
        return _json(message)
    return change


SILENT = object()
HANG_UP = b"<hang up>"

#: name -> (message the fault is injected into, nth such message, fault, expected text,
#: whether the link still works afterwards, so that the client's stop must arrive).
FAULTS: dict[str, tuple[str, int, Fault | object, str, bool]] = {
    "silent": ("step", 60, SILENT, "no reply to 'step' within 0.5 s", True),
    "hangs up": ("step", 60, _reply_with(HANG_UP), "closed the connection during 'step'",
                 False),
    "garbage": ("step", 60, _reply_with(b"{not json\n"), "not a JSON line", True),
    "deep json": ("step", 60, _reply_with(b"[" * 200_000 + b"]" * 200_000 + b"\n"),
                  "nested too deep", True),
    "NaN": ("step", 60, _reply_with(b'{"type":"step","observations":[[NaN, 1]]}\n'),
            "not a JSON line", True),
    "wrong shape": ("step", 60, _reply_with(
        b'{"type":"step","observations":[[1]],"rewards":[0],"terminated":[false],'
        b'"truncated":[false],"success":[false]}\n'), "'observations' must be numbers", True),
    "wrong reply": ("step", 60, _reply_with(b'{"type":"reset"}\n'), "got a 'reset' message",
                    True),
    "error with escapes": ("step", 60, _reply_with(_json({
        "type": "error", "code": "motor\x1b[2J", "message": "\x1b]0;owned\x07overheated\x1b[31m",
        "hint": "let it cool\x07"})), "reported an error (motor): overheated", True),
    "never ends an episode": ("step", 1, _never_ending,
                              "did not end episode", True),
    "welcome max_steps true": ("hello", 1, _welcome_with(max_steps=True),
                               "'max_steps' must be an integer in [1, 1,000,000], got true",
                               True),
    "welcome deep json": ("hello", 1, _reply_with(b"{" + b'"a":{' * 100_000 + b"}" * 100_001
                                                  + b"\n"), "nested too deep", True),
    "welcome huge": ("hello", 1, _reply_with(b'{"type":"welcome","robot":"' + b"x" * 2_000_000
                                             + b'"}\n'), "a line longer than", True),
}


class FaultyRobot:
    """A proxy to ``upstream`` that injects ``fault`` into its first connection only."""

    def __init__(self, upstream: int, kind: str, nth: int, fault: Fault | object) -> None:
        self.upstream, self.kind, self.nth, self.fault = upstream, kind, nth, fault
        self.connections = 0
        self.stopped_after_fault = threading.Event()
        self.faulted = threading.Event()
        self._closing = threading.Event()
        self._listener = socket.create_server(("127.0.0.1", 0))
        self._listener.settimeout(0.1)
        self.port: int = self._listener.getsockname()[1]
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while not self._closing.is_set():
            try:
                conn, _ = self._listener.accept()
            except TimeoutError:
                continue
            self.connections += 1
            threading.Thread(target=self._relay, args=(conn, self.connections == 1),
                             daemon=True).start()

    def _relay(self, conn: socket.socket, inject: bool) -> None:
        with contextlib.suppress(OSError):  # either side may hang up at any time
            self._relay_lines(conn, inject)

    def _relay_lines(self, conn: socket.socket, inject: bool) -> None:
        seen = 0
        local = getattr(self.fault, "local", False)  # the fault answers from the nth on
        with conn, socket.create_connection(("127.0.0.1", self.upstream), timeout=5) as up, \
                conn.makefile("rb") as lines, up.makefile("rb") as replies:
            conn.settimeout(10)
            for line in lines:
                request = json.loads(line)
                if inject and self.faulted.is_set() and request["type"] == "stop":
                    self.stopped_after_fault.set()
                hit = inject and request["type"] == self.kind and (
                    seen < self.nth or local) and not (self.faulted.is_set() and not local)
                if hit:
                    seen += 1
                    hit = seen >= self.nth
                if hit and local:
                    self.faulted.set()
                    assert callable(self.fault)
                    conn.sendall(self.fault(request, b""))
                    continue
                up.sendall(line)
                reply = replies.readline()
                if not reply:
                    return
                if hit:
                    self.faulted.set()
                    if self.fault is SILENT:
                        continue
                    assert callable(self.fault)
                    reply = self.fault(request, reply)
                    if reply == HANG_UP:
                        return
                conn.sendall(reply)

    def close(self) -> None:
        self._closing.set()
        self._thread.join(timeout=5)
        self._listener.close()


@pytest.fixture(scope="module")
def upstream() -> Iterator[int]:
    server = RobotServer.from_behaviour(SIM, port=0, idle_timeout=10.0)
    thread = server.serve_in_background()
    yield server.port
    server.close()
    thread.join(timeout=5)


@pytest.fixture(scope="module")
def clean_run(upstream: int, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The run without a fault, against the healthy robot, for comparison."""
    folder = tmp_path_factory.mktemp("clean")
    result = runner.invoke(app, ["learn", str(_behaviour_file(folder, upstream)),
                                 "--out", str(folder / "run"), "--json"])
    assert result.exit_code == 0, result.output
    return folder / "run"


def _behaviour_file(tmp_path: Path, port: int) -> Path:
    data = behaviour_to_data(SIM)
    data["learning"].update(generations=3, population=4, learner="hybrid")
    data["environment"] = {"adapter": "robot-link", "host": "127.0.0.1", "port": port,
                           "connect_timeout": 2.0, "reset_timeout": 2.0,
                           "step_timeout": STEP_TIMEOUT, "retries": 0}
    path = tmp_path / "robot.yaml"
    path.write_text(behaviour_to_yaml(behaviour_from_data(data)), encoding="utf-8")
    return path


def _metrics(run: Path) -> list[dict[str, str]]:
    """metrics.csv without its wall_time column (the only one a resume may change)."""
    with (run / "metrics.csv").open(encoding="utf-8") as handle:
        return [{k: v for k, v in row.items() if k != "wall_time"}
                for row in csv.DictReader(handle)]


#: The faults of the default test loop: one at a step (with its resume) and the welcome's,
#: which end before any run starts; each other step fault is a run and its resume (slow).
QUICK = {"error with escapes", "welcome max_steps true", "welcome deep json", "welcome huge"}


@pytest.mark.parametrize("name", [
    name if name in QUICK else pytest.param(name, marks=pytest.mark.slow) for name in FAULTS])
def test_a_robot_side_fault_ends_the_run_clearly_and_resume_loses_nothing(
        tmp_path: Path, upstream: int, clean_run: Path, name: str) -> None:
    kind, nth, fault, expected, link_alive = FAULTS[name]
    robot = FaultyRobot(upstream, kind, nth, fault)
    try:
        file = _behaviour_file(tmp_path, robot.port)
        start = time.monotonic()
        result = runner.invoke(app, ["learn", str(file), "--out", str(tmp_path / "run"),
                                     "--json"])
        took = time.monotonic() - start
        assert robot.faulted.is_set()
        assert result.exit_code == 1, result.output
        assert ("Traceback" not in result.output and result.exception is None) or isinstance(
            result.exception, SystemExit)
        assert "error:" in result.output and expected in result.output, result.output
        assert "\x1b" not in result.output and "\x07" not in result.output
        assert took < WITHIN
        if link_alive and kind == "step":
            # the client sends its stop before the command returns, but this server's thread
            # may read it a moment later: wait for it rather than race it
            assert robot.stopped_after_fault.wait(10), "no stop reached the robot"
        if kind == "hello":
            assert not (tmp_path / "run").exists()  # nothing was started
            return
        resumed = runner.invoke(app, ["learn", "--resume", str(tmp_path / "run"), "--json"])
        assert resumed.exit_code == 0, resumed.output
    finally:
        robot.close()
    assert _metrics(tmp_path / "run") == _metrics(clean_run)
    assert load_behaviour(tmp_path / "run" / "best.yaml").rules == \
        load_behaviour(clean_run / "best.yaml").rules
