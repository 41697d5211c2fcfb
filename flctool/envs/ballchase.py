"""The ballchase simulator of paper Sec. IV, a preset of the pitch world (envs/pitch.py).

A legged robot walks to a ball its head tracks. The ball does not move; the robot starts with
the ball ahead of its camera (``start.distance``, ``±start.bearing``), heading uniform, placed
uniformly where both fit on the pitch. Observations, in the behaviour's input order:

* ``ball_size`` -- apparent ball diameter as a fraction of the image width, pinhole camera:
  ``min(1, touch / d)`` with ``d`` the camera-to-ball distance and
  ``touch = diameter / (2 tan(fov / 2))`` the distance at which the ball fills the image;
  times ``(1 + sensor_noise.ball_size * z)``, clipped to [0, 1].
* ``pan`` -- the head pan angle in degrees = bearing of the ball from the camera, plus
  ``sensor_noise.pan * z``, clipped to the neck range.

Outcomes (delayed reward, as in the paper): reached (camera within ``goal.distance`` of the
ball and ``|pan| <= goal.bearing``) -> terminated, success, reward +1; lost (true pan beyond the
neck range, or the robot's centre off the pitch) -> terminated, reward -1; ``max_steps`` steps
-> truncated; reward 0 otherwise. In pitch-world terms: outcomes ``ball_reached``,
``ball_lost``, ``off_pitch``; a static ball; no obstacles.

The dynamics, the random draws (5 uniforms, then five standard normals per step) and both
code paths are the pitch world's.
"""

from __future__ import annotations

import math

from flctool.behaviour.environment import BALLCHASE_OBSERVATIONS, BallchaseSimConfig
from flctool.behaviour.models import Behaviour
from flctool.envs.pitch import PitchSim
from flctool.envs.pitch_world import OutcomeRule, Test, World
from flctool.errors import EnvError, Problem, SpecError

OBSERVATIONS = BALLCHASE_OBSERVATIONS
_RAD = math.pi / 180.0


def ballchase_world(config: BallchaseSimConfig) -> World:
    """The pitch world that is the ballchase simulator of this config."""
    half_x, half_y = config.pitch.length / 2.0, config.pitch.width / 2.0
    robot, goal = config.robot, config.goal
    return World(
        # a vote's output is a singleton, so it executes as the nearest command does
        max_steps=config.max_steps, nearest=config.action in ("nearest", "vote"),
        half_x=half_x, half_y=half_y, goal_half_width=0.0, robot_radius=robot.radius,
        neck_offset=robot.neck_offset, neck_range=robot.neck_range,
        touch=config.ball.diameter / (2.0 * math.tan(robot.camera_fov * _RAD / 2.0)),
        ball_radius=config.ball.diameter / 2.0, ball_movable=False, kick=0.0, friction=0.0,
        ball_ahead=True, start_distance=config.start.distance,
        start_bearing=config.start.bearing, ball_box=(0.0, 0.0, 0.0, 0.0),
        robot_box=(-half_x + robot.radius, half_x - robot.radius,
                   -half_y + robot.radius, half_y - robot.radius),
        heading_mid=0.0, heading_half=math.pi, obstacles=(), home=(0.0, 0.0),
        noise={"ball_size": config.sensor_noise.ball_size, "pan": config.sensor_noise.pan},
        outcomes=(OutcomeRule(Test("ball_reached", distance=goal.distance,
                                   bearing=goal.bearing * _RAD), 1.0, True),
                  OutcomeRule(Test("ball_lost"), -1.0, False),
                  OutcomeRule(Test("off_pitch"), -1.0, False)),
        timeout_reward=0.0, timeout_success=False)


class BallchaseSim(PitchSim):
    """B ballchase episodes; observations are the behaviour's inputs (ball_size and/or pan).

    Build it with :func:`flctool.envs.make_env` or :meth:`from_behaviour`.
    """

    def __init__(self, config: BallchaseSimConfig, commands: dict[str, float],
                 observation_names: tuple[str, ...] = OBSERVATIONS) -> None:
        _check_fit(config, commands, observation_names)
        self.config = config
        super().__init__(ballchase_world(config), commands, config.motion, config.noise,
                         observation_names, votes=config.action == "vote")

    @classmethod
    def from_behaviour(cls, behaviour: Behaviour, batch_size: int = 1) -> BallchaseSim:
        del batch_size  # B is the number of seeds given to reset
        config = behaviour.environment
        if not isinstance(config, BallchaseSimConfig):
            raise EnvError("the ballchase simulator needs 'environment: {adapter: ballchase-sim}'")
        return cls(config, dict(behaviour.output.commands), behaviour.input_names)


def _check_fit(config: BallchaseSimConfig, commands: dict[str, float],
               observation_names: tuple[str, ...]) -> None:
    """The behaviour's inputs and commands must be ones the simulator knows."""
    problems = config.fit_problems(observation_names, tuple(commands))
    if len(set(observation_names)) != len(observation_names):
        problems.append(Problem(("inputs",), "an observation is read by two inputs"))
    if problems:
        raise SpecError(problems)
