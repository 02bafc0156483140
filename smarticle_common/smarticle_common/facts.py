"""Robot facts, defined once: sizes, masses, servo, gait period, tag and binding radius of the paper's robots.

SI units (m, kg, s, rad). Every other module takes these values from here.

Body length: ``BL = W = w``, the width of the rigid central link along the body x axis (joint 1 to
joint 2): 5.4 cm for the ``small`` robot, 6.5 cm for the ``feedback`` robot. It is the only length of
a smarticle that does not change with its shape (``docs/sim_core.md`` says why it fits the paper).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .errors import RobotSpecError

#: Gait period T of the paper's square gait (s).
GAIT_PERIOD = 1.6
#: Servo top speed of the paper's robot: pi rad per 0.4 s quarter, the speed-controlled motors of the
#: authors' Chrono model (rad/s). At alpha_max = 90 deg the arm sweeps its 180 degree stroke in the whole
#: quarter, as the paper's gait does; amplitudes up to 90 deg fit a 1.6 s period. With it the converged
#: drift is reached at 1/480 s (7 % off); the earlier hobby-servo rating (0.1 s per 60 deg, 10.5 rad/s)
#: stops the arm 0.1 s early and its drift is 17 % off its limit at 1/480 s (docs/sim_calibration.md, P7).
SERVO_SPEED = math.pi / 0.4
#: The larger feedback robot's servo (not given in the paper): 0.1 s per 60 degrees, a hobby-servo rating.
FEEDBACK_SERVO_SPEED = math.radians(60.0) / 0.1
#: Side of each robot's ArUco tag, its outer black square (m); robot k carries tag k.
TAG_SIZE = 0.018
#: ArUco dictionary of the robots' tags.
TAG_DICTIONARY = 'DICT_4X4_50'
#: A pair counts as bound in a gait period in which its centre distance r falls below this many body
#: lengths (the batch calibration and the P6 lifetimes; the feedback robot's C2 glider sits at ~1.5 BL).
R_BIND_BL = 1.6


def require_positive(obj: Any, *names: str, error: type[ValueError] = RobotSpecError) -> None:
    """Raise ``error`` unless every named field of ``obj`` is a finite number > 0."""
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value <= 0.0:
            raise error(f'{type(obj).__name__}.{name} must be a finite number > 0, got {value!r}')


def require_non_negative(obj: Any, *names: str, error: type[ValueError] = RobotSpecError) -> None:
    """Raise ``error`` unless every named field of ``obj`` is a finite number >= 0."""
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value < 0.0:
            raise error(f'{type(obj).__name__}.{name} must be a finite number >= 0, got {value!r}')


@dataclass(frozen=True)
class RobotSpec:
    """Geometry, masses and servo of one smarticle (body box + two arm boxes)."""

    name: str
    body_width: float        # w, along body x (joint 1 to joint 2) = BL
    body_depth: float        # D, along the body normal y
    body_height: float       # z; the body box rests on the plate
    arm_length: float        # l, joint to tip
    arm_thickness: float     # along the arm's face normal
    arm_height: float        # z
    arm_clearance: float     # gap between the plate and the bottom of the arms
    total_mass: float
    arm_mass: float          # each arm
    servo_speed: float = SERVO_SPEED   # rad/s, the servo's top speed
    servo_torque: float = 0.15                 # N m, the servo's torque limit

    def __post_init__(self) -> None:
        require_positive(self, 'body_width', 'body_depth', 'body_height', 'arm_length', 'arm_thickness',
                  'arm_height', 'total_mass', 'arm_mass', 'servo_speed', 'servo_torque')
        require_non_negative(self, 'arm_clearance')
        if self.body_mass <= 0.0:
            raise RobotSpecError(f'RobotSpec.arm_mass: two arms of {self.arm_mass} kg leave nothing of '
                              f'total_mass {self.total_mass} kg for the body')
        if self.arm_clearance + self.arm_height > self.body_height:
            raise RobotSpecError(f'RobotSpec.arm_height: arms ({self.arm_clearance} + {self.arm_height} m) '
                              f'must fit within body_height {self.body_height} m')

    @property
    def body_mass(self) -> float:
        """Mass of the central link (kg)."""
        return self.total_mass - 2.0 * self.arm_mass

    @property
    def body_length(self) -> float:
        """BL = W = body width w (m), the length unit of pair coordinates."""
        return self.body_width

    @property
    def reach(self) -> float:
        """Largest distance of any robot point from the body centre (m), any shape."""
        return math.hypot(self.body_width / 2.0 + self.arm_length, self.body_depth / 2.0)


#: The paper's robot (34.8 g; arms 5.0 x 0.3 cm, body w = 5.4, D = 2.2 cm); heights and the mass split
#: from the authors' Chrono model (body 5.4 x 2.7 x 2.2 cm with 24.8 g, arms 5.0 x 2.3 x 0.3 cm with 5 g
#: each), arms 2 mm above the plate. Servo torque limit 0.05 N m, not the hobby servo's rating: a free
#: stroke needs ~0.006 N m (the drift is the same to the digit), while a stronger servo drives 5-17 N
#: contact forces in jams that tip robots (docs/history/physics_study.md section C, docs/sim_calibration.md).
SMALL = RobotSpec(name='small', body_width=0.054, body_depth=0.022, body_height=0.027,
                  arm_length=0.050, arm_thickness=0.003, arm_height=0.023, arm_clearance=0.002,
                  total_mass=0.0348, arm_mass=0.005, servo_torque=0.05)

#: The larger FSR robot of the paper's Fig. 5(a): measured there are its mass (175 g), arms (6.0 cm long,
#: 0.7 cm thick), body (6.5 cm wide, 3.5 cm deep) and FSRs on all four arm faces. Assumed, each named in
#: ``FEEDBACK_ASSUMED`` (docs/feedback.md, "The feedback robot as built"; sensitivity: docs/history/feedback.md):
#: the heights (body 4.0 cm, arms 3.4 cm with 3 mm clearance: the small robot's proportions, arms ~85 % of
#: the body height); the arm mass (20 g each, servo horn + arm + FSRs, body 135 g with two servos and
#: the board); the servo speed (``FEEDBACK_SERVO_SPEED``, a hobby-servo rating of 0.1 s / 60 deg); the
#: servo torque 0.3 N m, scaled from the small robot's 0.05 N m so that the largest arm-tip force per
#: robot weight is the same (tau / (l m g): 0.05 / (0.050 x 0.0348 x 9.81) = 2.9; 2.9 x 0.060 x 0.175 x
#: 9.81 = 0.30 N m); the small robot's 0.05 N m was lowered because stronger servos drive jams that tip
#: robots, and this keeps the same margin; 0.4 N m (the earlier value) was a guessed standard-servo stall
#: torque. The FSRs are modelled as covering each arm face whole (the sim's FSR force is the normal
#: contact force anywhere on the face): an FSR of the 400 series has a round active area of 5-13 mm
#: against a 60 x 34 mm face, so a real sensor misses touches off its pad.
FEEDBACK = RobotSpec(name='feedback', body_width=0.065, body_depth=0.035, body_height=0.040,
                     arm_length=0.060, arm_thickness=0.007, arm_height=0.034, arm_clearance=0.003,
                     total_mass=0.175, arm_mass=0.020, servo_speed=FEEDBACK_SERVO_SPEED, servo_torque=0.3)

#: The feedback robot's values that the paper does not give (field: value), see ``FEEDBACK``.
FEEDBACK_ASSUMED: dict[str, float] = {'body_height': FEEDBACK.body_height, 'arm_height': FEEDBACK.arm_height,
                                      'arm_clearance': FEEDBACK.arm_clearance, 'arm_mass': FEEDBACK.arm_mass,
                                      'servo_speed': FEEDBACK.servo_speed, 'servo_torque': FEEDBACK.servo_torque}

PRESETS: dict[str, RobotSpec] = {SMALL.name: SMALL, FEEDBACK.name: FEEDBACK}

#: BL = W of the paper's (small) robot (m): the default unit of pair distances.
BODY_LENGTH = SMALL.body_length


def robot_preset(name: str) -> RobotSpec:
    """Return the robot preset ``name`` (``small`` or ``feedback``) or raise RobotSpecError."""
    try:
        return PRESETS[name]
    except KeyError:
        raise RobotSpecError(f'robot preset {name!r} is unknown; choose one of {", ".join(PRESETS)}') from None
