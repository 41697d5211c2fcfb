"""The robot link: the :class:`~flctool.envs.base.BatchEnv` protocol over TCP to a real robot
or its bridge, so that ``flctool learn`` and ``flctool evaluate`` run on a robot exactly as on
the simulator.

Messages are JSON objects, one per line (docs/robot-link.md is the specification). The client
sends a request and waits for its one reply, within a timeout from the behaviour's
``environment:`` section::

    hello  -> welcome       versioned handshake: observation and command names are checked
    reset  -> reset         seeds (B,) -> observations (B, N), success (B,)
    step   -> step          actions (B,) -> observations, rewards, terminated, truncated, success
    fitness -> fitness      the robot side's trial fitness of finished episodes (optional)
    state  -> state         per-episode state for traces (optional)
    stop   -> stop          halt the robot; the connection stays open
    any    -> error         the robot side failed; it has stopped and closes the connection

**Safe stop.** On any fault -- a reply timeout, a malformed reply, a lost connection, an error
reported by the robot, a bad action or an interrupt -- the client sends ``stop`` (best effort:
the link may be dead), closes the socket and raises :class:`~flctool.errors.LinkError` saying
what happened and how to fix it (a KeyboardInterrupt is re-raised as it is, after the stop).
Steps are never retried: a step moves the robot. The next ``reset`` reconnects.

Fitness and success come from the robot side, which knows its outcome: every reply carries
``success``, so :meth:`RobotLinkEnv.success` needs no round trip, and
:meth:`RobotLinkEnv.episode_fitness` asks the robot side (a ``fitness`` request: a pure
function of returns, lengths and success) when its welcome lists the ``fitness`` feature, and
otherwise uses the undiscounted return.

JSON numbers carry floats exactly (Python writes the shortest text that reads back to the
same double), so a simulator behind the link gives bit for bit what it gives directly.

**A robot side is not trusted.** Lines are bounded (:data:`MAX_LINE`, the welcome
:data:`MAX_WELCOME_LINE`) and so is their nesting; welcome values are type-checked (a JSON
``true`` is not an integer) and bounded; text the robot sends is shown without terminal
control sequences; and an episode the robot side does not end by its own ``max_steps`` is a
fault: the robot is sent stop and the run ends, instead of running forever.
"""

from __future__ import annotations

import contextlib
import json
import math
import socket
import time
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.environment import RobotLinkConfig
from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.envs.robot_protocol import (
    FEATURES,
    MAX_BATCH_STEPS,
    MAX_LINE,
    MAX_WELCOME_BATCH,
    MAX_WELCOME_LINE,
    MAX_WELCOME_NAMES,
    MAX_WELCOME_STEPS,
    PROTOCOL,
    VERSION,
    Channel,
    ProtocolError,
    bool_array,
    float_array,
    printable,
    string_list,
)
from flctool.errors import EnvError, FlcError, LinkError, Problem, SpecError
from flctool.registry import did_you_mean

T = TypeVar("T")
_STOP_WAIT = 1.0  # s at most to hand a best-effort stop to a dying link


def _command_table(value: Any) -> dict[str, float]:
    if not (isinstance(value, dict) and len(value) <= MAX_WELCOME_NAMES and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in value.values())):
        raise ProtocolError("'commands' must map command names to finite numbers")
    return {printable(k, 200): float(v) for k, v in value.items()}


def _bounded_int(value: Any, what: str, limit: int, optional: bool = False) -> Any:
    """A welcome's integer: JSON true is not 1 here."""
    if optional and value is None:
        return None
    if not (isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= limit):
        raise ProtocolError(f"'{what}' must be {'null or ' if optional else ''}an integer "
                            f"in [1, {limit:,}], got {printable(json.dumps(value), 40)}")
    return value


class RobotLinkEnv(BatchEnv):
    """B episodes on a robot (or a simulator) behind a TCP connection; B = 1 for a real robot.

    Connects and shakes hands when built, so a wrong address or a behaviour that does not fit
    the robot fails at once, before anything runs. ``max_steps`` is the robot side's.
    """

    def __init__(self, config: RobotLinkConfig, behaviour_name: str,
                 observation_names: tuple[str, ...], commands: dict[str, float]) -> None:
        self.config = config
        self.behaviour_name = behaviour_name
        self.observation_names = observation_names
        self.commands = dict(commands)
        values = sorted(self.commands.values())
        self.action_bounds = (float(values[0]), float(values[-1]))
        self.where = f"robot link {config.host}:{config.port}"
        self.max_steps = 1
        self.max_batch: int | None = None
        self.robot = ""
        self.features: frozenset[str] = frozenset()
        self._channel: Channel | None = None
        self._columns: list[int] = []
        self._width = 0  # observations per episode the robot sends
        self._batch = 0  # episodes of the running reset; 0: none
        self._steps = 0  # steps of the running reset
        self._ended: BoolArray = np.zeros(0, dtype=bool)  # episodes that have ended
        self._success: BoolArray = np.zeros(0, dtype=bool)
        self._connect()

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, batch_size: int = 1) -> RobotLinkEnv:
        del batch_size  # B is the number of seeds given to reset
        config = behaviour.environment
        if not isinstance(config, RobotLinkConfig):
            raise EnvError("the robot link needs 'environment: {adapter: robot-link, port: ...}'")
        return cls(config, behaviour.name, behaviour.input_names, dict(behaviour.output.commands))

    def __enter__(self) -> RobotLinkEnv:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- connection --------------------------------------------------------------------------
    def _connect(self) -> None:
        cfg = self.config
        attempts = cfg.retries + 1
        error: OSError | None = None
        for attempt in range(attempts):
            if attempt:
                time.sleep(cfg.retry_delay)
            try:
                sock = socket.create_connection((cfg.host, cfg.port), timeout=cfg.connect_timeout)
            except socket.gaierror as failure:
                raise LinkError(f"{self.where}: cannot resolve host '{cfg.host}': {failure}",
                                hint="check environment.host") from None
            except OSError as failure:
                error = failure
                continue
            self._channel = Channel(sock)
            self._handshake()
            return
        reason = "refused" if isinstance(error, ConnectionRefusedError) else \
            "timed out" if isinstance(error, TimeoutError) else f"failed ({error})"
        raise LinkError(
            f"{self.where}: connection {reason} after {attempts} attempt"
            f"{'s' if attempts > 1 else ''}",
            hint=f"is the robot's bridge running and listening on port {cfg.port}? Check "
            "environment.host and environment.port; to try the link without a robot run "
            f"'flctool serve BEHAVIOUR.yaml --port {cfg.port}'")

    def _handshake(self) -> None:
        hello = {"type": "hello", "protocol": PROTOCOL, "version": VERSION,
                 "behaviour": self.behaviour_name, "observations": list(self.observation_names),
                 "commands": self.commands}
        welcome = self._request(hello, self.config.connect_timeout, "welcome",
                                hint="is the port that of a flctool robot link (and is no other "
                                "client connected)? raise environment.connect_timeout for a "
                                "slow bridge", limit=MAX_WELCOME_LINE)
        try:
            version = welcome.get("version")
            if welcome.get("protocol") != PROTOCOL or version != VERSION or isinstance(
                    version, bool):
                raise ProtocolError(
                    f"the robot speaks {printable(repr(welcome.get('protocol')), 60)} version "
                    f"{printable(repr(version), 20)}, not {PROTOCOL} {VERSION}")
            observations = string_list(welcome.get("observations"), "observations")
            commands = _command_table(welcome.get("commands"))
            max_steps = _bounded_int(welcome.get("max_steps"), "max_steps", MAX_WELCOME_STEPS)
            max_batch = _bounded_int(welcome.get("max_batch"), "max_batch", MAX_WELCOME_BATCH,
                                     optional=True)
            features = string_list(welcome.get("features", []), "features")
            robot = welcome.get("robot", "")
            if not isinstance(robot, str):
                raise ProtocolError("'robot' must be a string")
        except ProtocolError as error:
            raise self._fault(f"malformed welcome: {error}",
                              hint="see docs/robot-link.md") from None
        problems = self._fit_problems(observations, commands)
        if problems:
            self._abort("the behaviour does not fit the robot")
            raise SpecError(problems, f"{self.where} (robot '{printable(robot, 80)}')")
        self.robot = printable(robot, 200)
        self.max_steps, self.max_batch = max_steps, max_batch
        self.features = frozenset(features) & frozenset(FEATURES)
        self._columns = [observations.index(name) for name in self.observation_names]
        self._width = len(observations)

    def _fit_problems(self, observations: list[str], commands: dict[str, float]) -> list[Problem]:
        """The behaviour's inputs must be robot observations; its commands the robot's, with
        the same singletons (the robot interprets the crisp output by them)."""
        problems = [Problem(("inputs", name), f"the robot has no observation '{name}'."
                            f"{did_you_mean(name, observations)}",
                            f"name the inputs after the robot's observations: "
                            f"{', '.join(observations)}")
                    for name in self.observation_names if name not in observations]
        for name, value in self.commands.items():
            if name not in commands:
                problems.append(Problem(("output", "commands", name),
                                        f"the robot has no command '{name}'."
                                        f"{did_you_mean(name, list(commands))}",
                                        f"the robot's commands: {', '.join(commands)}"))
            elif commands[name] != value:
                problems.append(Problem(("output", "commands", name),
                                        f"singleton {value:g}, but the robot's is "
                                        f"{commands[name]:g}: the crisp output would mean "
                                        "another motion", f"set it to {commands[name]:g}"))
        extra = [name for name in commands if name not in self.commands]
        if extra:
            problems.append(Problem(("output", "commands"),
                                    f"the robot also has command{'s' if len(extra) > 1 else ''} "
                                    f"{', '.join(extra)}, which this behaviour lacks",
                                    "declare every command of the robot, with its singleton"))
        return problems

    def _live(self) -> Channel:
        if self._channel is None:
            self._connect()
        assert self._channel is not None  # _connect connects or raises
        return self._channel

    def _abort(self, reason: str) -> None:
        """Best effort: tell the robot to stop, then drop the connection."""
        channel, self._channel = self._channel, None
        self._batch = 0
        if channel is None:
            return
        # If the link is already gone, the robot side's watchdog must halt the robot.
        with contextlib.suppress(OSError, ValueError):
            channel.send({"type": "stop", "reason": reason},
                         min(_STOP_WAIT, self.config.step_timeout))
        channel.close()

    def _fault(self, what: str, hint: str) -> LinkError:
        """Safe stop; returns the LinkError to raise: ``what`` happened, ``hint`` says how to
        fix it."""
        self._abort(what)
        return LinkError(f"{self.where}: {what}; the robot was sent stop", hint=hint)

    def _request(self, message: dict[str, Any], timeout: float, expect: str,
                 hint: str = "", limit: int = MAX_LINE) -> dict[str, Any]:
        """Send one request, wait for its reply of type ``expect``; any fault stops the robot."""
        kind = message["type"]
        channel = self._channel
        if channel is None:
            raise LinkError(f"{self.where}: not connected", hint="reset to reconnect")
        try:
            channel.send(message, timeout)
            reply = channel.receive(timeout, limit=limit)
        except TimeoutError:
            raise self._fault(
                f"no reply to '{kind}' within {timeout:g} s",
                hint or f"is the bridge still running and not blocked? If the robot is just "
                f"slow, raise environment.{'reset' if kind == 'reset' else 'step'}_timeout") \
                from None
        except ProtocolError as error:
            raise self._fault(f"malformed reply to '{kind}': {error}",
                              "the bridge must follow docs/robot-link.md") from None
        except OSError as error:
            raise self._fault(f"connection lost during '{kind}': {error.strerror or error}",
                              "check the bridge's log and the network, then run again") \
                from None
        except KeyboardInterrupt:
            self._abort("interrupted")
            raise
        if reply is None:
            raise self._fault(f"the robot side closed the connection during '{kind}'",
                               "check the bridge's log; it may have crashed or timed out")
        if reply["type"] == "error":
            code = printable(reply.get("code", "?"), 40)
            raise self._fault(f"the robot side reported an error ({code}): "
                               f"{printable(reply.get('message', ''))}",
                               printable(reply.get("hint") or "see the bridge's log"))
        if reply["type"] != expect:
            raise self._fault(f"malformed reply to '{kind}': got a "
                               f"'{printable(reply['type'], 40)}' message",
                               "the bridge must answer each request with its reply, in order")
        return reply

    def _parse(self, kind: str, parse: Callable[[], T]) -> T:
        try:
            return parse()
        except ProtocolError as error:
            raise self._fault(f"malformed reply to '{kind}': {error}",
                              "the bridge must follow docs/robot-link.md") from None

    def _guarded(self, call: Callable[[], T]) -> T:
        """Run ``call``; if it fails for any reason but a LinkError (already handled), stop the
        robot first. FlcErrors keep their message; anything else becomes a LinkError."""
        try:
            return call()
        except LinkError:
            raise
        except KeyboardInterrupt:
            self._abort("interrupted")
            raise
        except FlcError as error:
            self._abort(str(error))
            raise
        except Exception as error:  # the robot must stop whatever went wrong
            raise self._fault(f"{type(error).__name__}: {printable(error)}",
                              "this is a bug; please report it with the message") from error

    # -- the protocol ------------------------------------------------------------------------
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Start one episode per seed on the robot side: (B,) -> observations (B, N), {}."""
        seeds = np.asarray(seeds).reshape(-1)
        if seeds.shape[0] < 1 or seeds.dtype.kind not in "iu":
            raise EnvError("reset needs at least one integer seed")
        if seeds.shape[0] * (self.max_steps + 1) > MAX_BATCH_STEPS:
            raise EnvError(f"{self.where}: {seeds.shape[0]:,} episodes of {self.max_steps:,} "
                           f"steps are more than the link's limit of {MAX_BATCH_STEPS:,} "
                           "episode steps per reset", hint="run fewer episodes at once")
        if self.max_batch is not None and seeds.shape[0] > self.max_batch:
            raise LinkError(f"{self.where}: the robot runs at most {self.max_batch} episode"
                            f"{'s' if self.max_batch > 1 else ''} at a time, asked for "
                            f"{seeds.shape[0]}", hint="run fewer episodes at once "
                            "(e.g. flctool evaluate --episodes 1)")
        return self._guarded(lambda: self._reset(seeds))

    def _reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        self._live()
        batch = seeds.shape[0]
        reply = self._request({"type": "reset", "seeds": seeds.tolist()},
                              self.config.reset_timeout, "reset")

        def parse() -> FloatArray:
            observations = float_array(reply.get("observations"), (batch, self._width),
                                       "observations")
            self._success = bool_array(reply.get("success", [False] * batch), batch, "success")
            return observations[:, self._columns]
        observations = self._parse("reset", parse)
        self._batch, self._steps = batch, 0
        self._ended = np.zeros(batch, dtype=bool)
        return observations, {}

    def step(self, actions: FloatArray) -> Step:
        """Send the crisp outputs ``actions (B,)``; returns the robot side's transition."""
        return self._guarded(lambda: self._step(actions))

    def _step(self, actions: FloatArray) -> Step:
        batch = self._batch
        if batch == 0:
            raise EnvError(f"{self.where}: step with no episode running",
                           hint="call reset(seeds) first (a fault or stop ends the episodes)")
        actions = np.asarray(actions, dtype=np.float64).reshape(-1)
        if actions.shape[0] != batch:
            raise EnvError(f"step got {actions.shape[0]} actions for {batch} episodes")
        if not np.isfinite(actions).all():
            raise EnvError("an action is NaN or infinite", hint="check the controller's output")
        if self._steps >= self.max_steps:
            raise self._overrun()
        reply = self._request({"type": "step", "actions": actions.tolist()},
                              self.config.step_timeout, "step")

        def parse() -> Step:
            observations = float_array(reply.get("observations"), (batch, self._width),
                                       "observations")
            rewards = float_array(reply.get("rewards"), (batch,), "rewards")
            terminated = bool_array(reply.get("terminated"), batch, "terminated")
            truncated = bool_array(reply.get("truncated"), batch, "truncated")
            self._success = bool_array(reply.get("success"), batch, "success")
            return Step(observations[:, self._columns], rewards, terminated, truncated)
        step = self._parse("step", parse)
        self._steps += 1
        self._ended |= step.terminated | step.truncated
        if self._steps >= self.max_steps and not self._ended.all():
            raise self._overrun()
        return step

    def _overrun(self) -> LinkError:
        """The robot side let an episode run past its own max_steps: stop it (a robot side
        that never ends an episode would otherwise keep ``learn`` running forever)."""
        running = np.flatnonzero(~self._ended)
        shown = ", ".join(str(i) for i in running[:5]) + (", ..." if len(running) > 5 else "")
        return self._fault(
            f"the robot side did not end episode{'s' if len(running) > 1 else ''} {shown} "
            f"after its max_steps = {self.max_steps} steps",
            "the bridge must report truncated: true at the step limit it announces "
            "(docs/robot-link.md)")

    def success(self) -> BoolArray:
        """(B,) success as the robot side last reported it (no round trip)."""
        success: BoolArray = self._success.copy()
        return success

    def episode_fitness(self, returns: FloatArray, lengths: NDArray[np.int64],
                        success: BoolArray) -> FloatArray:
        """The robot side's fitness of finished trials (a ``fitness`` request) if it offers
        one, else the undiscounted return."""
        returns = np.array(returns, dtype=np.float64).reshape(-1)
        if "fitness" not in self.features:
            return returns
        count = returns.shape[0]

        def ask() -> FloatArray:
            self._live()
            reply = self._request({"type": "fitness", "returns": returns.tolist(),
                                   "lengths": np.asarray(lengths).reshape(-1).tolist(),
                                   "success": np.asarray(success).reshape(-1).tolist()},
                                  self.config.step_timeout, "fitness")
            return self._parse("fitness", lambda: float_array(
                reply.get("fitness"), (count,), "fitness"))
        return self._guarded(ask)

    def trace_state(self) -> dict[str, FloatArray]:
        """The robot side's per-episode state (e.g. pose from a ceiling camera), each (B,);
        empty when the robot side does not offer the ``state`` feature."""
        batch = self._batch
        if "state" not in self.features or batch == 0:
            return {}

        def ask() -> dict[str, FloatArray]:
            reply = self._request({"type": "state"}, self.config.step_timeout, "state")

            def parse() -> dict[str, FloatArray]:
                state = reply.get("state")
                if not isinstance(state, dict):
                    raise ProtocolError("'state' must map names to lists of numbers")
                return {str(k): float_array(v, (batch,), f"state.{k}") for k, v in state.items()}
            return self._parse("state", parse)
        return self._guarded(ask)

    def close(self) -> None:
        """Stop the robot (waiting briefly for its acknowledgement) and disconnect."""
        channel = self._channel
        if channel is None:
            return
        try:
            channel.send({"type": "stop", "reason": "close"}, self.config.step_timeout)
            channel.receive(self.config.step_timeout)
        except (OSError, ProtocolError):
            pass  # closing anyway; the robot side stops when the connection drops
        finally:
            self._channel = None
            self._batch = 0
            channel.close()
