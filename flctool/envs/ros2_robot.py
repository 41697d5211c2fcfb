"""A simulator as a ROS 2 robot (``flctool serve --ros2``): the reference robot for the ``ros2``
adapter and the deployment node, and a way to try the ROS path before the real robot.

Topics, under the namespace (default ``/robot``)::

    <input>    std_msgs/Float64      one per observation of the simulator (e.g. ball_size, pan)
    status     std_msgs/String       running, success, failure or timeout, after every change
    reward     std_msgs/Float64      the step's reward
    odom       nav_msgs/Odometry     the robot's pose (m, yaw), when the simulator has one
    cmd_vel    geometry_msgs/Twist   subscribed: linear.x > 0 walks, turning by angular.z = the
                                     crisp output a; a zero Twist (the stop command) halts
    reset      std_msgs/Int64        subscribed: start an episode from this seed

The simulator steps once per walking command while an episode runs (a lockstep robot: each
command is one control period), then publishes every observation, the odometry, the reward and
the status. A halt, or a command while no episode runs, moves nothing and is not answered.
With ``auto_reset`` (for deployment nodes, which never reset) an episode starts at once and a
new one when one ends, from consecutive seeds, and while it waits for a command the robot
republishes its observations every :data:`HEARTBEAT` seconds, as a real robot's sensors do.
Values travel as float64, so a controller learned over this robot sees bit for bit what it
sees in process.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from flctool.behaviour.models import Behaviour
from flctool.behaviour.ros2 import Qos
from flctool.envs.base import BatchEnv
from flctool.errors import EnvError
from flctool.ros2.fields import message_class
from flctool.ros2.graph import RosGraph

#: s the robot waits, before answering a reset, for a subscriber on each topic it publishes
#: (a reply published before the client's subscription is matched would be lost) once one of
#: them has a subscriber: a client need not read every topic.
MATCH_WAIT = 2.0
#: s a robot reset by a client waits, before answering, for the first subscriber on any topic
#: it publishes: the client's subscriptions are discovered apart from its reset publisher, and
#: on a loaded machine seconds later.
CLIENT_WAIT = 30.0
#: s between republished observations while an auto-reset robot waits for a command.
HEARTBEAT = 0.02


class SimRobot:
    """Serves one simulator (any :class:`BatchEnv`, run B = 1) as ROS 2 topics."""

    def __init__(self, env: BatchEnv, namespace: str = "/robot", node: str = "flctool_sim",
                 auto_reset: bool = False, first_seed: int = 0,
                 log: Callable[[str], None] | None = None) -> None:
        self.env = env
        self.auto_reset = auto_reset
        self.next_seed = first_seed
        self.log = log or (lambda text: None)
        self.episodes = 0  # episodes ended
        self.outcomes: dict[str, int] = {"success": 0, "failure": 0, "timeout": 0}
        self.steps = 0
        self._running = False
        self._observation: Any = None
        self._published = 0.0  # time.monotonic() of the last observations published
        self._lock = threading.Lock()
        self.graph = RosGraph(node, namespace)
        # a deeper history than ROS 2's default 10, so that a recorder that falls behind for
        # a moment loses nothing
        qos = Qos(depth=100)
        prefix = namespace.rstrip("/") + "/" if namespace else ""
        self.float64 = message_class("std_msgs/Float64")
        self.string = message_class("std_msgs/String")
        self.odometry = message_class("nav_msgs/Odometry")
        self.observation_publishers = [
            self.graph.publisher(f"{prefix}{name}", "std_msgs/Float64", qos)
            for name in env.observation_names]
        self.status_publisher = self.graph.publisher(f"{prefix}status", "std_msgs/String", qos)
        self.reward_publisher = self.graph.publisher(f"{prefix}reward", "std_msgs/Float64", qos)
        self.odom_publisher = self.graph.publisher(f"{prefix}odom", "nav_msgs/Odometry", qos)
        node_ = self.graph.node
        node_.create_subscription(message_class("geometry_msgs/Twist"), f"{prefix}cmd_vel",
                                  self._on_command, 10)
        node_.create_subscription(message_class("std_msgs/Int64"), f"{prefix}reset",
                                  self._on_reset, 10)
        if auto_reset:
            node_.create_timer(HEARTBEAT, self._heartbeat)
        self.topics = [p.topic_name for p in (*self.observation_publishers,
                                              self.status_publisher, self.reward_publisher,
                                              self.odom_publisher)]

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, **options: Any) -> SimRobot:
        """Serve the simulator adapter of a behaviour's ``environment:`` section; for a
        composed behaviour, its world as the robot a deployment of it drives (every channel
        the tree reads, the parts' walking commands: :func:`composition_world`)."""
        from flctool.envs import make_env
        from flctool.envs.robot_server import composition_world

        env = behaviour.environment
        if env is not None and env.adapter in ("ros2", "robot-link"):
            raise EnvError(f"behaviour '{behaviour.name}' names a robot ({env.adapter}) as its "
                           "environment; serving needs a simulator",
                           hint="serve a behaviour with e.g. 'environment: {adapter: "
                           "ballchase-sim}'")
        if getattr(env, "compose", None):
            return cls(composition_world(behaviour), **options)
        return cls(make_env(behaviour, 1), **options)

    # -- callbacks (the executor's thread) ------------------------------------------------------
    def _on_reset(self, message: Any) -> None:
        self._start(int(message.data) % 2**63)

    def _start(self, seed: int) -> None:
        self._await_subscribers()
        with self._lock:
            observation = self.env.reset_one(seed)
            self._running = True
            self._publish(observation, 0.0, "running")

    def _on_command(self, message: Any) -> None:
        with self._lock:
            if not self._running or not message.linear.x > 0:
                return  # a halt, or a command between episodes: nothing moves
            action = float(message.angular.z)
            if not math.isfinite(action):
                return
            low, high = self.env.action_bounds
            observation, reward, terminated, truncated = self.env.step_one(
                min(max(action, low), high))
            self.steps += 1
            status = "running"
            if terminated or truncated:
                self._running = False
                self.episodes += 1
                status = ("success" if bool(self.env.success()[0]) else "failure") \
                    if terminated else "timeout"
                self.outcomes[status] += 1
                self.log(f"episode ended: {status}")
            self._publish(observation, reward, status)
        if not self._running and self.auto_reset:
            seed, self.next_seed = self.next_seed, self.next_seed + 1
            self._start(seed)

    def _heartbeat(self) -> None:
        with self._lock:
            if self._running and time.monotonic() - self._published >= HEARTBEAT:
                self._publish_observation(self._observation)

    def _await_subscribers(self) -> None:
        """Wait for the client's subscriptions before answering: a lockstep robot answers
        once, so its first reply must not go out before anyone listens. A deployment node
        (``auto_reset``) republishes its observations, so it waits only briefly."""
        publishers = [*self.observation_publishers, self.status_publisher, self.reward_publisher]
        if not self.auto_reset:
            self.graph.wait(lambda: any(p.get_subscription_count() > 0 for p in publishers),
                            CLIENT_WAIT, poll=0.01)
        self.graph.wait(lambda: all(p.get_subscription_count() > 0 for p in publishers),
                        MATCH_WAIT, poll=0.01)

    def _publish(self, observation: Any, reward: float, status: str) -> None:
        """Observations, odometry and reward, then the status (clients wait for all)."""
        self._publish_observation(observation)
        self.reward_publisher.publish(self.float64(data=float(reward)))
        self.status_publisher.publish(self.string(data=status))

    def _publish_observation(self, observation: Any) -> None:
        self._observation = observation
        self._published = time.monotonic()
        for publisher, value in zip(self.observation_publishers, observation.tolist(),
                                    strict=True):
            publisher.publish(self.float64(data=float(value)))
        state = self.env.trace_state()
        if "robot_x" in state:
            odometry = self.odometry()
            odometry.header.frame_id = "pitch"
            odometry.child_frame_id = "base_link"
            odometry.header.stamp = self.graph.node.get_clock().now().to_msg()
            position = odometry.pose.pose.position
            position.x = float(state["robot_x"][0]) / 1000.0
            position.y = float(state["robot_y"][0]) / 1000.0
            half = math.radians(float(state["robot_heading"][0])) / 2.0
            odometry.pose.pose.orientation.z = math.sin(half)
            odometry.pose.pose.orientation.w = math.cos(half)
            self.odom_publisher.publish(odometry)

    # -- lifecycle ------------------------------------------------------------------------------
    def start_episode(self) -> None:
        """Start the first episode now (``auto_reset``: the deployment node never resets)."""
        seed, self.next_seed = self.next_seed, self.next_seed + 1
        self._start(seed)

    def serve(self, episodes: int | None = None, stop: threading.Event | None = None) -> None:
        """Serve until ``episodes`` episodes have ended, ``stop`` is set, or Ctrl-C."""
        stop = stop or threading.Event()
        while not stop.is_set() and (episodes is None or self.episodes < episodes):
            stop.wait(0.05)

    def close(self) -> None:
        self.graph.close()
