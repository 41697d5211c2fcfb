"""The robot link's wire protocol, shared by the client (:mod:`flctool.envs.robot_link`) and
the reference robot side (:mod:`flctool.envs.robot_server`): message framing, the bounds every
line is held to, and the checks that turn untrusted JSON into arrays.

The messages are specified in docs/robot-link.md.
"""

from __future__ import annotations

import contextlib
import json
import re
import socket
import time
from typing import Any

import numpy as np

from flctool.envs.base import BoolArray, FloatArray
from flctool.errors import ProtocolError as ProtocolError  # defined with the others

PROTOCOL = "flctool-robot-link"
VERSION = 1
#: Longest line either side accepts (a batch of 10^5 episodes of a few observations fits).
MAX_LINE = 64 * 1024 * 1024
#: Longest welcome a client accepts: names and singletons only.
MAX_WELCOME_LINE = 1024 * 1024
#: Largest ``max_steps`` and ``max_batch`` a welcome may announce, and most names in it.
MAX_WELCOME_STEPS = 1_000_000
MAX_WELCOME_BATCH = 100_000
MAX_WELCOME_NAMES = 10_000
#: Episodes x steps a reset may ask for: the reference server keeps per-step noise of every
#: episode, so this bounds its memory (about 1 GB at the limit).
MAX_BATCH_STEPS = 20_000_000
#: Optional requests a robot side may support, announced in its welcome.
FEATURES = ("fitness", "state")


def encode(message: dict[str, Any]) -> bytes:
    """One message as a line: compact JSON, UTF-8, ``\\n``-terminated. NaN and infinity are
    not JSON and raise ValueError."""
    return (json.dumps(message, allow_nan=False, separators=(",", ":")) + "\n").encode()


def decode(line: bytes) -> dict[str, Any]:
    """Parse one line (without its ``\\n``) into a message with a string ``type``."""
    try:
        message = json.loads(line.decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, ValueError) as error:
        shown = printable(line[:80].decode("utf-8", "replace"))
        raise ProtocolError(f"not a JSON line ({error}): {shown!r}") from None
    except RecursionError:
        raise ProtocolError("a JSON line nested too deep") from None
    if not isinstance(message, dict):
        raise ProtocolError(f"a message must be a JSON object, got {type(message).__name__}")
    if not isinstance(message.get("type"), str):
        raise ProtocolError("a message needs a string 'type'")
    return message


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not JSON")


# Terminal control: CSI / OSC escape sequences, then any other C0 / C1 control character.
_ESCAPES = re.compile(r"\x1b\[[0-?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)?"
                      r"|\x9b[0-?]*[ -/]*[@-~]")
_CONTROL = re.compile(r"[\x00-\x08\x0a-\x1f\x7f-\x9f]")


def printable(value: Any, limit: int = 300) -> str:
    """Text from the other side, safe to print: no terminal escape sequences or control
    characters (a robot's error text must not recolour or retitle the user's terminal), at
    most ``limit`` characters."""
    text = _CONTROL.sub("?", _ESCAPES.sub("", str(value)))
    return text if len(text) <= limit else text[:limit] + "..."


class Channel:
    """Newline-delimited JSON over a connected socket, with a deadline on every receive."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        # A request and its reply are small and alternate: without TCP_NODELAY, Nagle's
        # algorithm and delayed ACKs would add tens of milliseconds per step.
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._buffer = bytearray()

    def send(self, message: dict[str, Any], timeout: float) -> None:
        """Send one message; OSError (TimeoutError included) when the link fails."""
        self.sock.settimeout(timeout)
        self.sock.sendall(encode(message))

    def receive(self, timeout: float, poll: float | None = None,
                cancelled: Any = None, limit: int = MAX_LINE) -> dict[str, Any] | None:
        """The next message, or None when the peer closed the connection.

        Raises TimeoutError after ``timeout`` seconds, :class:`ProtocolError` on a malformed
        line. With ``poll``, waits in slices of that length and gives up (TimeoutError) as
        soon as ``cancelled()`` is true, so a server can shut down promptly.
        """
        deadline = time.monotonic() + timeout
        while True:
            end = self._buffer.find(b"\n")
            if end >= 0:
                line = bytes(self._buffer[:end])
                del self._buffer[: end + 1]
                return decode(line)
            if len(self._buffer) > limit:
                raise ProtocolError(f"a line longer than {limit:,} bytes")
            remaining = deadline - time.monotonic()
            if remaining <= 0 or (cancelled is not None and cancelled()):
                raise TimeoutError(f"no message within {timeout:g} s")
            self.sock.settimeout(remaining if poll is None else min(poll, remaining))
            try:
                chunk = self.sock.recv(1 << 16)
            except TimeoutError:
                continue
            if not chunk:
                if self._buffer:
                    raise ProtocolError("the connection closed in the middle of a message")
                return None
            self._buffer += chunk

    def close(self) -> None:
        with contextlib.suppress(OSError):  # already disconnected
            self.sock.shutdown(socket.SHUT_RDWR)
        self.sock.close()


# -- checking what arrives -------------------------------------------------------------------
def float_array(value: Any, shape: tuple[int, ...], what: str) -> FloatArray:
    """``value`` as a float64 array of ``shape`` with finite numbers only, or ProtocolError."""
    array = np.array(value) if isinstance(value, list) else np.array(None)
    if array.shape != shape or array.dtype.kind not in "iuf":
        raise ProtocolError(f"'{what}' must be numbers of shape {list(shape)}")
    result = np.asarray(array, dtype=np.float64)
    if not np.isfinite(result).all():
        raise ProtocolError(f"'{what}' has a non-finite number")
    return result


def bool_array(value: Any, size: int, what: str) -> BoolArray:
    """``value`` as a bool array of ``size`` entries (JSON true/false only), or ProtocolError."""
    array = np.array(value) if isinstance(value, list) else np.array(None)
    if array.shape != (size,) or array.dtype != np.bool_:
        raise ProtocolError(f"'{what}' must be {size} true/false values")
    result: BoolArray = array
    return result


def string_list(value: Any, what: str) -> list[str]:
    if not (isinstance(value, list) and all(isinstance(v, str) for v in value)):
        raise ProtocolError(f"'{what}' must be a list of strings")
    if len(value) > MAX_WELCOME_NAMES:
        raise ProtocolError(f"'{what}' has more than {MAX_WELCOME_NAMES:,} entries")
    return [printable(v, 200) for v in value]
