"""Logged robot data: record a session's topics as an MCAP bag, replay a controller over a
bag's inputs, and fit the simulator's motion and noise tables to logged commands and odometry
(the paper's "statistically modelled by measuring real robot motion", from the user's robot).

Bags are data, not an environment. They are read with rosbags (pure Python; ROS 1 ``.bag``,
ROS 2 sqlite3 and MCAP bags) and written as ROS 2 bags in MCAP storage, each message stamped
with its publisher's source time, so that a bag's order is the order in which things happened:
the observations a command was computed from come before the command. Reading is bounded
(:data:`MAX_MESSAGES`).
"""

from __future__ import annotations

import contextlib
import math
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from flctool.behaviour.ros2 import Qos, Ros2Config
from flctool.behaviour.ros2_messages import MESSAGES, normal_type, parse_path, ros_type
from flctool.errors import FlcError, MissingDependencyError
from flctool.ros2.fields import input_reader, nearest_command, pose_of, wrap_degrees

#: The recorder's node name: sessions do not take a recorder for the robot (ros2_env).
RECORDER_NODE = "flctool_record"
#: Most messages a bag may hold for replay and fit-sim (hostile files are bounded).
MAX_MESSAGES = 5_000_000


def _rosbags() -> Any:
    try:
        import rosbags.rosbag2
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise MissingDependencyError("rosbags", "ros2", "Reading and writing bags") from None
    return rosbags.rosbag2, get_typestore(Stores.ROS2_KILTED)


def session_topics(config: Ros2Config, extra: Sequence[tuple[str, str]] = ()
                   ) -> list[tuple[str, str]]:
    """(topic, type) of every topic a robot file maps (inputs, command, episode), then
    ``extra``, each once."""
    found: dict[str, str] = {}
    for source in config.inputs.values():
        found.setdefault(source.topic, source.type)
    found.setdefault(config.command.topic, config.command.type)
    episode = config.episode
    for watched in (episode.status, episode.reward):
        if watched is not None:
            found.setdefault(watched.topic, watched.type)
    if episode.reset is not None and episode.reset.topic is not None:
        found.setdefault(episode.reset.topic, episode.reset.type)
    for topic, type_name in extra:
        found.setdefault(topic, normal_type(type_name))
    return list(found.items())


class BagRecorder:
    """Subscribes to topics and writes every message, as published, into a new MCAP bag."""

    def __init__(self, path: Path, topics: list[tuple[str, str]], qos: Qos | None = None,
                 node: str = RECORDER_NODE) -> None:
        rosbag2, store = _rosbags()
        from rclpy.serialization import serialize_message  # noqa: F401 - rclpy is present

        from flctool.ros2.fields import message_class, qos_profile
        from flctool.ros2.graph import RosGraph

        if path.exists():
            raise FlcError(f"{path} exists", hint="record into a new bag (a folder)")
        self.path = path
        self.counts = dict.fromkeys((t for t, _ in topics), 0)
        self._lock = threading.Lock()
        self._writer = rosbag2.Writer(path, version=9,
                                      storage_plugin=rosbag2.StoragePlugin.MCAP)
        self._writer.open()
        self._open = True
        self.graph = RosGraph(node)
        self.subscriptions = []
        try:
            for topic, type_name in topics:
                if type_name not in MESSAGES:
                    raise FlcError(f"{topic}: unsupported message type {type_name}")
                connection = self._writer.add_connection(topic, ros_type(type_name),
                                                         typestore=store)
                self.subscriptions.append(self.graph.node.create_subscription(
                    message_class(type_name), topic, self._writes(topic, connection),
                    qos_profile(qos or Qos(depth=1000)), raw=True))
        except BaseException:
            self.close()
            raise

    def _writes(self, topic: str, connection: Any) -> Any:
        def write(data: bytes, info: Any) -> None:
            stamp = int(info["source_timestamp"]) or int(info["received_timestamp"])
            with self._lock:
                if self._open:
                    self._writer.write(connection, stamp, bytes(data))
                    self.counts[topic] += 1
        return write

    def publishers_found(self) -> bool:
        """Whether every recorded topic has a publisher (record only once they are matched)."""
        return all(s.get_publisher_count() > 0 for s in self.subscriptions)

    @property
    def messages(self) -> int:
        return sum(self.counts.values())

    def close(self) -> None:
        """Leave the graph, then finish the bag (its index and metadata)."""
        self.graph.close()
        with self._lock:
            if self._open:
                self._open = False
                self._writer.close()


def read_messages(path: Path, topics: list[str] | None = None
                  ) -> Iterator[tuple[str, int, Any]]:
    """(topic, time in ns, message) of a bag in time order, for ``topics`` (default all)."""
    _, store = _rosbags()
    from rosbags.highlevel import AnyReader

    if not path.exists():
        raise FlcError(f"{path}: no such bag", hint="give a bag folder, or an .mcap or .bag file")
    try:
        reader = AnyReader([path], default_typestore=store)
        reader.open()
    except Exception as error:  # rosbags' errors for a file that is not a bag
        raise FlcError(f"{path}: not a readable bag ({type(error).__name__}: {error})",
                       hint="give a ROS 2 bag (folder with metadata.yaml, or .mcap) or a "
                       "ROS 1 .bag") from None
    try:
        connections = [c for c in reader.connections if topics is None or c.topic in topics]
        for count, (connection, stamp, raw) in enumerate(reader.messages(connections)):
            if count >= MAX_MESSAGES:
                raise FlcError(f"{path}: more than {MAX_MESSAGES:,} messages",
                               hint="cut the bag to the session you need")
            yield connection.topic, stamp, reader.deserialize(raw, connection.msgtype)
    finally:
        with contextlib.suppress(Exception):
            reader.close()


def bag_topics(path: Path) -> dict[str, str]:
    """Topic -> message type (``pkg/Type``) of a bag."""
    _, store = _rosbags()
    from rosbags.highlevel import AnyReader

    with AnyReader([path], default_typestore=store) as reader:
        return {c.topic: normal_type(c.msgtype) for c in reader.connections}


# -- replay --------------------------------------------------------------------------------------
@dataclass
class ReplayRow:
    stamp: int  # ns, the recorded command's time
    time: float  # s since the bag's first message
    inputs: list[float]
    recorded: float  # the crisp output the command carried ((value - offset) / scale)
    replayed: float

    @property
    def difference(self) -> float:
        return self.replayed - self.recorded


def replay(path: Path, config: Ros2Config, input_names: tuple[str, ...],
           commands: dict[str, float], act: Any) -> list[ReplayRow]:
    """The controller ``act(values) -> a`` at each recorded command, from the latest inputs
    before it; beside the output the command carried.

    A deployed node reads its inputs at its tick and publishes a moment later, so an input
    published in between (within one control period before the command) may not have
    reached it: where the command is the output on the inputs just before that message and
    not on the latest, those are the inputs it was computed from, and the row has them."""
    sources = [config.inputs[name] for name in input_names]
    readers = {name: input_reader(source) for name, source in zip(input_names, sources,
                                                                    strict=True)}
    by_topic: dict[str, list[str]] = {}
    for name, source in zip(input_names, sources, strict=True):
        by_topic.setdefault(source.topic, []).append(name)
    command = config.command
    topics = [*by_topic, command.topic]

    def output(inputs: dict[str, float]) -> tuple[list[float], float]:
        """The inputs in the controller's order, and its output on them."""
        values = [inputs[name] for name in input_names]
        replayed = act(values)
        if command.type == "std_msgs/String":
            replayed = commands[nearest_command(commands, replayed)]
        return values, replayed

    latest: dict[str, float] = {}
    before: dict[str, float] = {}  # the inputs before the latest input message
    arrived = 0  # when the latest input message was published (ns)
    period = round(config.period * 1e9)
    rows: list[ReplayRow] = []
    start: int | None = None
    stop_text = command.stop
    for topic, stamp, message in read_messages(path, topics):
        start = stamp if start is None else start
        if topic in by_topic:
            before, arrived = dict(latest), stamp
            for name in by_topic[topic]:
                latest[name] = readers[name](message)
        if topic != command.topic or len(latest) < len(input_names):
            continue
        if command.type == "std_msgs/String":
            if message.data == stop_text or message.data not in commands:
                continue
            recorded = commands[message.data]
        else:
            assert command.field is not None
            if _is_stop(message, command.field, command.fixed):
                continue  # a stop command carries no output
            recorded = (float(_field(message, command.field)) - command.offset) / command.scale
        values, replayed = output(latest)
        if (replayed != recorded and stamp - arrived < period
                and len(before) == len(input_names)):
            earlier = output(before)  # the message may have come after the node's tick
            if earlier[1] == recorded:
                values, replayed = earlier
        rows.append(ReplayRow(stamp, (stamp - start) / 1e9, values, recorded, replayed))
    return rows


def write_replay_bag(source: Path, out: Path, command_topic: str,
                     rows: list[ReplayRow]) -> int:
    """A copy of the bag ``source`` (its ROS 2 CDR messages) with two topics beside the
    recorded commands, at each replayed command's time: ``COMMAND/replayed`` and
    ``COMMAND/difference`` (std_msgs/Float64). Returns the messages written."""
    rosbag2, store = _rosbags()
    from rosbags.highlevel import AnyReader

    if out.exists():
        raise FlcError(f"{out} exists", hint="write the replay into a new bag (a folder)")
    written = 0
    with AnyReader([source], default_typestore=store) as reader, rosbag2.Writer(
            out, version=9, storage_plugin=rosbag2.StoragePlugin.MCAP) as writer:
        copies = {}
        for connection in reader.connections:
            if connection.msgdef.format.name != "MSG" or not connection.digest.startswith(
                    "RIHS01_"):
                continue  # a ROS 1 bag's connections: not copied into a ROS 2 bag
            copies[connection.id] = writer.add_connection(
                connection.topic, connection.msgtype, msgdef=connection.msgdef.data,
                rihs01=connection.digest)
        replayed = writer.add_connection(f"{command_topic}/replayed", "std_msgs/msg/Float64",
                                         typestore=store)
        difference = writer.add_connection(f"{command_topic}/difference",
                                           "std_msgs/msg/Float64", typestore=store)
        float64 = store.types["std_msgs/msg/Float64"]
        for connection, stamp, raw in reader.messages(
                [c for c in reader.connections if c.id in copies]):
            writer.write(copies[connection.id], stamp, raw)
            written += 1
        for row in rows:
            for target, value in ((replayed, row.replayed), (difference, row.difference)):
                writer.write(target, row.stamp, store.serialize_cdr(float64(data=value),
                                                                    "std_msgs/msg/Float64"))
                written += 1
    return written


def _field(message: Any, path: str) -> Any:
    for name in parse_path(path).names:
        message = getattr(message, name)
    return message


def _is_stop(message: Any, output_field: str, fixed: dict[str, float]) -> bool:
    """A stop command: the output and every fixed field 0 where a fixed one is not."""
    if fixed:
        return all(float(_field(message, f)) == 0.0 for f in fixed) and any(
            v != 0.0 for v in fixed.values())
    return False


# -- fit-sim -------------------------------------------------------------------------------------
@dataclass
class CommandFit:
    """One command's motion per step: mean and standard deviation of forward (mm), sideways
    (mm) and rotation (deg), from ``steps`` logged steps."""

    steps: int
    mean: tuple[float, float, float]
    std: tuple[float, float, float]

    def standard_error(self) -> tuple[float, float, float]:
        n = max(self.steps, 1)
        return tuple(s / math.sqrt(n) for s in self.std)  # type: ignore[return-value]


def step_displacement(before: tuple[float, float, float], after: tuple[float, float, float],
                      unit: float) -> tuple[float, float, float]:
    """(forward, sideways in mm, rotation in deg) of one step between two poses (x, y in the
    pose's units, heading rad), in the frame of the heading after the step -- the
    simulator turns first, then moves (envs/pitch_dynamics.advance)."""
    x0, y0, h0 = before
    x1, y1, h1 = after
    dx, dy = (x1 - x0) * unit, (y1 - y0) * unit
    cos_h, sin_h = math.cos(h1), math.sin(h1)
    return (dx * cos_h + dy * sin_h, -dx * sin_h + dy * cos_h,
            wrap_degrees(math.degrees(h1 - h0)))


def fit_motion(path: Path, config: Ros2Config, commands: dict[str, float], odom_topic: str,
               unit: float = 1000.0) -> dict[str, CommandFit]:
    """Per command (the nearest singleton to each logged output): the motion table's mean
    and noise, from the odometry just before and just after each command.

    ``unit`` converts odometry lengths to mm (1000 for metres). Stop commands and commands
    with no odometry after them are left out.
    """
    types = bag_topics(path)
    if odom_topic not in types:
        raise FlcError(f"{path} has no topic {odom_topic}",
                       hint=f"its topics: {', '.join(sorted(types)) or 'none'}; name the "
                       "odometry with --odom")
    odom_type = types[odom_topic]
    command = config.command
    last_pose: tuple[float, float, float] | None = None
    # the command since the last pose, with that pose; None when there is none, or when two
    # came between two poses (then the step's displacement is not one command's)
    current: tuple[str, tuple[float, float, float]] | None = None
    commands_since_pose = 0
    samples: dict[str, list[tuple[float, float, float]]] = {name: [] for name in commands}
    for topic, _, message in read_messages(path, [odom_topic, command.topic]):
        if topic == odom_topic:
            pose = pose_of(message, odom_type)
            if current is not None and commands_since_pose == 1:
                name, before = current
                samples[name].append(step_displacement(before, pose, unit))
            last_pose, current, commands_since_pose = pose, None, 0
            continue
        sent = _command_name(message, config, commands)
        if sent is None:
            continue  # a stop: nothing moved
        commands_since_pose += 1
        if last_pose is not None:
            current = (sent, last_pose)
    fits = {}
    for name, rows in samples.items():
        if len(rows) < 2:
            continue
        columns = list(zip(*rows, strict=True))
        means = tuple(math.fsum(c) / len(c) for c in columns)
        stds = tuple(math.sqrt(math.fsum((v - m) ** 2 for v in c) / (len(c) - 1))
                     for c, m in zip(columns, means, strict=True))
        fits[name] = CommandFit(len(rows), means, stds)  # type: ignore[arg-type]
    return fits


def _command_name(message: Any, config: Ros2Config, commands: dict[str, float]) -> str | None:
    """The command a logged command message carried (the nearest singleton), None for a stop."""
    command = config.command
    if command.type == "std_msgs/String":
        return str(message.data) if message.data in commands else None
    assert command.field is not None
    if _is_stop(message, command.field, command.fixed):
        return None
    value = (float(_field(message, command.field)) - command.offset) / command.scale
    return nearest_command(commands, value)


def environment_section(fits: dict[str, CommandFit], base: dict[str, Any]) -> dict[str, Any]:
    """``base`` (a simulator's environment section) with the fitted motion and noise
    tables."""
    motion = {name: {"forward": round(f.mean[0], 3), "sideways": round(f.mean[1], 3),
                     "rotation": round(f.mean[2], 4)} for name, f in fits.items()}
    noise = {name: {"forward": round(f.std[0], 3), "sideways": round(f.std[1], 3),
                    "rotation": round(f.std[2], 4)} for name, f in fits.items()}
    return {**base, "motion": motion, "noise": noise}
