"""The robot link client over real sockets on 127.0.0.1: against the reference server (a
simulator behind a socket) and against scripted bridges that misbehave on purpose."""

from __future__ import annotations

import json
import signal
import socket
import threading
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from flctool import compile_behaviour, load_behaviour
from flctool.behaviour import Behaviour, behaviour_from_data, behaviour_to_data, parse_behaviour
from flctool.envs import check_env, make_env
from flctool.envs.robot_link import RobotLinkEnv
from flctool.envs.robot_protocol import PROTOCOL, VERSION
from flctool.envs.robot_server import RobotServer
from flctool.errors import EnvError, LinkError, SpecError
from flctool.rollout import evaluate, evaluation_seeds, trace_episode

from ..conftest import BEHAVIOURS

HANDMADE = load_behaviour(BEHAVIOURS / "ballchase-handmade.yaml")
FAST = {"connect_timeout": 2.0, "reset_timeout": 2.0, "step_timeout": 2.0, "retries": 0}


def link_behaviour(behaviour: Behaviour | dict[str, Any], port: int,
                   **options: Any) -> Behaviour:
    """``behaviour`` (or its data) with its environment replaced by a robot link to
    127.0.0.1:port."""
    data = behaviour_to_data(behaviour) if isinstance(behaviour, Behaviour) else behaviour
    data["environment"] = {"adapter": "robot-link", "host": "127.0.0.1", "port": port,
                           **FAST, **options}
    return behaviour_from_data(data)


@pytest.fixture
def server() -> Iterator[RobotServer]:
    """The reference server for the handmade ballchase behaviour, in a thread."""
    robot = RobotServer.from_behaviour(HANDMADE, port=0, idle_timeout=5.0)
    thread = robot.serve_in_background()
    yield robot
    robot.close()
    thread.join(timeout=5)


def free_port() -> int:
    """A port nobody listens on (bound, then released)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
    return port


class ScriptedBridge:
    """A bridge on a real socket that answers each request with ``script(message)``: a line
    to send (bytes), None to stay silent, or ``CLOSE`` to hang up. Records what it received."""

    CLOSE = b"<close>"

    def __init__(self, script: Callable[[dict[str, Any]], bytes | None],
                 features: tuple[str, ...] = ()) -> None:
        self.script = script
        self.features = features
        self.received: list[dict[str, Any]] = []
        self.got_stop = threading.Event()
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.port: int = self._listener.getsockname()[1]
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def welcome(self) -> bytes:
        message = {"type": "welcome", "protocol": PROTOCOL, "version": VERSION,
                   "robot": "scripted", "observations": list(HANDMADE.input_names),
                   "commands": dict(HANDMADE.output.commands), "max_steps": 50,
                   "max_batch": 1, "features": list(self.features)}
        return (json.dumps(message) + "\n").encode()

    def _serve(self) -> None:
        self._listener.settimeout(5.0)
        conn, _ = self._listener.accept()
        conn.settimeout(5.0)
        with conn, conn.makefile("rb") as lines:
            for line in lines:
                message = json.loads(line)
                self.received.append(message)
                if message["type"] == "stop":
                    self.got_stop.set()
                    return
                reply = self.welcome() if message["type"] == "hello" else self.script(message)
                if reply == self.CLOSE:
                    return
                if reply is not None:
                    conn.sendall(reply)

    def close(self) -> None:
        self._thread.join(timeout=5)
        self._listener.close()


def reset_reply(message: dict[str, Any]) -> bytes | None:
    if message["type"] == "reset":
        return b'{"type":"reset","observations":[[0.2,10.0]],"success":[false]}\n'
    return None


def test_the_link_passes_the_adapter_checker(server: RobotServer) -> None:
    env = make_env(link_behaviour(HANDMADE, server.port))
    assert isinstance(env, RobotLinkEnv)
    assert env.max_steps == make_env(HANDMADE).max_steps and env.features == {"fitness", "state"}
    check_env(env, batch_size=3)


def test_evaluate_over_the_link_equals_the_simulator_bit_for_bit(server: RobotServer) -> None:
    controller = compile_behaviour(HANDMADE)
    seeds = evaluation_seeds(3, 40)
    with RobotLinkEnv.from_behaviour(link_behaviour(HANDMADE, server.port)) as link:
        remote = evaluate(controller, link, seeds)
        remote_trace = trace_episode(controller, link, int(seeds[0]))
    sim = make_env(HANDMADE)
    local = evaluate(controller, sim, seeds)
    for field in ("returns", "lengths", "success", "fitness"):
        assert np.array_equal(getattr(remote, field), getattr(local, field)), field
    assert remote_trace == trace_episode(controller, sim, int(seeds[0]))
    assert "robot_x" in remote_trace[0]


def test_a_one_episode_robot_is_evaluated_episode_after_episode() -> None:
    # A real robot runs one episode at a time: evaluate then takes the seeds one by one.
    robot = RobotServer.from_behaviour(HANDMADE, port=0, idle_timeout=5.0, max_batch=1)
    thread = robot.serve_in_background()
    try:
        controller = compile_behaviour(HANDMADE)
        seeds = evaluation_seeds(4, 6)
        with RobotLinkEnv.from_behaviour(link_behaviour(HANDMADE, robot.port)) as link:
            assert link.max_batch == 1
            remote = evaluate(controller, link, seeds)
        local = evaluate(controller, make_env(HANDMADE), seeds)
        for field in ("returns", "lengths", "success", "fitness"):
            assert np.array_equal(getattr(remote, field), getattr(local, field)), field
    finally:
        robot.close()
        thread.join(timeout=5)


def test_the_one_episode_path_equals_the_simulator(server: RobotServer) -> None:
    link = make_env(link_behaviour(HANDMADE, server.port))
    sim = make_env(HANDMADE)
    assert np.array_equal(link.reset_one(11), sim.reset_one(11))
    for action in (0.3, -0.7, 1.0, 0.0):
        remote, local = link.step_one(action), sim.step_one(action)
        assert np.array_equal(remote[0], local[0]) and remote[1:] == local[1:]
    link.close()


def test_fitness_comes_from_the_robot_side(server: RobotServer) -> None:
    link = make_env(link_behaviour(HANDMADE, server.port))
    returns, lengths = np.array([1.0, -1.0, 0.0]), np.array([30, 80, 200])
    success = np.array([True, False, False])
    expected = make_env(HANDMADE).episode_fitness(returns, lengths, success)
    assert np.array_equal(link.episode_fitness(returns, lengths, success), expected)
    link.close()


def test_without_the_fitness_feature_fitness_is_the_return() -> None:
    bridge = ScriptedBridge(reset_reply)
    link = make_env(link_behaviour(HANDMADE, bridge.port))
    assert link.max_batch == 1 and link.features == frozenset()
    returns = np.array([1.0])
    assert link.episode_fitness(returns, np.array([3]), np.array([True])).tolist() == [1.0]
    assert link.trace_state() == {}
    link.close()
    bridge.close()


@pytest.mark.parametrize(("change", "field", "message"), [
    (lambda d: d["inputs"].update(head_pan=d["inputs"].pop("pan")), "inputs.head_pan",
     "the robot has no observation 'head_pan'. Did you mean 'pan'?"),
    (lambda d: d["output"]["commands"].update(forward=0.1), "output.commands.forward",
     "singleton 0.1, but the robot's is 0"),
    (lambda d: d["output"]["commands"].pop("turn_left"), "output.commands",
     "the robot also has command turn_left"),
])
def test_a_behaviour_that_does_not_fit_the_robot_names_the_field(
        server: RobotServer, change: Callable[[dict[str, Any]], None], field: str,
        message: str) -> None:
    data = behaviour_to_data(HANDMADE)
    data["rules"] = []
    change(data)
    with pytest.raises(SpecError) as raised:
        make_env(link_behaviour(data, server.port))
    assert f"{field}: {message}" in str(raised.value)


def test_the_behaviour_may_read_a_subset_of_the_observations(server: RobotServer) -> None:
    data = behaviour_to_data(HANDMADE)
    del data["inputs"]["ball_size"]
    data["rules"] = []
    link = make_env(link_behaviour(data, server.port))
    observations, _ = link.reset(np.array([4, 5]))
    full, _ = make_env(HANDMADE).reset(np.array([4, 5]))
    assert np.array_equal(observations, full[:, 1:])
    link.close()


def test_no_server_gives_a_link_error_with_a_hint() -> None:
    port = free_port()
    with pytest.raises(LinkError) as raised:
        make_env(link_behaviour(HANDMADE, port, retries=1, retry_delay=0.01))
    text = str(raised.value)
    assert f"127.0.0.1:{port}: connection refused after 2 attempts" in text
    assert "is the robot's bridge running" in text and "flctool serve" in text


def test_a_silent_robot_times_out_and_is_sent_stop() -> None:
    bridge = ScriptedBridge(reset_reply)  # answers reset, then never a step
    link = make_env(link_behaviour(HANDMADE, bridge.port, step_timeout=0.2))
    link.reset(np.array([1]))
    with pytest.raises(LinkError, match=r"no reply to 'step' within 0.2 s; the robot was sent "
                       r"stop.*raise environment.step_timeout"):
        link.step(np.array([0.0]))
    assert bridge.got_stop.wait(5)
    assert bridge.received[-1]["type"] == "stop"
    assert "no reply to 'step'" in bridge.received[-1]["reason"]
    bridge.close()


@pytest.mark.parametrize(("reply", "message"), [
    (b"this is not json\n", "not a JSON line"),
    (b'{"type":"reset","observations":[[0.2]],"success":[false]}\n',
     "'observations' must be numbers of shape [1, 2]"),
    (b'{"type":"reset","observations":[[0.2,"x"]],"success":[false]}\n',
     "'observations' must be numbers"),
    (b'{"type":"reset","observations":[[0.2,1]],"success":[1]}\n',
     "'success' must be 1 true/false values"),
    (b'{"type":"step"}\n', "got a 'step' message"),
    (b'[1, 2]\n', "must be a JSON object"),
])
def test_a_malformed_reply_stops_the_robot(reply: bytes, message: str) -> None:
    bridge = ScriptedBridge(lambda m: reply)
    link = make_env(link_behaviour(HANDMADE, bridge.port))
    with pytest.raises(LinkError, match="malformed reply to 'reset'") as raised:
        link.reset(np.array([1]))
    assert message in str(raised.value)
    assert bridge.got_stop.wait(5)
    bridge.close()


def test_a_robot_that_hangs_up_gives_a_link_error() -> None:
    bridge = ScriptedBridge(lambda m: ScriptedBridge.CLOSE)
    link = make_env(link_behaviour(HANDMADE, bridge.port))
    with pytest.raises(LinkError, match=r"closed the connection during 'reset'.*bridge's log"):
        link.reset(np.array([1]))
    bridge.close()


def test_an_error_from_the_robot_side_is_reported_with_its_hint() -> None:
    error = {"type": "error", "code": "robot", "message": "motor 3 overheated",
             "hint": "let it cool"}
    bridge = ScriptedBridge(lambda m: (json.dumps(error) + "\n").encode())
    link = make_env(link_behaviour(HANDMADE, bridge.port))
    with pytest.raises(LinkError, match=r"reported an error \(robot\): motor 3 overheated.*"
                       r"fix: let it cool"):
        link.reset(np.array([1]))
    bridge.close()


@pytest.mark.skipif(not hasattr(signal, "pthread_kill"), reason="needs POSIX signals")
@pytest.mark.usefixtures("ctrl_c_raises")
def test_an_interrupt_stops_the_robot_and_propagates() -> None:
    main = threading.main_thread().ident
    assert main is not None and threading.current_thread().ident == main

    def interrupt(message: dict[str, Any]) -> bytes | None:
        if message["type"] == "step":
            signal.pthread_kill(main, signal.SIGINT)  # Ctrl-C while the client waits
            return None
        return reset_reply(message)
    bridge = ScriptedBridge(interrupt)
    # a long step timeout: the interrupt, not the timeout, must end the wait, even on a
    # loaded machine
    link = make_env(link_behaviour(HANDMADE, bridge.port, step_timeout=60.0))
    link.reset(np.array([1]))
    with pytest.raises(KeyboardInterrupt):
        link.step(np.array([0.5]))
    assert bridge.got_stop.wait(5)
    assert bridge.received[-1] == {"type": "stop", "reason": "interrupted"}
    bridge.close()


def test_a_bad_action_stops_the_robot_before_raising(server: RobotServer) -> None:
    link = make_env(link_behaviour(HANDMADE, server.port))
    link.reset(np.array([1, 2]))
    with pytest.raises(EnvError, match="an action is NaN"):
        link.step(np.array([0.0, np.nan]))
    with pytest.raises(EnvError, match="step with no episode running"):
        link.step(np.array([0.0, 0.0]))
    link.reset(np.array([1, 2]))  # the next reset reconnects
    link.close()
    assert server.connections == 2
    assert any("an action is NaN" in reason for reason in server.stops)


def test_close_sends_stop_and_a_batch_beyond_the_robot_is_refused() -> None:
    bridge = ScriptedBridge(reset_reply)
    link = make_env(link_behaviour(HANDMADE, bridge.port))
    with pytest.raises(LinkError, match="at most 1 episode at a time, asked for 2"):
        link.reset(np.array([1, 2]))
    link.reset(np.array([1]))
    link.close()
    link.close()  # closing twice is harmless
    assert bridge.got_stop.wait(5)
    assert bridge.received[-1] == {"type": "stop", "reason": "close"}
    bridge.close()


def test_a_second_robot_version_is_refused() -> None:
    listener = socket.create_server(("127.0.0.1", 0))

    def answer() -> None:
        conn, _ = listener.accept()
        with conn:
            conn.recv(4096)
            conn.sendall(b'{"type":"welcome","protocol":"flctool-robot-link","version":2}\n')
            conn.recv(4096)
    thread = threading.Thread(target=answer, daemon=True)
    thread.start()
    with pytest.raises(LinkError, match="malformed welcome: the robot speaks "
                       "'flctool-robot-link' version 2"):
        make_env(link_behaviour(HANDMADE, listener.getsockname()[1]))
    thread.join(timeout=5)
    listener.close()


@pytest.mark.parametrize(("environment", "field"), [
    ("{adapter: robot-link}", "environment.port: required field 'port' is missing"),
    ("{adapter: robot-link, port: 70000}", "environment.port"),
    ("{adapter: robot-link, port: 9000, step_timeout: 0}", "environment.step_timeout"),
    ("{adapter: robot-link, port: 9000, retries: -1}", "environment.retries"),
    ("{adapter: robot-link, port: 9000, host: ''}", "environment.host"),
    ("{adapter: robot-link, port: 9000, timeout: 3}", "unknown key 'timeout'"),
])
def test_the_link_config_is_validated(minimal_text: str, environment: str, field: str) -> None:
    with pytest.raises(SpecError, match=field.replace(".", r"\.")):
        parse_behaviour(minimal_text + f"environment: {environment}\n")


# -- a robot side that is not to be trusted ---------------------------------------------------
def _welcome_bridge(**fields: Any) -> ScriptedBridge:
    bridge = ScriptedBridge(reset_reply)
    base = bridge.welcome

    def welcome() -> bytes:
        message = json.loads(base())
        message.update(fields)
        return (json.dumps(message) + "\n").encode()

    bridge.welcome = welcome  # type: ignore[method-assign]
    return bridge


@pytest.mark.parametrize(("fields", "message"), [
    ({"max_steps": True}, "'max_steps' must be an integer in [1, 1,000,000], got true"),
    ({"max_steps": 10**9}, "'max_steps' must be an integer in [1, 1,000,000]"),
    ({"max_batch": False}, "'max_batch' must be null or an integer in [1, 100,000], got false"),
    ({"version": True}, "not flctool-robot-link 1"),
    ({"robot": {"name": 1}}, "'robot' must be a string"),
    ({"observations": ["x"] * 10_001}, "'observations' has more than 10,000 entries"),
])
def test_welcome_values_are_type_checked_and_bounded(fields: dict[str, Any],
                                                     message: str) -> None:
    bridge = _welcome_bridge(**fields)
    with pytest.raises(LinkError, match="malformed welcome") as info:
        make_env(link_behaviour(HANDMADE, bridge.port))
    assert message in str(info.value)
    assert bridge.got_stop.wait(2)
    bridge.close()


def test_a_robot_name_with_escapes_is_shown_without_them() -> None:
    bridge = _welcome_bridge(robot="\x1b]0;owned\x07AIBO\x1b[5m", observations=["size", "pan"])
    with pytest.raises(SpecError) as info:
        make_env(link_behaviour(HANDMADE, bridge.port))
    assert "robot 'AIBO'" in str(info.value) and "\x1b" not in str(info.value)
    bridge.close()


def test_an_episode_the_robot_never_ends_is_stopped_at_its_max_steps() -> None:
    def endless(message: dict[str, Any]) -> bytes | None:
        if message["type"] == "reset":
            return b'{"type":"reset","observations":[[0.2,10.0]],"success":[false]}\n'
        return (b'{"type":"step","observations":[[0.2,10.0]],"rewards":[0],'
                b'"terminated":[false],"truncated":[false],"success":[false]}\n')

    bridge = ScriptedBridge(endless)
    env = make_env(link_behaviour(HANDMADE, bridge.port))
    env.reset(np.array([1]))
    for _ in range(env.max_steps - 1):
        env.step(np.zeros(1))
    with pytest.raises(LinkError, match="did not end episode 0 after its max_steps = 50"):
        env.step(np.zeros(1))
    assert bridge.got_stop.wait(2)
    assert sum(m["type"] == "step" for m in bridge.received) == 50
    bridge.close()


def test_a_reset_past_the_link_s_episode_step_limit_is_refused() -> None:
    bridge = ScriptedBridge(reset_reply)
    bridge_welcome = json.loads(bridge.welcome())
    assert bridge_welcome["max_batch"] == 1
    env = make_env(link_behaviour(HANDMADE, bridge.port))
    with pytest.raises(EnvError, match="episode steps per reset"):
        env.reset(np.arange(1_000_000))
    env.close()
    bridge.close()
