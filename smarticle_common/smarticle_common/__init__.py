"""The common contract of the smarticle stack: what every other package agrees on.

Modules (no rclpy import in any of them but ``node``, the node helper):

* ``facts``: robot facts, defined once (``RobotSpec``, ``SMALL``, ``FEEDBACK``, ``GAIT_PERIOD``,
  ``SERVO_SPEED``, ``TAG_SIZE``, ``TAG_DICTIONARY``, ``R_BIND_BL``, ``BODY_LENGTH``);
* ``topics``: the topic contract (names, types, QoS kinds, frames, units), documented in docs/topics.md;
* ``gait``: the square gait core that the gait node and the sim's gait controller both run;
* ``pairs``: pair coordinates r, theta, phi (the one implementation; metres and radians);
* ``poses``: planar pose <-> quaternion conversions, a Bullet body's heading and tilt, tag corners;
* ``messages``: planar poses to and from ``geometry_msgs`` Pose and PoseArray;
* ``runs``: the one run format on disk (batch trials, the demo, ``smarticle-bag export --run``);
* ``commands``: the joint-command checks shared by the servo bridge and the sim bridge;
* ``params``: parameter tables (``ParamSpec``, ``ROBOT_ID_PARAM``) and their shipped YAML defaults;
* ``node``: the node helper (``read_config``, ``DiagnosticsPublisher``, ``resolve_robot_id``, ``run_node``,
  ``SigintShutsDown``, ``ended_by_signal``);
* ``launching``: the process launcher of tests, benchmarks and the demo;
* ``cli``: the command-line habits of every console script (``--version``, a closed pipe, the seed syntax);
* ``robot_model``: a preset's URDF from ``RobotSpec`` and the TF frames of a robot from its pose and arms;
* ``exports``: the lazy ``__all__`` of the other packages (``lazy_getattr``);
* ``errors``: ``CommonError`` and its subclasses.
"""

from __future__ import annotations

from .errors import CommonError, PairInputError, RobotSpecError
from .facts import (BODY_LENGTH, FEEDBACK, GAIT_PERIOD, PRESETS, R_BIND_BL, SERVO_SPEED, SMALL, TAG_DICTIONARY,
                    TAG_SIZE, RobotSpec, robot_preset)
from .gait import GaitCommand, GaitConfig, GaitError, SquareGait
from .pairs import PairCoordinates, one_pair, pair_coordinates, place_pair, wrap_2pi, wrap_pi

__all__ = [
    'BODY_LENGTH', 'FEEDBACK', 'GAIT_PERIOD', 'PRESETS', 'R_BIND_BL', 'SERVO_SPEED', 'SMALL', 'TAG_DICTIONARY',
    'TAG_SIZE', 'CommonError', 'GaitCommand', 'GaitConfig', 'GaitError', 'PairCoordinates', 'PairInputError',
    'RobotSpec', 'RobotSpecError', 'SquareGait', 'one_pair', 'pair_coordinates', 'place_pair', 'robot_preset',
    'wrap_2pi', 'wrap_pi',
]
