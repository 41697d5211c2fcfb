"""The reference robot side of the robot link: any registered simulator adapter behind a socket.

Tests run the link against it, ``flctool serve`` starts it, and whoever writes a bridge for a
real robot can read it as a worked example of docs/robot-link.md (or reuse it: wrap the robot
in a :class:`~flctool.envs.base.BatchEnv` and pass ``on_stop`` to halt the motors).

One client at a time (a robot has one body); others wait in the listen queue. The server
brings the robot to a **safe stop** -- ends the running episodes and calls ``on_stop`` --
when the client sends ``stop``, disconnects, sends nothing for ``idle_timeout`` seconds, sends
a malformed or unexpected message, when the environment raises, or when the server itself is
interrupted (Ctrl-C). Every fault is answered with an ``error`` message (when the client can
still hear it) and closes the connection.
"""

from __future__ import annotations

import contextlib
import socket
import sys
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from flctool.envs.base import BatchEnv
from flctool.envs.robot_link import (
    FEATURES,
    PROTOCOL,
    VERSION,
    Channel,
    ProtocolError,
    bool_array,
    float_array,
)
from flctool.errors import EnvError, FlcError
from flctool.spec.models import Behaviour

_POLL = 0.1  # s; how often blocking waits look whether the server is shutting down


class _Fault(Exception):
    """End the connection: send an error (code, message, hint), stop the robot."""

    def __init__(self, code: str, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.code = code
        self.hint = hint


class RobotServer:
    """Serves one :class:`BatchEnv` over the robot-link protocol.

    ``commands`` are the behaviour's command singletons (the env interprets the crisp output
    by them); ``max_batch`` limits the episodes per reset (1 for a real robot, None: any).
    """

    def __init__(self, env: BatchEnv, commands: dict[str, float], host: str = "127.0.0.1",
                 port: int = 0, idle_timeout: float = 60.0, max_batch: int | None = None,
                 robot: str = "flctool reference server",
                 on_stop: Callable[[str], None] | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        if idle_timeout <= 0:
            raise EnvError(f"idle_timeout must be > 0 s, got {idle_timeout:g}")
        self.env = env
        self.commands = dict(commands)
        self.idle_timeout = idle_timeout
        self.max_batch = max_batch
        self.robot = robot
        self.on_stop = on_stop
        self.log = log or (lambda text: None)
        #: Why the robot was brought to a safe stop, one entry per stop (tests read it).
        self.stops: list[str] = []
        self.connections = 0
        self._batch = 0  # episodes of the running reset; 0: stopped
        self._closing = threading.Event()
        try:
            self._listener = socket.create_server((host, port))
        except OSError as error:
            raise EnvError(f"cannot listen on {host}:{port}: {error.strerror or error}",
                           hint="choose another --port (0 picks a free one)") from None
        self._listener.settimeout(_POLL)
        self.host, self.port = self._listener.getsockname()[:2]

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, **options: Any) -> RobotServer:
        """Serve the simulator adapter named by the behaviour's ``environment:`` section."""
        from flctool.envs import make_env

        env = behaviour.environment
        if env is not None and env.adapter == "robot-link":
            raise EnvError(f"behaviour '{behaviour.name}' names the robot link itself as its "
                           "environment; the server needs a simulator to serve",
                           hint="serve a behaviour with e.g. 'environment: {adapter: "
                           "ballchase-sim}'")
        return cls(make_env(behaviour, 1), dict(behaviour.output.commands), **options)

    # -- lifecycle ---------------------------------------------------------------------------
    def serve(self, once: bool = False) -> None:
        """Accept clients one after another until :meth:`close` (or after one with ``once``)."""
        try:
            while not self._closing.is_set():
                try:
                    conn, peer = self._listener.accept()
                except TimeoutError:
                    continue
                except OSError:
                    break  # the listener was closed
                self.connections += 1
                self.log(f"client {peer[0]}:{peer[1]} connected")
                self._serve_client(Channel(conn))
                self.log(f"client {peer[0]}:{peer[1]} disconnected")
                if once:
                    break
        finally:
            self._listener.close()

    def serve_in_background(self, once: bool = False) -> threading.Thread:
        """:meth:`serve` in a daemon thread (tests, notebooks); stop it with :meth:`close`."""
        thread = threading.Thread(target=self.serve, args=(once,), daemon=True,
                                  name=f"robot-server:{self.port}")
        thread.start()
        return thread

    def close(self) -> None:
        """Stop accepting; the current client's connection ends within ``_POLL`` seconds."""
        self._closing.set()

    def safe_stop(self, reason: str) -> None:
        """Halt the robot: end the running episodes and call ``on_stop``."""
        self._batch = 0
        self.stops.append(reason)
        self.log(f"safe stop: {reason}")
        if self.on_stop is not None:
            self.on_stop(reason)

    # -- one client --------------------------------------------------------------------------
    def _serve_client(self, channel: Channel) -> None:
        try:
            self._converse(channel)
        except _Fault as fault:
            self.safe_stop(f"{fault.code}: {fault}")
            self._send_quietly(channel, {"type": "error", "code": fault.code,
                                         "message": str(fault), "hint": fault.hint})
        except Exception as error:  # the robot must stop whatever went wrong
            self.safe_stop(f"server error: {error}")
            hint = error.hint if isinstance(error, FlcError) else "see the server's log"
            self._send_quietly(channel, {"type": "error", "code": "robot",
                                         "message": f"{type(error).__name__}: {error}",
                                         "hint": hint})
        except BaseException:  # Ctrl-C, SystemExit: halt the motors before the server goes
            self.safe_stop("the server was interrupted")
            self._send_quietly(channel, {"type": "error", "code": "shutdown",
                                         "message": "the robot server was interrupted",
                                         "hint": "start the server again, then reconnect"})
            raise
        finally:
            channel.close()

    @staticmethod
    def _send_quietly(channel: Channel, message: dict[str, Any]) -> None:
        with contextlib.suppress(OSError, ValueError):  # the client may be gone
            channel.send(message, _POLL * 10)

    def _receive(self, channel: Channel) -> dict[str, Any] | None:
        try:
            return channel.receive(self.idle_timeout, _POLL, self._closing.is_set)
        except TimeoutError:
            if self._closing.is_set():
                raise _Fault("shutdown", "the server is shutting down") from None
            raise _Fault("timeout", f"no message for {self.idle_timeout:g} s",
                         "the client must keep stepping or send stop; raise the server's "
                         "--idle-timeout for slow clients") from None
        except ProtocolError as error:
            raise _Fault("malformed", str(error), "see docs/robot-link.md") from None
        except OSError as error:
            self.safe_stop(f"connection lost: {error}")
            return None

    def _converse(self, channel: Channel) -> None:
        hello = self._receive(channel)
        if hello is None:
            return
        self._check_hello(hello)
        channel.send(self._welcome(), self.idle_timeout)
        handlers: dict[str, Callable[[dict[str, Any]], dict[str, Any]]] = {
            "reset": self._reset, "step": self._step, "fitness": self._fitness,
            "state": self._state, "stop": self._stop}
        while True:
            message = self._receive(channel)
            if message is None:
                if self._batch:
                    self.safe_stop("the client disconnected")
                return
            handler = handlers.get(message["type"])
            if handler is None:
                raise _Fault("unexpected", f"unknown message type '{message['type']}'",
                             f"send one of: {', '.join(handlers)}")
            channel.send(handler(message), self.idle_timeout)

    def _check_hello(self, hello: dict[str, Any]) -> None:
        if hello["type"] != "hello":
            raise _Fault("unexpected", f"expected 'hello' first, got '{hello['type']}'",
                         "start every connection with the handshake")
        if hello.get("protocol") != PROTOCOL or hello.get("version") != VERSION:
            raise _Fault("version", f"this server speaks {PROTOCOL} version {VERSION}, the "
                         f"client {hello.get('protocol')!r} version {hello.get('version')!r}",
                         "use a flctool release that speaks the same version")

    def _welcome(self) -> dict[str, Any]:
        return {"type": "welcome", "protocol": PROTOCOL, "version": VERSION,
                "robot": self.robot, "observations": list(self.env.observation_names),
                "commands": self.commands, "max_steps": self.env.max_steps,
                "max_batch": self.max_batch, "features": list(FEATURES)}

    # -- requests ----------------------------------------------------------------------------
    def _reset(self, message: dict[str, Any]) -> dict[str, Any]:
        seeds = message.get("seeds")
        if not (isinstance(seeds, list) and seeds and all(
                isinstance(s, int) and not isinstance(s, bool) and 0 <= s < 2**63
                for s in seeds)):
            raise _Fault("malformed", "'seeds' must be a non-empty list of integers "
                         "in [0, 2^63)")
        if self.max_batch is not None and len(seeds) > self.max_batch:
            raise _Fault("batch", f"this robot runs at most {self.max_batch} episodes at a "
                         f"time, asked for {len(seeds)}", "reset fewer seeds at once")
        self._batch = 0
        observations, _ = self.env.reset(np.array(seeds, dtype=np.int64))
        self._batch = len(seeds)
        return {"type": "reset", "observations": observations.tolist(),
                "success": self.env.success().tolist()}

    def _step(self, message: dict[str, Any]) -> dict[str, Any]:
        if not self._batch:
            raise _Fault("unexpected", "step with no episode running (after a stop, or "
                         "before any reset)", "send reset first")
        try:
            actions = float_array(message.get("actions"), (self._batch,), "actions")
        except ProtocolError as error:
            raise _Fault("malformed", str(error)) from None
        out = self.env.step(actions)
        return {"type": "step", "observations": out.observations.tolist(),
                "rewards": out.rewards.tolist(), "terminated": out.terminated.tolist(),
                "truncated": out.truncated.tolist(), "success": self.env.success().tolist()}

    def _fitness(self, message: dict[str, Any]) -> dict[str, Any]:
        returns = message.get("returns")
        count = len(returns) if isinstance(returns, list) else -1
        try:
            values = float_array(returns, (count,), "returns")
            lengths = float_array(message.get("lengths"), (count,), "lengths")
            success = bool_array(message.get("success"), count, "success")
        except ProtocolError as error:
            raise _Fault("malformed", str(error)) from None
        fitness = self.env.episode_fitness(values, lengths.astype(np.int64), success)
        return {"type": "fitness", "fitness": np.asarray(fitness, dtype=np.float64).tolist()}

    def _state(self, message: dict[str, Any]) -> dict[str, Any]:
        del message
        state = self.env.trace_state() if self._batch else {}
        return {"type": "state", "state": {k: v.tolist() for k, v in state.items()}}

    def _stop(self, message: dict[str, Any]) -> dict[str, Any]:
        self.safe_stop(f"the client sent stop ({message.get('reason', 'no reason given')})")
        return {"type": "stop"}


def print_log(text: str) -> None:
    """The server's log on stderr (stdout carries the listening address)."""
    print(f"flctool serve: {text}", file=sys.stderr, flush=True)
