"""The smarticle square gait (paper Fig. 1(b)): a pure, clock-agnostic state machine.

Convention (drawn in docs/gait.md):

* Body frame: x along the body from joint 1 to joint 2, y = the body normal (the robot's heading).
  Arm 1 hangs on the -x end, arm 2 on the +x end.
* ``alpha_i = 0``: arm i straight, in line with the body. ``alpha_i > 0``: the arm's tip turned
  toward +y (the normal side). Both arms at ``+alpha_max`` make a U that opens toward +y.
* Corners, visited in this order (counter-clockwise in the (alpha1, alpha2) plane)::

      c0 = (+a, +a) -> c1 = (-a, +a) -> c2 = (-a, -a) -> c3 = (+a, -a) -> c0

  Quarter q of a period moves one arm only, from c_q to c_(q+1): arm 1 in quarters 0 and 2, arm 2
  in quarters 1 and 3, at most at the servo speed, then holds until the quarter ends.
* Gait time ``tau = (t - t_start) / T + phase`` counts periods; a robot with phase 0 is at c0 at the
  shared start time, and the one-arm move of quarter 0 (arm 1, + to -) begins there.
* Halt: both arms hold where they are now. At the start of the next period (the next whole tau) the
  gait resumes with quarter 0; every move starts from the arm's held position toward its next corner.

Times are plain seconds from any clock (wall or simulated) and must not go backwards.
"""

from __future__ import annotations

import math
import dataclasses
from dataclasses import dataclass

from .errors import CommonError
from .facts import GAIT_PERIOD, SERVO_SPEED

#: Arm index moved in each quarter of the period.
MOVING_ARM: tuple[int, int, int, int] = (0, 1, 0, 1)
#: Corner signs (alpha1, alpha2) in traversal order.
CORNER_SIGNS: tuple[tuple[int, int], ...] = ((1, 1), (-1, 1), (-1, -1), (1, -1))

#: Clock tolerance (s) of every caller of ``SquareGait.command``: a tick whose time lands on a quarter
#: boundary up to floating-point rounding belongs to the new quarter, so callers ask for ``t + TIME_EPS``.
#: The batch runner and the gait node use the same value, so the simulation's batch and ROS paths switch
#: quarters at the same tick.
TIME_EPS = 1e-9

ALPHA_MAX_RANGE_DEG = (5.0, 120.0)

#: Quarter boundaries ``SquareGait`` crosses one by one before it jumps: a halt resumes at the next period
#: boundary (at most 4 quarters on), a new amplitude takes over at the next one, and two more quarters put both
#: arms on their corners.
_STEPPED_BOUNDARIES = 8


class GaitError(CommonError):
    """An invalid gait setting or call."""


@dataclass(frozen=True)
class GaitConfig:
    """Square-gait settings, SI units (radians, seconds)."""

    alpha_max: float = math.radians(90.0)
    period: float = GAIT_PERIOD
    servo_speed: float = SERVO_SPEED
    phase: float = 0.0

    def __post_init__(self) -> None:
        lo, hi = (math.radians(v) for v in ALPHA_MAX_RANGE_DEG)
        if not (math.isfinite(self.alpha_max) and lo - 1e-12 <= self.alpha_max <= hi + 1e-12):
            raise GaitError(f'alpha_max must be {ALPHA_MAX_RANGE_DEG[0]:g} to {ALPHA_MAX_RANGE_DEG[1]:g} '
                            f'degrees, got {math.degrees(self.alpha_max):g}')
        if not (math.isfinite(self.period) and self.period > 0.0):
            raise GaitError(f'period must be a positive number of seconds, got {self.period!r}')
        if not (math.isfinite(self.servo_speed) and self.servo_speed > 0.0):
            raise GaitError(f'servo_speed must be positive (rad/s), got {self.servo_speed!r}')
        if not (math.isfinite(self.phase) and 0.0 <= self.phase < 1.0):
            raise GaitError(f'phase must be a fraction of a period in [0, 1), got {self.phase!r}')
        stroke_time = 2.0 * self.alpha_max / self.servo_speed   # at least a quarter period at slowest_servo()
        if stroke_time > self.period / 4.0 + 1e-9:
            raise GaitError(
                f'a {math.degrees(2 * self.alpha_max):g} degree stroke at {self.servo_speed:g} rad/s takes '
                f'{stroke_time:.3f} s, longer than a quarter period ({self.period / 4:.3f} s): '
                'raise servo_speed or period, or lower alpha_max')

    @classmethod
    def from_degrees(cls, alpha_max_deg: float, period: float = GAIT_PERIOD,
                     servo_speed: float = SERVO_SPEED, phase: float = 0.0) -> GaitConfig:
        """Build a config with the amplitude given in degrees."""
        return cls(math.radians(alpha_max_deg), period, servo_speed, phase)

    def corner(self, index: int) -> tuple[float, float]:
        """Return corner ``index`` (0..3) as (alpha1, alpha2) in radians."""
        s1, s2 = CORNER_SIGNS[index % 4]
        return (s1 * self.alpha_max, s2 * self.alpha_max)


@dataclass(frozen=True)
class GaitCommand:
    """What the gait asks of the servos at one instant."""

    targets: tuple[float, float]     # commanded arm angles (rad): the corner being approached
    positions: tuple[float, float]   # reference arm angles now (rad), following the speed limit
    speed: float                     # servo speed limit (rad/s)
    started: bool
    halted: bool
    period_index: int                # whole periods of gait time (-1 before the start)
    quarter: int                     # quarter of the period (0..3)


class SquareGait:
    """Square-gait state machine for one robot; feed it times from one clock, in order."""

    def __init__(self, config: GaitConfig) -> None:
        self.config = config
        self._start_time: float | None = None
        self._pending: GaitConfig | None = None
        self._reset()

    def _reset(self) -> None:
        phase = self.config.phase
        self._quarter_count = math.floor(4.0 * phase)          # global quarter number at _tau_event
        self._tau_event = self._quarter_count / 4.0
        self._pos0 = self.config.corner(self._quarter_count % 4)
        self._halted = False
        self._resume_tau = 0.0
        self._last_tau = phase
        self._start_pose = self._position(phase)

    @property
    def start_time(self) -> float | None:
        """The shared start time (s), or None before a start."""
        return self._start_time

    @property
    def pending(self) -> GaitConfig | None:
        """A config waiting for the next period boundary (``set_alpha_max``), or None."""
        return self._pending

    def set_alpha_max(self, alpha_max: float) -> None:
        """Change the amplitude (rad) from the next period boundary of gait time on (at once before the start).

        The arms finish the current period on the old square and then head for the corners of the new one,
        so the change never jumps. GaitError (nothing changes) if the amplitude is out of range or its
        stroke no longer fits a quarter period at the servo speed.
        """
        config = dataclasses.replace(self.config, alpha_max=alpha_max)    # checked by GaitConfig
        if self._start_time is None:
            self.config, self._pending = config, None
            self._reset()
        else:
            self._pending = config

    @property
    def halted(self) -> bool:
        """True while the arms hold after a halt."""
        return self._halted

    def start(self, t0: float) -> None:
        """(Re)start the gait at time ``t0``; a new start resets any halt."""
        if not math.isfinite(t0):
            raise GaitError(f'start time must be finite, got {t0!r}')
        self._start_time = float(t0)
        if self._pending is not None:
            self.config, self._pending = self._pending, None
        self._reset()

    def gait_time(self, t: float) -> float:
        """Return the gait time tau (in periods) at clock time ``t``."""
        if self._start_time is None:
            return self.config.phase
        return max(t - self._start_time, 0.0) / self.config.period + self.config.phase

    def halt(self, t: float) -> bool:
        """Hold the arms at time ``t``; return False if the gait was not running or already halted."""
        if self._start_time is None or t < self._start_time or self._halted:
            return False
        tau = self._advance(t)
        self._pos0 = self._position(tau)
        self._tau_event = tau
        self._halted = True
        self._resume_tau = math.floor(tau) + 1.0
        return True

    def command(self, t: float) -> GaitCommand:
        """Return the servo command at clock time ``t``."""
        speed = self.config.servo_speed
        if self._start_time is None or t < self._start_time:
            pose = self._start_pose
            return GaitCommand(pose, pose, speed, False, False, -1, self._quarter_count % 4)
        tau = self._advance(t)
        positions = self._position(tau)
        quarter = self._quarter_count % 4
        if self._halted:
            targets = self._pos0
        else:
            arm = MOVING_ARM[quarter]
            goal = self.config.corner(quarter + 1)[arm]
            targets = (goal, positions[1]) if arm == 0 else (positions[0], goal)
        return GaitCommand(targets, positions, speed, True, self._halted,
                           math.floor(tau), quarter)

    def _advance(self, t: float) -> float:
        """Move the state machine through the quarter boundaries up to clock time ``t``, in constant time.

        A few boundaries are crossed one by one (a halt resumes and a new amplitude takes over at the next
        period boundary, and the arms reach their corners within two quarters after either); past those the
        gait is periodic, so the state jumps to two quarters before the last boundary, with the arms on that
        quarter's corner, and steps the last two. A time a billion seconds after the start costs what the
        next tick costs.
        """
        tau = self.gait_time(t)
        if tau < self._last_tau - 1e-12:
            raise GaitError(f'time went backwards: gait time {tau:.6f} after {self._last_tau:.6f}')
        self._last_tau = tau
        last = math.floor(4.0 * tau)          # the global number of the quarter that holds tau
        for _ in range(_STEPPED_BOUNDARIES):
            if self._quarter_count >= last:
                return tau
            self._cross_boundary()
        if self._quarter_count + 2 < last and not self._halted and self._pending is None:
            count = last - 2                  # periodic from here: the arms on the corner of quarter ``count``
            self._quarter_count, self._tau_event = count, count / 4.0
            self._pos0 = self.config.corner(count % 4)
        while self._quarter_count < last:
            self._cross_boundary()
        return tau

    def _cross_boundary(self) -> None:
        """Cross the next quarter boundary: the quarter's end pose becomes the next quarter's start."""
        boundary = (self._quarter_count + 1) / 4.0
        if self._halted:
            if boundary >= self._resume_tau:
                self._halted = False   # resume from the held pose with quarter 0
        else:
            self._pos0 = self._position(boundary)
        self._quarter_count += 1
        self._tau_event = boundary
        if self._pending is not None and self._quarter_count % 4 == 0:   # a new period: new amplitude
            self.config, self._pending = self._pending, None

    def _position(self, tau: float) -> tuple[float, float]:
        """Reference arm angles at gait time ``tau`` within the current quarter."""
        if self._halted:
            return self._pos0
        quarter = self._quarter_count % 4
        arm = MOVING_ARM[quarter]
        goal = self.config.corner(quarter + 1)[arm]
        start = self._pos0[arm]
        reach = self.config.servo_speed * self.config.period * max(tau - self._tau_event, 0.0)
        delta = goal - start
        moved = goal if abs(delta) <= reach else start + math.copysign(reach, delta)
        return (moved, self._pos0[1]) if arm == 0 else (self._pos0[0], moved)


def slowest_servo(alpha_max: float, period: float) -> float:
    """The slowest servo speed (rad/s) ``GaitConfig`` accepts for amplitude ``alpha_max`` (rad) and ``period``
    (s): its stroke of 2 alpha_max takes a quarter period."""
    return 8.0 * alpha_max / period


def check_start_time(start: float, now: float, period: float) -> None:
    """Refuse (GaitError) a gait start more than one ``period`` before ``now``: a clock mix-up, not a start.

    A start a little in the past (a start message on its way, a launch that took a moment) joins the gait
    where it is; a start long before that is a time on another clock (sim seconds given to a board's wall
    clock).
    """
    if not math.isfinite(start):
        raise GaitError(f'start time must be finite, got {start!r}')
    if start < now - period:
        raise GaitError(f'{start:.3f} s is {now - start:.3f} s before now ({now:.3f} s on this clock), more '
                        f'than one period ({period:g} s) in the past')


def board_time(t: float, start: float | None, rate: float) -> float:
    """Reading at reference time ``t`` of a board clock running ``rate`` times as fast, set at ``start``.

    A gait started at the shared time ``start`` on a board whose clock runs at ``rate`` (1 + relative
    error) sees start + (t - start) * rate; before a start (``start`` None) and at rate 1 it sees ``t``.
    """
    if rate == 1.0 or start is None:
        return t
    return start + (t - start) * rate


def open_loop_angles(config: GaitConfig, tau: float) -> tuple[float, float]:
    """Arm angles of an unhalted gait at gait time ``tau`` (periods), in closed form."""
    if not math.isfinite(tau) or tau < 0.0:
        raise GaitError(f'gait time must be finite and >= 0, got {tau!r}')
    count = math.floor(4.0 * tau)
    quarter = count % 4
    arm = MOVING_ARM[quarter]
    start = config.corner(quarter)
    goal = config.corner(quarter + 1)[arm]
    reach = config.servo_speed * config.period * (tau - count / 4.0)
    delta = goal - start[arm]
    moved = goal if abs(delta) <= reach else start[arm] + math.copysign(reach, delta)
    return (moved, start[1]) if arm == 0 else (start[0], moved)
