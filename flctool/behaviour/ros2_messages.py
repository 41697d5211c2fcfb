"""The ROS 2 message types a behaviour file may name, and the field paths into them.

A closed table, written out here, so that a ``ros2`` environment is checked against the message
definitions when the file is loaded -- without rclpy, and without importing a module a file
names (the adapter imports only the packages of this table). The definitions are those of ROS 2
Kilted (``std_msgs``, ``geometry_msgs``, ``sensor_msgs``, ``nav_msgs``, ``std_srvs``); a test
checks them against rosbags' type store.

A field path names a numeric field: ``.data``, ``angular.z``, ``pose.pose.position.x``; its
last part may index an array (``ranges[3]``) or slice it (``ranges[0:90]``, then a reduction
``min``, ``max`` or ``mean`` makes one number of the slice).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_F64 = "float64"
_F32 = "float32"
_XYZ = {"x": _F64, "y": _F64, "z": _F64}
_HEADER = "std_msgs/Header"

#: Message type -> field -> type: a primitive, ``primitive[]`` (a sequence, or ``[N]`` fixed),
#: or another message type of the table.
MESSAGES: dict[str, dict[str, str]] = {
    **{f"std_msgs/{name}": {"data": kind} for name, kind in (
        ("Float32", _F32), ("Float64", _F64), ("Int8", "int8"), ("Int16", "int16"),
        ("Int32", "int32"), ("Int64", "int64"), ("UInt8", "uint8"), ("UInt16", "uint16"),
        ("UInt32", "uint32"), ("UInt64", "uint64"), ("Bool", "bool"), ("String", "string"))},
    "std_msgs/Empty": {},
    _HEADER: {"stamp": "builtin_interfaces/Time", "frame_id": "string"},
    "builtin_interfaces/Time": {"sec": "int32", "nanosec": "uint32"},
    "geometry_msgs/Vector3": dict(_XYZ),
    "geometry_msgs/Point": dict(_XYZ),
    "geometry_msgs/Quaternion": {**_XYZ, "w": _F64},
    "geometry_msgs/Pose": {"position": "geometry_msgs/Point",
                           "orientation": "geometry_msgs/Quaternion"},
    "geometry_msgs/Pose2D": {"x": _F64, "y": _F64, "theta": _F64},
    "geometry_msgs/PoseStamped": {"header": _HEADER, "pose": "geometry_msgs/Pose"},
    "geometry_msgs/PoseWithCovariance": {"pose": "geometry_msgs/Pose",
                                         "covariance": "float64[36]"},
    "geometry_msgs/Twist": {"linear": "geometry_msgs/Vector3",
                            "angular": "geometry_msgs/Vector3"},
    "geometry_msgs/TwistStamped": {"header": _HEADER, "twist": "geometry_msgs/Twist"},
    "geometry_msgs/TwistWithCovariance": {"twist": "geometry_msgs/Twist",
                                          "covariance": "float64[36]"},
    "sensor_msgs/LaserScan": {"header": _HEADER, **{k: _F32 for k in (
        "angle_min", "angle_max", "angle_increment", "time_increment", "scan_time",
        "range_min", "range_max")}, "ranges": "float32[]", "intensities": "float32[]"},
    "sensor_msgs/Range": {"header": _HEADER, "radiation_type": "uint8",
                          **{k: _F32 for k in ("field_of_view", "min_range", "max_range",
                                               "range", "variance")}},
    "nav_msgs/Odometry": {"header": _HEADER, "child_frame_id": "string",
                          "pose": "geometry_msgs/PoseWithCovariance",
                          "twist": "geometry_msgs/TwistWithCovariance"},
}
#: Service types a reset may call (their requests carry nothing).
SERVICES = ("std_srvs/Empty", "std_srvs/Trigger")
#: Where each type that carries a planar pose keeps it: (x, y) and the heading's source, a
#: quaternion's path or a yaw angle in radians.
POSES: dict[str, tuple[str, str, str]] = {
    "nav_msgs/Odometry": ("pose.pose.position.x", "pose.pose.position.y",
                          "pose.pose.orientation"),
    "geometry_msgs/PoseStamped": ("pose.position.x", "pose.position.y", "pose.orientation"),
    "geometry_msgs/Pose": ("position.x", "position.y", "orientation"),
    "geometry_msgs/Pose2D": ("x", "y", "theta"),
}
NUMERIC = ("float32", "float64", "int8", "int16", "int32", "int64", "uint8", "uint16",
           "uint32", "uint64", "bool")
REDUCTIONS = ("min", "max", "mean")

_PATH = re.compile(r"^\.?([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)*)(?:\[(\d{1,6})(?::(\d{1,6}))?\])?$")
_TYPE = re.compile(r"^([a-z][a-z0-9_]*)/(?:msg/|srv/)?([A-Z][A-Za-z0-9]*)$")


def normal_type(name: str) -> str:
    """``pkg/Type`` for ``pkg/Type`` or ``pkg/msg/Type`` (``pkg/srv/Type``); unchanged if it is
    neither."""
    match = _TYPE.match(name)
    return f"{match[1]}/{match[2]}" if match else name


def ros_type(name: str, kind: str = "msg") -> str:
    """The ``pkg/msg/Type`` (``pkg/srv/Type``) spelling that rclpy and bags use."""
    package, _, type_name = normal_type(name).partition("/")
    return f"{package}/{kind}/{type_name}"


@dataclass(frozen=True)
class FieldPath:
    """A parsed field path: the names from the message down to the field, and an index
    (``stop`` None) or a slice ``[start:stop]`` into it, if any."""

    names: tuple[str, ...]
    start: int | None = None
    stop: int | None = None

    @property
    def is_slice(self) -> bool:
        return self.stop is not None

    def __str__(self) -> str:
        text = "." + ".".join(self.names)
        if self.start is not None:
            text += f"[{self.start}" + (f":{self.stop}]" if self.stop is not None else "]")
        return text


def parse_path(text: str) -> FieldPath:
    """``.a.b[i:j]`` as a :class:`FieldPath`; ValueError saying the grammar when it is not."""
    match = _PATH.match(text.strip())
    if match is None:
        raise ValueError(f"'{text}' is not a field path: write names separated by dots, e.g. "
                         "'.data', 'angular.z', 'ranges[0:90]'")
    start = None if match[2] is None else int(match[2])
    stop = None if match[3] is None else int(match[3])
    if start is not None and stop is not None and stop <= start:
        raise ValueError(f"'{text}': the slice [{start}:{stop}] is empty; write [start:stop] "
                         "with start < stop")
    return FieldPath(tuple(match[1].split(".")), start, stop)


def message_problem(type_name: str) -> str | None:
    """Why ``type_name`` is not a message type of the table, or None."""
    if normal_type(type_name) in MESSAGES:
        return None
    from flctool.registry import did_you_mean

    known = sorted(MESSAGES)
    return (f"unknown message type '{type_name}'.{did_you_mean(normal_type(type_name), known)}"
            f" Supported: {', '.join(known)}")


def field_type(type_name: str, path: FieldPath) -> str:
    """The type the path leads to (an array's element type when indexed or sliced);
    ValueError naming the first part that does not exist, or an index on a non-array."""
    current = normal_type(type_name)
    walked = ""
    for name in path.names:
        fields = MESSAGES.get(current)
        if fields is None:
            raise ValueError(f"'{walked}' is a {current}, which has no fields")
        if name not in fields:
            from flctool.registry import did_you_mean

            raise ValueError(f"{current} has no field '{name}'."
                             f"{did_you_mean(name, list(fields))} Its fields: "
                             f"{', '.join(fields) or 'none'}")
        current = fields[name]
        walked += "." + name
    if path.start is None:
        if current.endswith("]"):
            raise ValueError(f"'{walked}' is an array ({current}): index it ('{walked}[0]') "
                             "or slice it with a reduction ('[0:10]' and min, max or mean)")
        return current
    if not current.endswith("]"):
        raise ValueError(f"'{walked}' is a {current}, not an array: it cannot be indexed")
    element, _, size = current[:-1].partition("[")
    limit = path.stop if path.stop is not None else path.start + 1
    if size and limit > int(size):
        raise ValueError(f"'{walked}' has {size} elements; [{path.start}"
                         f"{':' + str(path.stop) if path.stop is not None else ''}] is beyond")
    return element


def numeric_problem(type_name: str, path: FieldPath) -> str | None:
    """Why ``path`` in ``type_name`` is not one number (or a slice of numbers), or None."""
    try:
        leaf = field_type(type_name, path)
    except ValueError as error:
        return str(error)
    if leaf not in NUMERIC:
        example = _numeric_field(leaf) if leaf in MESSAGES else ""
        return (f"'{path}' is a {leaf}, not a number: name a numeric field"
                + (f" (e.g. '{path}.{example}')" if example else ""))
    return None


def _numeric_field(type_name: str) -> str:
    """The path of the first numeric field inside ``type_name``, or ''."""
    for name, kind in MESSAGES[type_name].items():
        if kind in NUMERIC:
            return name
        if kind in MESSAGES and (inner := _numeric_field(kind)):
            return f"{name}.{inner}"
    return ""
