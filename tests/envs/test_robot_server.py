"""The reference robot-side server, spoken to line by line over a real socket on 127.0.0.1."""

from __future__ import annotations

import json
import socket
import threading
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from flctool import load_behaviour
from flctool.behaviour import behaviour_from_data, behaviour_to_data
from flctool.envs import make_env
from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.envs.robot_protocol import PROTOCOL, VERSION
from flctool.envs.robot_server import RobotServer
from flctool.errors import EnvError

from ..conftest import BEHAVIOURS

HANDMADE = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
HELLO = {"type": "hello", "protocol": PROTOCOL, "version": VERSION, "behaviour": "test",
         "observations": ["ball_size", "pan"], "commands": {}}


class Client:
    """A raw protocol client: one JSON line out, one JSON line back."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.lines = self.sock.makefile("rb")

    def send(self, message: dict[str, Any] | bytes) -> None:
        data = message if isinstance(message, bytes) else (json.dumps(message) + "\n").encode()
        self.sock.sendall(data)

    def receive(self) -> dict[str, Any] | None:
        line = self.lines.readline()
        return json.loads(line) if line else None

    def ask(self, message: dict[str, Any] | bytes) -> dict[str, Any] | None:
        self.send(message)
        return self.receive()

    def close(self) -> None:
        self.lines.close()
        self.sock.close()


def start(env: BatchEnv | None = None, **options: Any) -> Iterator[RobotServer]:
    server = (RobotServer(env, dict(HANDMADE.output.commands), **options) if env is not None
              else RobotServer.from_behaviour(HANDMADE, **options))
    thread = server.serve_in_background()
    yield server
    server.close()
    thread.join(timeout=5)
    assert not thread.is_alive()


@pytest.fixture
def server() -> Iterator[RobotServer]:
    yield from start(idle_timeout=5.0)


@pytest.fixture
def client(server: RobotServer) -> Iterator[Client]:
    talk = Client(server.port)
    yield talk
    talk.close()


def test_the_welcome_describes_the_robot(server: RobotServer, client: Client) -> None:
    welcome = client.ask(HELLO)
    assert welcome == {"type": "welcome", "protocol": PROTOCOL, "version": VERSION,
                       "robot": "flctool reference server", "observations": ["ball_size", "pan"],
                       "commands": dict(HANDMADE.output.commands), "max_steps": 200,
                       "max_batch": None, "features": ["fitness", "state"]}


def test_reset_and_step_are_the_simulator_s(client: Client) -> None:
    client.ask(HELLO)
    sim = make_env(HANDMADE)
    observations, _ = sim.reset(np.array([3, 4, 5]))
    reply = client.ask({"type": "reset", "seeds": [3, 4, 5]})
    assert reply == {"type": "reset", "observations": observations.tolist(),
                     "success": [False] * 3}
    out = sim.step(np.array([0.25, -1.0, 0.5]))
    reply = client.ask({"type": "step", "actions": [0.25, -1, 0.5]})
    assert reply == {"type": "step", "observations": out.observations.tolist(),
                     "rewards": out.rewards.tolist(), "terminated": out.terminated.tolist(),
                     "truncated": out.truncated.tolist(), "success": sim.success().tolist()}
    state = client.ask({"type": "state"})
    assert state is not None and state["state"]["robot_x"] == sim.trace_state()["robot_x"].tolist()
    fitness = client.ask({"type": "fitness", "returns": [1, -1], "lengths": [20, 100],
                          "success": [True, False]})
    expected = sim.episode_fitness(np.array([1.0, -1.0]), np.array([20, 100]),
                                   np.array([True, False]))
    assert fitness == {"type": "fitness", "fitness": expected.tolist()}


def test_stop_halts_the_robot_and_keeps_the_connection(server: RobotServer,
                                                       client: Client) -> None:
    client.ask(HELLO)
    client.ask({"type": "reset", "seeds": [1]})
    assert client.ask({"type": "stop", "reason": "done"}) == {"type": "stop"}
    assert server.stops == ["the client sent stop (done)"]
    reply = client.ask({"type": "step", "actions": [0.0]})
    assert reply is not None and reply["code"] == "unexpected"
    assert "step with no episode running" in reply["message"]
    assert client.receive() is None  # every error ends the connection


@pytest.mark.parametrize(("messages", "code", "text"), [
    ([{"type": "reset", "seeds": [1]}], "unexpected", "expected 'hello' first"),
    ([{**HELLO, "version": 2}], "version", "the client 'flctool-robot-link' version 2"),
    ([HELLO, b"{not json\n"], "malformed", "not a JSON line"),
    ([HELLO, {"type": "jump"}], "unexpected", "unknown message type 'jump'"),
    ([HELLO, {"type": "reset", "seeds": []}], "malformed", "'seeds' must be a non-empty list"),
    ([HELLO, {"type": "reset", "seeds": [1]}, {"type": "step", "actions": [0.0, 1.0]}],
     "malformed", "'actions' must be numbers of shape [1]"),
    ([HELLO, {"type": "reset", "seeds": [1]}, {"type": "step", "actions": ["left"]}],
     "malformed", "'actions' must be numbers"),
    ([HELLO, {"type": "fitness", "returns": [1], "lengths": [1, 2], "success": [True]}],
     "malformed", "'lengths' must be numbers of shape [1]"),
])
def test_a_bad_message_is_answered_with_an_error_and_a_stop(
        server: RobotServer, client: Client, messages: list[dict[str, Any] | bytes], code: str,
        text: str) -> None:
    for message in messages[:-1]:
        client.ask(message)
    reply = client.ask(messages[-1])
    assert reply is not None and reply["type"] == "error" and reply["code"] == code
    assert text in reply["message"]
    assert client.receive() is None
    if len(messages) == 1:  # refused at the handshake: it never controlled the robot
        assert server.stops == []
    else:
        assert server.stops and server.stops[-1].startswith(code)


def test_a_client_that_disconnects_mid_episode_stops_the_robot(server: RobotServer) -> None:
    halted: list[str] = []
    server.on_stop = halted.append
    client = Client(server.port)
    client.ask(HELLO)
    client.ask({"type": "reset", "seeds": [7]})
    client.close()
    follow = Client(server.port)  # served once the first client is gone
    assert follow.ask(HELLO) is not None
    follow.close()
    assert halted == ["the client disconnected"] == server.stops


def test_a_silent_client_is_timed_out_and_the_robot_stopped() -> None:
    for server in start(idle_timeout=0.2):
        client = Client(server.port)
        client.ask(HELLO)
        # No timing window: whether the reset is answered before the watchdog fires (on a
        # busy machine it may not be), the next message that is not its reply is the timeout.
        client.send({"type": "reset", "seeds": [7]})
        reply = client.receive()
        if reply is not None and reply.get("type") == "reset":
            reply = client.receive()  # then send nothing: the server's watchdog fires
        assert reply is not None and reply["code"] == "timeout"
        assert reply["message"] == "no message for 0.2 s"
        assert server.stops == ["timeout: no message for 0.2 s"]
        client.close()


def test_a_robot_that_runs_one_episode_at_a_time_refuses_more() -> None:
    for server in start(max_batch=1, idle_timeout=5.0):
        client = Client(server.port)
        welcome = client.ask(HELLO)
        assert welcome is not None and welcome["max_batch"] == 1
        reply = client.ask({"type": "reset", "seeds": [1, 2]})
        assert reply is not None and reply["code"] == "batch"
        client.close()


class _Faulty(BatchEnv):
    """An environment whose step fails, as a robot's driver might."""

    observation_names = ("ball_size", "pan")
    max_steps = 5
    action_bounds = (-1.0, 1.0)

    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        return np.zeros((seeds.shape[0], 2)), {}

    def step(self, actions: FloatArray) -> Step:
        raise EnvError("motor 3 overheated", hint="let it cool")

    def success(self) -> BoolArray:
        return np.zeros(1, dtype=bool)


def test_an_environment_fault_is_reported_and_stops_the_robot() -> None:
    for server in start(_Faulty(), idle_timeout=5.0):
        client = Client(server.port)
        client.ask(HELLO)
        client.ask({"type": "reset", "seeds": [1]})
        reply = client.ask({"type": "step", "actions": [0.0]})
        assert reply == {"type": "error", "code": "robot",
                         "message": "EnvError: motor 3 overheated (fix: let it cool)",
                         "hint": "let it cool"}
        assert server.stops == ["server error: motor 3 overheated (fix: let it cool)"]
        client.close()


def test_close_ends_a_connection_in_progress() -> None:
    server = RobotServer.from_behaviour(HANDMADE, idle_timeout=30.0)
    thread = server.serve_in_background()
    client = Client(server.port)
    client.ask(HELLO)
    server.close()
    reply = client.receive()
    assert reply is not None and reply["code"] == "shutdown"
    thread.join(timeout=5)
    assert not thread.is_alive()
    client.close()


def test_the_server_refuses_to_serve_a_robot_link() -> None:
    data = behaviour_to_data(HANDMADE)
    data["environment"] = {"adapter": "robot-link", "port": 9}
    with pytest.raises(EnvError, match="needs a simulator to serve"):
        RobotServer.from_behaviour(behaviour_from_data(data))


def test_a_taken_port_is_an_error(server: RobotServer) -> None:
    with pytest.raises(EnvError, match=f"cannot listen on 127.0.0.1:{server.port}.*--port"):
        RobotServer.from_behaviour(HANDMADE, port=server.port)


def test_any_simulator_adapter_can_be_served() -> None:
    cartpole = load_behaviour(BEHAVIOURS / "cartpole.yaml")
    server = RobotServer.from_behaviour(cartpole, idle_timeout=5.0)
    thread = server.serve_in_background(once=True)
    client = Client(server.port)
    welcome = client.ask({**HELLO, "observations": list(cartpole.input_names)})
    assert welcome is not None and welcome["observations"] == list(cartpole.input_names)
    sim = make_env(cartpole)
    observations, _ = sim.reset(np.array([2]))
    reply = client.ask({"type": "reset", "seeds": [2]})
    assert reply is not None and reply["observations"] == observations.tolist()
    client.close()
    thread.join(timeout=5)  # --once: the server ends with its first client
    assert not thread.is_alive()


class _Interrupted(_Faulty):
    """Ctrl-C arrives while the robot is stepping."""

    def step(self, actions: FloatArray) -> Step:
        raise KeyboardInterrupt


def test_ctrl_c_mid_episode_stops_the_robot_before_the_server_ends() -> None:
    halted: list[str] = []
    server = RobotServer(_Interrupted(), dict(HANDMADE.output.commands), idle_timeout=5.0,
                         on_stop=halted.append)
    replies: list[dict[str, Any] | None] = []

    def drive() -> None:  # the client, in a thread: the server runs here, as `serve` does
        client = Client(server.port)
        client.ask(HELLO)
        client.ask({"type": "reset", "seeds": [1]})
        replies.append(client.ask({"type": "step", "actions": [0.0]}))
        client.close()

    thread = threading.Thread(target=drive)
    thread.start()
    with pytest.raises(KeyboardInterrupt):
        server.serve()
    thread.join(timeout=5)
    assert halted == ["the server was interrupted"] == server.stops
    assert replies == [{"type": "error", "code": "shutdown",
                        "message": "the robot server was interrupted",
                        "hint": "start the server again, then reconnect"}]


# -- hostile clients -------------------------------------------------------------------------
def test_idle_connections_do_not_lock_out_a_client() -> None:
    from flctool.envs.robot_server import MAX_PENDING

    for server in start(idle_timeout=5.0):
        idle = [socket.create_connection(("127.0.0.1", server.port)) for _ in range(200)]
        good = Client(server.port)
        welcome = good.ask(HELLO)
        assert welcome is not None and welcome["type"] == "welcome"
        assert good.ask({"type": "reset", "seeds": [3]}) is not None
        good.close()
        assert server.connections == 201 and len(server._pending) <= MAX_PENDING
        for sock in idle:
            sock.close()


def test_a_connection_without_a_hello_is_dropped() -> None:
    for server in start(idle_timeout=5.0, hello_timeout=0.2):
        quiet = Client(server.port)
        reply = quiet.receive()
        assert reply is not None and reply["code"] == "timeout"
        assert "no hello within 0.2 s" in reply["message"]
        assert server.stops == []  # it never controlled the robot
        quiet.close()


def test_a_second_client_is_told_the_robot_is_busy(monkeypatch: pytest.MonkeyPatch) -> None:
    from flctool.envs import robot_server

    monkeypatch.setattr(robot_server, "BUSY_WAIT", 0.2)
    for server in start(idle_timeout=5.0):
        first = Client(server.port)
        assert first.ask(HELLO) is not None
        second = Client(server.port)
        reply = second.ask(HELLO)
        assert reply is not None and reply["code"] == "busy"
        assert first.ask({"type": "reset", "seeds": [1]}) is not None  # undisturbed
        first.close()
        second.close()


def test_a_client_that_only_sends_stop_loses_control_after_the_idle_timeout() -> None:
    for server in start(idle_timeout=0.5):
        spammer = Client(server.port)
        assert spammer.ask(HELLO) is not None
        reply: dict[str, Any] | None = {"type": "stop"}
        while reply is not None and reply["type"] == "stop":
            reply = spammer.ask({"type": "stop", "reason": "spam"})
        assert reply is not None and reply["code"] == "timeout"
        spammer.close()
        good = Client(server.port)
        welcome = good.ask(HELLO)
        assert welcome is not None and welcome["type"] == "welcome"
        good.close()


@pytest.mark.parametrize(("message", "code", "text"), [
    ({"type": "reset", "seeds": list(range(1_000_000))}, "batch",
     "1,000,000 episodes of 200 steps are more than 20,000,000 episode steps per reset"),
    ({"type": "fitness", "returns": [1.0], "lengths": [-5], "success": [True]}, "malformed",
     "'lengths' must be whole numbers of steps in [0, 200]"),
    ({"type": "fitness", "returns": [1.0], "lengths": [1e300], "success": [True]}, "malformed",
     "'lengths' must be whole numbers of steps in [0, 200]"),
    ({"type": "fitness", "returns": [1.0] * 100_001, "lengths": [1] * 100_001,
      "success": [True] * 100_001}, "batch", "fitness of 100,001 episodes asked"),
    ({"type": "stop", "reason": "\x1b[2Jcleared"}, None, ""),
])
@pytest.mark.slow
def test_requests_are_bounded(server: RobotServer, client: Client, message: dict[str, Any],
                              code: str | None, text: str) -> None:
    client.ask(HELLO)
    reply = client.ask(message)
    assert reply is not None
    if code is None:
        assert reply == {"type": "stop"}
        assert server.stops == ["the client sent stop (cleared)"]
    else:
        assert reply["code"] == code and text in reply["message"]
