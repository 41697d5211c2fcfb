"""The reference robot side of the robot link: any registered simulator adapter behind a socket.

Tests run the link against it, ``flctool serve`` starts it, and whoever writes a bridge for a
real robot can read it as a worked example of docs/robot-link.md (or reuse it: wrap the robot
in a :class:`~flctool.envs.base.BatchEnv` and pass ``on_stop`` to halt the motors).

One client controls the robot at a time (a robot has one body). Connections are accepted
and their handshakes read concurrently, each within ``hello_timeout``, at most
:data:`MAX_PENDING` at once (the oldest is dropped for a new one), so idle connections cannot
lock a client out; a client that says hello while another controls the robot waits up to
:data:`BUSY_WAIT` seconds, then gets a ``busy`` error. The controlling client is dropped when
it sends no ``reset`` or ``step`` for ``idle_timeout`` seconds (``stop``, ``state`` and
``fitness`` do not count), so neither can a client that only keeps sending ``stop``.

The server brings the robot to a **safe stop** -- ends the running episodes and calls
``on_stop`` -- when the client sends ``stop``, disconnects, makes no progress for
``idle_timeout`` seconds, sends a malformed or unexpected message, when the environment
raises, or when the server itself is interrupted (Ctrl-C; the controlling session runs in the
thread that called :meth:`serve`). Every fault is answered with an ``error`` message (when
the client can still hear it) and closes the connection. Requests are bounded: a reset's
seeds times the episode length (:data:`~flctool.envs.robot_protocol.MAX_BATCH_STEPS`), a fitness
request's episodes and lengths.
"""

from __future__ import annotations

import contextlib
import queue
import socket
import sys
import threading
import time
from collections import OrderedDict
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from flctool.behaviour.models import Behaviour
from flctool.envs.base import BatchEnv
from flctool.envs.robot_protocol import (
    FEATURES,
    MAX_BATCH_STEPS,
    MAX_WELCOME_BATCH,
    MAX_WELCOME_LINE,
    PROTOCOL,
    VERSION,
    Channel,
    ProtocolError,
    bool_array,
    float_array,
    printable,
)
from flctool.errors import EnvError, FlcError

if TYPE_CHECKING:
    from flctool.envs.pitch import PitchSim

_POLL = 0.1  # s; how often blocking waits look whether the server is shutting down
#: Connections whose handshake is still awaited; a new one beyond this drops the oldest.
MAX_PENDING = 64
#: s a client that said hello waits for the one controlling the robot to finish.
BUSY_WAIT = 2.0


def composition_world(behaviour: Behaviour) -> PitchSim:
    """A composition's world as its robot: the composing file's pitch world, observed through
    every channel the arbiter and its parts read (named by channel), driven by the parts'
    common walking commands, blended. The same episodes as the composition's for every seed
    (the same channels read, so the same noise table)."""
    from flctool.envs.pitch import PitchSim
    from flctool.envs.pitch_compose import common_commands, composition_parts
    from flctool.envs.pitch_drive import CommandDrive
    from flctool.envs.pitch_world import world_from_config

    config, _, drive, read = composition_parts(behaviour)
    commands = common_commands(drive)
    names = tuple(dict.fromkeys(read))
    walk = CommandDrive(commands, config.motion, config.noise, False)
    return PitchSim(world_from_config(config), commands, config.motion, config.noise, names,
                    names, False, drive=walk)


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
                 log: Callable[[str], None] | None = None,
                 hello_timeout: float = 10.0) -> None:
        if idle_timeout <= 0 or hello_timeout <= 0:
            raise EnvError(f"idle_timeout and hello_timeout must be > 0 s, got "
                           f"{idle_timeout:g} and {hello_timeout:g}")
        self.env = env
        self.commands = dict(commands)
        self.idle_timeout = idle_timeout
        self.hello_timeout = min(hello_timeout, idle_timeout)
        self.max_batch = max_batch
        self.robot = robot
        self.on_stop = on_stop
        self.log = log or (lambda text: None)
        #: Why the robot was brought to a safe stop, one entry per stop (tests read it).
        self.stops: list[str] = []
        self.connections = 0
        self._batch = 0  # episodes of the running reset; 0: stopped
        self._closing = threading.Event()
        self._pending: OrderedDict[int, Channel] = OrderedDict()  # awaiting their hello
        self._pending_lock = threading.Lock()
        self._free = threading.Semaphore(1)  # held while a client controls the robot
        self._admitted: queue.Queue[tuple[Channel, dict[str, Any], str]] = queue.Queue()
        try:
            self._listener = socket.create_server((host, port))
        except OSError as error:
            raise EnvError(f"cannot listen on {host}:{port}: {error.strerror or error}",
                           hint="choose another --port (0 picks a free one)") from None
        self._listener.settimeout(_POLL)
        self.host, self.port = self._listener.getsockname()[:2]

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, **options: Any) -> RobotServer:
        """Serve the simulator adapter named by the behaviour's ``environment:`` section; for a
        composed behaviour, its world as the robot a deployment of it drives
        (:func:`composition_world`)."""
        from flctool.envs import make_env

        env = behaviour.environment
        if env is not None and env.adapter == "robot-link":
            raise EnvError(f"behaviour '{behaviour.name}' names the robot link itself as its "
                           "environment; the server needs a simulator to serve",
                           hint="serve a behaviour with e.g. 'environment: {adapter: "
                           "ballchase-sim}'")
        if getattr(env, "compose", None):
            # a composition's robot only walks: the controller side runs arbiter and parts
            world = composition_world(behaviour)
            return cls(world, dict(zip(world.drive.order, world.drive.values.tolist(),
                                       strict=True)), **options)
        return cls(make_env(behaviour, 1), dict(behaviour.output.commands), **options)

    # -- lifecycle ---------------------------------------------------------------------------
    def serve(self, once: bool = False) -> None:
        """Serve clients, one controlling the robot at a time, until :meth:`close` (or after
        the first with ``once``). The controlling session runs in the calling thread."""
        doorman = threading.Thread(target=self._accept, daemon=True,
                                   name=f"robot-server-accept:{self.port}")
        doorman.start()
        try:
            while not self._closing.is_set():
                try:
                    channel, hello, who = self._admitted.get(timeout=_POLL)
                except queue.Empty:
                    continue
                try:
                    self._serve_client(channel, hello)
                finally:
                    self.log(f"client {who} disconnected")
                    self._free.release()
                if once:
                    break
        finally:
            self._closing.set()
            self._listener.close()
            doorman.join(timeout=1.0)
            with self._pending_lock:
                waiting = list(self._pending.values())
            for channel in waiting:
                channel.close()
            while not self._admitted.empty():
                self._admitted.get_nowait()[0].close()

    def _accept(self) -> None:
        """Accept connections and read each one's hello in a thread of its own."""
        while not self._closing.is_set():
            try:
                conn, peer = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return  # the listener was closed
            self.connections += 1
            who = f"{peer[0]}:{peer[1]}"
            self.log(f"client {who} connected")
            channel = Channel(conn)
            with self._pending_lock:
                self._pending[id(channel)] = channel
                oldest = (self._pending.popitem(last=False)[1]
                          if len(self._pending) > MAX_PENDING else None)
            if oldest is not None:  # idle connections must not fill the server
                self.log("too many connections without a handshake: dropped the oldest")
                oldest.close()
            threading.Thread(target=self._greet, args=(channel, who), daemon=True,
                             name=f"robot-server-hello:{who}").start()

    def _greet(self, channel: Channel, who: str) -> None:
        """Read a connection's hello; hand it to :meth:`serve` once the robot is free."""
        try:
            try:
                hello = channel.receive(self.hello_timeout, _POLL, self._closing.is_set,
                                        limit=MAX_WELCOME_LINE)
            except TimeoutError:
                raise _Fault("timeout", f"no hello within {self.hello_timeout:g} s",
                             "send hello right after connecting") from None
            except ProtocolError as error:
                raise _Fault("malformed", str(error), "see docs/robot-link.md") from None
            except OSError:
                hello = None
            if hello is None:
                channel.close()
                return
            self._check_hello(hello)
            if not self._free.acquire(timeout=BUSY_WAIT):
                raise _Fault("busy", "another client controls the robot",
                             "try again when it is done")
        except _Fault as fault:
            self._send_quietly(channel, {"type": "error", "code": fault.code,
                                         "message": str(fault), "hint": fault.hint})
            channel.close()
            return
        finally:
            with self._pending_lock:
                self._pending.pop(id(channel), None)
        if self._closing.is_set():
            self._free.release()
            channel.close()
            return
        self._admitted.put((channel, hello, who))

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
    def _serve_client(self, channel: Channel, hello: dict[str, Any]) -> None:
        try:
            self._converse(channel, hello)
        except _Fault as fault:
            self.safe_stop(f"{fault.code}: {fault}")
            self._send_quietly(channel, {"type": "error", "code": fault.code,
                                         "message": str(fault), "hint": fault.hint})
        except Exception as error:  # the robot must stop whatever went wrong
            self.safe_stop(f"server error: {printable(error)}")
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

    def _receive(self, channel: Channel, progress: float) -> dict[str, Any] | None:
        """The next message; a timeout ``idle_timeout`` s after the last ``progress``."""
        try:
            return channel.receive(max(progress + self.idle_timeout - time.monotonic(), 0.0),
                                   _POLL, self._closing.is_set)
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

    def _converse(self, channel: Channel, hello: dict[str, Any]) -> None:
        del hello  # checked when the client was admitted
        channel.send(self._welcome(), self.idle_timeout)
        handlers: dict[str, Callable[[dict[str, Any]], dict[str, Any]]] = {
            "reset": self._reset, "step": self._step, "fitness": self._fitness,
            "state": self._state, "stop": self._stop}
        progress = time.monotonic()  # the last reset or step: what keeps a client in control
        while True:
            message = self._receive(channel, progress)
            if message is None:
                if self._batch:
                    self.safe_stop("the client disconnected")
                return
            handler = handlers.get(message["type"])
            if handler is None:
                raise _Fault("unexpected", f"unknown message type "
                             f"'{printable(message['type'], 40)}'",
                             f"send one of: {', '.join(handlers)}")
            channel.send(handler(message), self.idle_timeout)
            if message["type"] in ("reset", "step"):
                progress = time.monotonic()

    def _check_hello(self, hello: dict[str, Any]) -> None:
        if hello["type"] != "hello":
            raise _Fault("unexpected", f"expected 'hello' first, got "
                         f"'{printable(hello['type'], 40)}'",
                         "start every connection with the handshake")
        if hello.get("protocol") != PROTOCOL or hello.get("version") != VERSION:
            raise _Fault("version", f"this server speaks {PROTOCOL} version {VERSION}, the "
                         f"client {printable(repr(hello.get('protocol')), 60)} version "
                         f"{printable(repr(hello.get('version')), 20)}",
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
        if len(seeds) * (self.env.max_steps + 1) > MAX_BATCH_STEPS:
            raise _Fault("batch", f"{len(seeds):,} episodes of {self.env.max_steps:,} steps "
                         f"are more than {MAX_BATCH_STEPS:,} episode steps per reset",
                         "reset fewer seeds at once")
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
        if count > MAX_WELCOME_BATCH:
            raise _Fault("batch", f"fitness of {count:,} episodes asked, more than "
                         f"{MAX_WELCOME_BATCH:,}", "ask for fewer at once")
        try:
            values = float_array(returns, (count,), "returns")
            lengths = float_array(message.get("lengths"), (count,), "lengths")
            success = bool_array(message.get("success"), count, "success")
        except ProtocolError as error:
            raise _Fault("malformed", str(error)) from None
        if ((lengths < 0) | (lengths > self.env.max_steps) | (lengths != np.round(lengths))).any():
            raise _Fault("malformed", f"'lengths' must be whole numbers of steps in "
                         f"[0, {self.env.max_steps}]")
        fitness = self.env.episode_fitness(values, lengths.astype(np.int64), success)
        return {"type": "fitness", "fitness": np.asarray(fitness, dtype=np.float64).tolist()}

    def _state(self, message: dict[str, Any]) -> dict[str, Any]:
        del message
        state = self.env.trace_state() if self._batch else {}
        return {"type": "state", "state": {k: v.tolist() for k, v in state.items()}}

    def _stop(self, message: dict[str, Any]) -> dict[str, Any]:
        reason = printable(message.get("reason", "no reason given"), 200)
        self.safe_stop(f"the client sent stop ({reason})")
        return {"type": "stop"}


def print_log(text: str) -> None:
    """The server's log on stderr (stdout carries the listening address)."""
    print(f"flctool serve: {text}", file=sys.stderr, flush=True)
