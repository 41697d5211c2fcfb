"""One ROS 2 node in a context of its own, spun by an executor in a background thread.

Subscriptions turn each message into a number at once (their reader) and keep the latest in an
:class:`Inbox` with its count and arrival time, under one condition variable, so that the
adapter and the deployment node wait on conditions with deadlines (:meth:`RosGraph.wait`)
instead of spinning. The context is private: several graphs (a robot and a controller in one
test) live in one process, and rclpy installs no signal handlers (flctool's CLI owns Ctrl-C).
"""

from __future__ import annotations

import atexit
import contextlib
import math
import threading
import time
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from flctool.behaviour.ros2 import Qos
from flctool.ros2 import import_rclpy
from flctool.ros2.fields import message_class, qos_profile

#: Graphs not closed yet: closed at interpreter exit, since an executor thread still spinning
#: then makes the C++ runtime abort the process (and its exit code is lost).
_LIVE: weakref.WeakSet[RosGraph] = weakref.WeakSet()


@atexit.register
def _close_live_graphs() -> None:
    for graph in list(_LIVE):
        graph.close()


@dataclass
class Inbox:
    """The latest value of one subscription: what it is, when it came, how many came."""

    topic: str
    value: float = math.nan
    text: str = ""
    count: int = 0
    time: float = -math.inf  # time.monotonic() of the latest message
    total: float = 0.0  # sum of the values since :meth:`take_total` (rewards)
    subscription: Any = field(default=None, repr=False)

    def take_total(self) -> float:
        total, self.total = self.total, 0.0
        return total

    def publishers(self) -> int:
        return int(self.subscription.get_publisher_count())


class RosGraph:
    """A node named ``name`` in ``namespace``, spinning until :meth:`close`."""

    def __init__(self, name: str, namespace: str = "") -> None:
        rclpy = import_rclpy()
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions

        self.condition = threading.Condition()
        self.context = Context()
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO)
        try:
            self.node = rclpy.create_node(name, namespace=namespace, context=self.context)
        except Exception:
            self.context.try_shutdown()
            raise
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True, name=f"ros2:{name}")
        self._closed = False
        self._thread.start()
        _LIVE.add(self)

    def _spin(self) -> None:
        # spin ends when the context shuts down (close); an executor error must not hang it
        with contextlib.suppress(Exception):
            self.executor.spin()

    def subscribe(self, topic: str, type_name: str, qos: Qos,
                  read: Callable[[Any], float] | None = None,
                  on_message: Callable[[Any], None] | None = None) -> Inbox:
        """Subscribe; each message's ``read(message)`` (or its ``data`` text for strings) goes
        to the returned inbox; ``on_message`` sees every message too."""
        inbox = Inbox(topic)

        def receive(message: Any) -> None:
            value = math.nan
            text = ""
            if read is not None:
                try:
                    value = float(read(message))
                except (ArithmeticError, ValueError, TypeError, IndexError):
                    value = math.nan  # a malformed message is a fault for the watchdog
            else:
                text = str(getattr(message, "data", ""))[:200]
            with self.condition:
                inbox.value, inbox.text = value, text
                inbox.total += value if math.isfinite(value) else 0.0
                inbox.count += 1
                inbox.time = time.monotonic()
                self.condition.notify_all()
            if on_message is not None:
                on_message(message)

        inbox.subscription = self.node.create_subscription(
            message_class(type_name), topic, receive, qos_profile(qos))
        return inbox

    def publisher(self, topic: str, type_name: str, qos: Qos) -> Any:
        return self.node.create_publisher(message_class(type_name), topic, qos_profile(qos))

    def client(self, service: str, type_name: str) -> Any:
        return self.node.create_client(message_class(type_name, "srv"), service)

    def wait(self, ready: Callable[[], bool], timeout: float, poll: float = 0.05) -> bool:
        """Whether ``ready()`` became true within ``timeout`` s (checked on every message,
        and every ``poll`` s for conditions no message signals, such as discovery)."""
        deadline = time.monotonic() + timeout
        with self.condition:
            while not ready():
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                self.condition.wait(min(remaining, poll))
        return True

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        # The executor's thread stops before the node it spins goes: destroying a node under
        # a spinning executor can crash the C++ runtime (a SIGSEGV, seen once in 7 CI runs).
        with contextlib.suppress(Exception):
            self.executor.shutdown(timeout_sec=5.0)
        self._thread.join(timeout=5.0)
        if self._thread.is_alive():  # still waiting: ending the context ends its spin
            with contextlib.suppress(Exception):
                self.context.try_shutdown()
            self._thread.join(timeout=5.0)
        with contextlib.suppress(Exception):
            self.node.destroy_node()
        with contextlib.suppress(Exception):
            self.context.try_shutdown()
