"""Deployment as a ROS 2 node (``flctool run CONTROLLER --ros2``): a compiled controller that
publishes a command at the control rate from the latest inputs, guarded by a watchdog.

:class:`Deployment` is the node's logic without a graph (tests drive it tick by tick):

* an input that is NaN, infinite or outside its ``valid`` range, stale (no message for
  ``stale_after`` s), never received, or whose publisher is gone -> the stop command, published
  at once (a bad value stops the robot from the message's own callback, not the next tick),
  and one clear log line saying which input and why;
* while stopped, the stop command every tick; when every input is good again, one log line and
  the controller drives again.

:class:`ControllerNode` wires it to the graph: a subscription per input, a timer at the
control rate, the command publisher; Ctrl-C (or the end of :meth:`ControllerNode.run`)
publishes stop before the node leaves. With an episode status topic it also counts the
episodes that ended and how.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from flctool.behaviour.ros2 import InputSource, Ros2Config
from flctool.ros2.fields import STATUSES, CommandWriter, input_reader, message_class, value_problem
from flctool.ros2.graph import Inbox, RosGraph


class Deployment:
    """One control tick at a time: inputs -> the crisp output, or None for stop."""

    def __init__(self, act: Callable[[list[float]], float], names: tuple[str, ...],
                 sources: list[InputSource], stale_bound: float,
                 log: Callable[[str], None]) -> None:
        self.act = act
        self.names = names
        self.sources = sources
        self.stale_bound = stale_bound
        self.log = log
        self.stopped = True
        self.reason = "no input received yet"
        self.stops = 0  # times the watchdog stopped the robot

    def problem(self, values: list[float], ages: list[float],
                publishers: list[int] | None = None) -> str | None:
        """Why the controller must not drive now, or None. ``ages``: s since each input's
        last message (inf: never); ``publishers``: each input topic's publisher count."""
        for i, (name, source) in enumerate(zip(self.names, self.sources, strict=True)):
            if publishers is not None and publishers[i] == 0:
                return f"input {name}: no publisher on {source.topic} (the robot's node is gone?)"
            if math.isinf(ages[i]):
                return f"input {name}: no message on {source.topic} yet"
            if ages[i] > self.stale_bound:
                return (f"input {name} is stale: no message on {source.topic} for "
                        f"{ages[i]:.3g} s (bound {self.stale_bound:g} s)")
            bad = value_problem(name, values[i], source)
            if bad:
                return bad
        return None

    def tick(self, values: list[float], ages: list[float],
             publishers: list[int] | None = None) -> float | None:
        """The action to publish, or None: publish stop."""
        problem = self.problem(values, ages, publishers)
        if problem is not None:
            self._stop(problem)
            return None
        if self.stopped:
            self.log(f"inputs good again: driving (stopped for: {self.reason})"
                     if self.stops else "inputs good: driving")
            self.stopped = False
        return self.act(values)

    def value_arrived(self, index: int, value: float) -> bool:
        """A message for input ``index``: whether it must stop the robot at once."""
        problem = value_problem(self.names[index], value, self.sources[index])
        if problem is None:
            return False
        self._stop(problem)
        return True

    def _stop(self, problem: str) -> None:
        if not self.stopped or problem.split(":")[0] != self.reason.split(":")[0]:
            self.log(f"stop: {problem}")
        if not self.stopped:
            self.stops += 1
        self.stopped, self.reason = True, problem


class ControllerNode:
    """A controller driving a ROS 2 robot at ``config.rate`` Hz."""

    def __init__(self, config: Ros2Config, input_names: tuple[str, ...],
                 commands: dict[str, float], act: Callable[[list[float]], float],
                 log: Callable[[str], None]) -> None:
        self.config = config
        self.log = log
        self.sources = [config.inputs[name] for name in input_names]
        self.deployment = Deployment(act, input_names, self.sources, config.stale_bound, log)
        self.graph = RosGraph(config.node, config.namespace)
        self.outcomes = dict.fromkeys(STATUSES[1:], 0)
        self.episodes = 0
        self.commands_sent = 0
        self.status_messages = 0  # every message of the episode status topic received
        #: time.monotonic() of every stop command published, for tests and logs.
        self.stop_times: list[float] = []
        self._ended = threading.Event()
        self._limit: int | None = None
        # A tick may be running on the executor's thread when run() ends: publishing under
        # this lock, and no tick once _leaving is set, makes the final stop the last command.
        self._publishing = threading.Lock()
        self._leaving = False
        try:
            self.inboxes: list[Inbox] = []
            for index, source in enumerate(self.sources):
                self.inboxes.append(self.graph.subscribe(
                    source.topic, source.type, source.qos, input_reader(source),
                    on_message=self._input_callback(index)))
            self.status: Inbox | None = None
            status = config.episode.status
            if status is not None:
                self.status = self.graph.subscribe(status.topic, status.type, status.qos,
                                                   on_message=self._on_status)
            self.publisher = self.graph.publisher(config.command.topic, config.command.type,
                                                  config.command.qos)
            self.writer = CommandWriter(config.command, commands,
                                        message_class(config.command.type))
            self.timer = self.graph.node.create_timer(config.period, self._tick)
        except BaseException:
            self.graph.close()
            raise

    def _input_callback(self, index: int) -> Callable[[Any], None]:
        def arrived(message: Any) -> None:
            del message
            if self.deployment.value_arrived(index, self.inboxes[index].value):
                self.publish_stop()
        return arrived

    def _on_status(self, message: Any) -> None:
        self.status_messages += 1
        text = str(message.data)
        if text in self.outcomes:
            self.outcomes[text] += 1
            self.episodes += 1
            self.log(f"episode {self.episodes} ended: {text}")
            if self._limit is not None and self.episodes >= self._limit:
                self._ended.set()

    def _tick(self) -> None:
        now = time.monotonic()
        with self.graph.condition:
            values = [i.value for i in self.inboxes]
            ages = [now - i.time for i in self.inboxes]
        publishers = [i.publishers() for i in self.inboxes]
        with self._publishing:
            if self._leaving:
                return
            action = self.deployment.tick(values, ages, publishers)
            if action is None:
                self._publish_stop()
            else:
                self.publisher.publish(self.writer.command(action))
                self.commands_sent += 1

    def publish_stop(self) -> None:
        with self._publishing:
            self._publish_stop()

    def _publish_stop(self) -> None:
        self.publisher.publish(self.writer.stop())
        self.stop_times.append(time.monotonic())

    def run(self, episodes: int | None = None, duration: float | None = None) -> None:
        """Drive until ``episodes`` episodes ended (status topic), ``duration`` s passed, or
        Ctrl-C; publishes stop before returning (or re-raising the interrupt)."""
        self._limit = episodes
        deadline = math.inf if duration is None else time.monotonic() + duration
        try:
            while not self._ended.is_set() and time.monotonic() < deadline:
                self._ended.wait(min(0.1, max(deadline - time.monotonic(), 0.0)))
        finally:
            self.timer.cancel()
            with self._publishing:  # after a tick in flight, and before none
                self._leaving = True
                self._publish_stop()
            self.log("stop published; leaving")

    def close(self) -> None:
        self.graph.close()
