"""The ``ros2`` adapter: the :class:`~flctool.envs.base.BatchEnv` protocol over ROS 2 topics, so
``flctool learn`` and ``flctool evaluate`` run on a ROS 2 robot as on the simulator.

One episode at a time (``max_batch = 1``: a robot has one body). A step publishes the crisp
output on the command topic, then either waits one control period and reads the latest inputs
(``sync: rate``) or waits for a fresh message on every input (``sync: lockstep``, a simulator
that steps per command, such as ``flctool serve --ros2``). Episodes start by a reset topic or
service and end by the robot's status topic, the outcome rules over the inputs, or
``max_steps``.

**Safe stop.** On any fault -- an input that does not arrive in time or goes stale, a NaN or
a value outside its ``valid`` range, a publisher lost, a bad action, an interrupt -- the
adapter publishes the stop command at once, and raises :class:`~flctool.errors.LinkError`
saying what happened and how to fix it (a KeyboardInterrupt is re-raised after the stop).
Every wait is bounded by a timeout of the ``environment:`` section. The stop command is also
published when an episode ends and on :meth:`Ros2Env.close`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from flctool.behaviour.models import Behaviour
from flctool.behaviour.ros2 import Ros2Config
from flctool.envs.base import BatchEnv, BoolArray, FloatArray, Step
from flctool.envs.pitch import PitchSim, timed_fitness
from flctool.errors import EnvError, FlcError, LinkError, SpecError
from flctool.ros2.fields import CommandWriter, input_reader, message_class, outcome, value_problem
from flctool.ros2.graph import Inbox, RosGraph

T = TypeVar("T")


class Ros2Env(BatchEnv):
    """One episode at a time on a ROS 2 robot (or ``flctool serve --ros2``).

    Builds its node and waits (``startup_timeout``) until every topic it reads has a publisher
    and every topic it writes a subscriber, so a robot that is not there fails at once.
    """

    max_batch = 1

    def __init__(self, config: Ros2Config, behaviour_name: str,
                 input_names: tuple[str, ...], commands: dict[str, float]) -> None:
        problems = config.fit_problems(input_names, tuple(commands))
        if problems:
            raise SpecError(problems)
        self.config = config
        self.observation_names = input_names
        self.commands = dict(commands)
        values = sorted(self.commands.values())
        self.action_bounds = (float(values[0]), float(values[-1]))
        self.max_steps = config.episode.max_steps
        if config.episode.fitness == "timed":
            # the pitch world's bounds: the same intervals as learning in the simulator
            self.fitness_range = PitchSim.fitness_range
        self.where = f"ROS 2 robot (node {config.namespace}/{config.node})"
        self.graph = RosGraph(config.node, config.namespace)
        try:
            self._build(behaviour_name)
        except BaseException:
            self.graph.close()
            raise
        self._running = False
        self._steps = 0
        self._success = False
        self._tick = 0.0

    def _build(self, behaviour_name: str) -> None:
        del behaviour_name
        config, graph = self.config, self.graph
        self.sources = [config.inputs[name] for name in self.observation_names]
        self.inboxes = [graph.subscribe(s.topic, s.type, s.qos, input_reader(s))
                        for s in self.sources]
        episode = config.episode
        self.status: Inbox | None = None
        if episode.status is not None:
            self.status = graph.subscribe(episode.status.topic, episode.status.type,
                                          episode.status.qos)
        self.reward: Inbox | None = None
        if episode.reward is not None:
            reward = episode.reward
            self.reward = graph.subscribe(reward.topic, reward.type, reward.qos, input_reader(
                _reward_source(reward.topic, reward.type, reward.field)))
        self.command_publisher = graph.publisher(config.command.topic, config.command.type,
                                                 config.command.qos)
        self.writer = CommandWriter(config.command, self.commands,
                                    message_class(config.command.type))
        self.reset_publisher: Any = None
        self.reset_client: Any = None
        reset = episode.reset
        if reset is not None and reset.topic is not None:
            self.reset_publisher = graph.publisher(reset.topic, reset.type, reset.qos)
            self.reset_message = message_class(reset.type)
        elif reset is not None and reset.service is not None:
            self.reset_client = graph.client(reset.service, reset.type)
            self.reset_request = message_class(reset.type, "srv").Request
        self._wait_for_peers(config.startup_timeout, "startup")

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, batch_size: int = 1) -> Ros2Env:
        del batch_size  # one episode at a time
        config = behaviour.environment
        if not isinstance(config, Ros2Config):
            raise EnvError("the ros2 adapter needs 'environment: {adapter: ros2, ...}'")
        return cls(config, behaviour.name, behaviour.input_names,
                   dict(behaviour.output.commands))

    def __enter__(self) -> Ros2Env:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the graph -----------------------------------------------------------------------------
    def _subscriptions(self) -> list[Inbox]:
        return [*self.inboxes, *(i for i in (self.status, self.reward) if i is not None)]

    def _missing_peers(self) -> list[str]:
        """Topics without a publisher (read) or a subscriber (written), and a reset service
        that is not offered."""
        missing = [f"no publisher on {i.topic}" for i in self._subscriptions()
                   if i.publishers() == 0]
        writers = [self.command_publisher]
        if self.reset_publisher is not None:
            writers.append(self.reset_publisher)
        missing += [f"no subscriber on {publisher.topic_name}" for publisher in writers
                    if not self._robot_listens(publisher)]
        if self.reset_client is not None and not self.reset_client.service_is_ready():
            missing.append(f"no reset service {self.config.episode.reset.service}")  # type: ignore[union-attr]
        return missing

    def _robot_listens(self, publisher: Any) -> bool:
        """Whether a subscriber other than a recorder is on ``publisher``'s topic, and every
        subscriber the graph shows is matched (so a message published now reaches the robot:
        a recorder's subscription, matched first, must not pass for the robot's)."""
        from flctool.ros2.bags import RECORDER_NODE

        found = self.graph.node.get_subscriptions_info_by_topic(publisher.topic_name)
        return publisher.get_subscription_count() >= len(found) and any(
            info.node_name != RECORDER_NODE for info in found)

    def _wait_for_peers(self, timeout: float, when: str) -> None:
        if self.graph.wait(lambda: not self._missing_peers(), timeout):
            return
        missing = self._missing_peers()
        raise self._fault(
            f"{'; '.join(missing[:4])} after {timeout:g} s ({when})",
            "is the robot (its bridge, or 'flctool serve --ros2 SIM.yaml') running, with the "
            "same ROS_DOMAIN_ID and the topics of environment.inputs, command and episode? "
            "'ros2 topic list' shows what it offers; raise environment.startup_timeout if "
            "discovery is slow")

    def _stop(self) -> None:
        """Publish the stop command (best effort: this runs on every fault)."""
        self._running = False
        try:
            self.command_publisher.publish(self.writer.stop())
        except Exception:  # the context may be shutting down; nothing more can be sent
            return

    def _fault(self, what: str, hint: str) -> LinkError:
        self._stop()
        return LinkError(f"{self.where}: {what}; the stop command was published", hint=hint)

    def _guarded(self, call: Callable[[], T]) -> T:
        """Run ``call``; if it fails for any reason, stop the robot first."""
        try:
            return call()
        except LinkError:
            raise
        except KeyboardInterrupt:
            self._stop()
            raise
        except FlcError:
            self._stop()
            raise
        except Exception as error:  # the robot must stop whatever went wrong
            raise self._fault(f"{type(error).__name__}: {error}",
                              "this is a bug; please report it with the message") from error

    # -- the protocol ----------------------------------------------------------------------------
    def reset(self, seeds: NDArray[np.int64]) -> tuple[FloatArray, dict[str, Any]]:
        """Start one episode (B = 1); returns its observation (1, N) and {}."""
        seeds = np.asarray(seeds).reshape(-1)
        if seeds.shape[0] != 1 or seeds.dtype.kind not in "iu":
            raise EnvError(f"{self.where} runs one episode at a time: reset needs one integer "
                           f"seed, got {seeds.shape[0]}",
                           hint="run fewer episodes at once (e.g. flctool evaluate "
                           "--episodes 1 repeats them one by one)")
        return self._guarded(lambda: self._reset(int(seeds[0])))

    def _reset(self, seed: int) -> tuple[FloatArray, dict[str, Any]]:
        self._stop()
        self._wait_for_peers(self.config.startup_timeout, "before reset")
        counts = [i.count for i in self._subscriptions()]
        reset = self.config.episode.reset
        timeout = self.config.reset_timeout
        if self.reset_publisher is not None:
            message = self.reset_message()
            if hasattr(message, "data"):
                message.data = seed % (2**31 if "32" in reset.type else 2**63)  # type: ignore[union-attr]
            self.reset_publisher.publish(message)
        elif self.reset_client is not None:
            future = self.reset_client.call_async(self.reset_request())
            if not self.graph.wait(future.done, timeout):
                raise self._fault(f"the reset service gave no answer within {timeout:g} s",
                                  "is the robot's reset service working? raise "
                                  "environment.reset_timeout if it takes longer")
        fresh = self._fresh(counts, running=True)
        if not self.graph.wait(fresh, timeout):
            raise self._fault(self._late(counts, f"within {timeout:g} s of the reset"),
                              "is the robot publishing every input? A person placing the "
                              "robot may need a longer environment.reset_timeout")
        if self.reward is not None:
            self.reward.take_total()
        observation = self._observation()
        self._running, self._steps, self._success = True, 0, False
        self._tick = time.monotonic()
        return observation[None, :], {}

    def _fresh(self, counts: list[int], running: bool = False) -> Callable[[], bool]:
        """Whether every subscription has a message newer than ``counts`` (and, with
        ``running``, the status says running)."""
        inboxes = self._subscriptions()
        status = self.status

        def ready() -> bool:
            if any(i.count <= c for i, c in zip(inboxes, counts, strict=True)):
                return False
            return not (running and status is not None and status.text != "running")
        return ready

    def _late(self, counts: list[int], when: str) -> str:
        late = [i for i, c in zip(self._subscriptions(), counts, strict=True) if i.count <= c]
        lost = [i.topic for i in late if i.publishers() == 0]
        if lost:
            return f"the publisher of {', '.join(lost)} is gone"
        if not late and self.status is not None:
            return f"the status stayed '{self.status.text}' {when}, not running"
        return f"no fresh message on {', '.join(i.topic for i in late)} {when}"

    def _observation(self) -> FloatArray:
        """The inputs' latest values (N,); a fault when one is NaN, out of range or stale."""
        now = time.monotonic()
        values = []
        for name, source, inbox in zip(self.observation_names, self.sources, self.inboxes,
                                       strict=True):
            problem = value_problem(name, inbox.value, source)
            if problem is None and now - inbox.time > self.config.stale_bound:
                problem = (f"input {name} is stale: its last message on {source.topic} is "
                           f"{now - inbox.time:.3g} s old (bound {self.config.stale_bound:g} s)")
                if inbox.publishers() == 0:
                    problem += "; its publisher is gone"
            if problem is not None:
                raise self._fault(problem, "check the robot's sensors and its node; raise "
                                  "environment.stale_after for a slow sensor")
            values.append(inbox.value)
        return np.array(values, dtype=np.float64)

    def step(self, actions: FloatArray) -> Step:
        """Publish the crisp output ``actions (1,)``; returns the robot's transition."""
        return self._guarded(lambda: self._step(actions))

    def _step(self, actions: FloatArray) -> Step:
        if not self._running:
            raise EnvError(f"{self.where}: step with no episode running",
                           hint="call reset(seeds) first (a fault or the episode's end stops "
                           "the robot)")
        actions = np.asarray(actions, dtype=np.float64).reshape(-1)
        if actions.shape[0] != 1:
            raise EnvError(f"step got {actions.shape[0]} actions for 1 episode")
        action = float(actions[0])
        if not math.isfinite(action):
            raise EnvError("an action is NaN or infinite", hint="check the controller's output")
        counts = [i.count for i in self._subscriptions()]
        self.command_publisher.publish(self.writer.command(action))
        config = self.config
        if config.sync == "lockstep":
            if not self.graph.wait(self._fresh(counts), config.step_timeout):
                raise self._fault(self._late(counts, f"within {config.step_timeout:g} s of the "
                                             "command"),
                                  "is the robot still running? raise environment.step_timeout "
                                  "for a slow simulator")
        else:
            self._tick = max(self._tick + config.period, time.monotonic() - config.period)
            while (remaining := self._tick - time.monotonic()) > 0:
                time.sleep(remaining)
        observation = self._observation()
        self._steps += 1
        reward = self.reward.take_total() if self.reward is not None else 0.0
        terminated, truncated = self._ending(observation)
        if terminated is None:
            terminated = False
        elif not isinstance(terminated, bool):  # an outcome rule
            reward += terminated.reward
            self._success = terminated.success
            terminated = True
        if self._steps >= self.max_steps and not terminated:
            truncated = True
        if terminated or truncated:
            self._stop()
        return Step(observation[None, :], np.array([reward]), np.array([terminated]),
                    np.array([truncated]))

    def _ending(self, observation: FloatArray) -> tuple[Any, bool]:
        """(terminated: True, an OutcomeRule or None; truncated) from the status, then the
        outcome rules."""
        if self.status is not None:
            text = self.status.text
            if text == "success":
                self._success = True
                return True, False
            if text == "failure":
                return True, False
            if text == "timeout":
                return None, True
            if text != "running":
                raise self._fault(f"the status topic {self.status.topic} says '{text[:60]}'",
                                  "the status must be one of running, success, failure, "
                                  "timeout")
        values = dict(zip(self.observation_names, observation.tolist(), strict=True))
        return outcome(list(self.config.episode.outcomes), values), False

    def success(self) -> BoolArray:
        return np.array([self._success])

    def episode_fitness(self, returns: FloatArray, lengths: NDArray[np.int64],
                        success: BoolArray) -> FloatArray:
        """The undiscounted return, or the pitch world's timed fitness."""
        if self.config.episode.fitness == "timed":
            return timed_fitness(lengths, success, self.max_steps)
        return np.asarray(returns, dtype=np.float64)

    def close(self) -> None:
        """Publish stop, then leave the graph."""
        self._stop()
        self.graph.close()


def _reward_source(topic: str, type_name: str, field: str | None) -> Any:
    from flctool.behaviour.ros2 import InputSource

    return InputSource(topic=topic, type=type_name, field=field)
