"""The servo bridge without ROS: command checking, watchdog, servo slew model, FSR sampling, faults.

``ServoBridgeCore`` is driven by two calls from its node (or a test): ``handle_command`` for every
joint command and ``step`` at the FSR rate. It talks to the board only through ``boards.ServoBoard``
over a ``serial_link.SerialLink`` and returns plain values and messages: it never raises on bad
input or a failing port. Times are seconds of one monotonic clock.

Thread safety: ``handle_command``, ``step``, ``poll_board_errors``, ``status`` and ``close`` may be
called from different threads. One lock serialises the board (the serial link) and the core's state
(targets, slew models, watchdog, counters), and ``step`` holds it only for one board transaction at a
time (reconnect and target sync, then the single FSR request/reply, then the joint-state readout), never
across the whole step, so a command arriving during a step waits for at most one short request/reply.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager
from dataclasses import asdict, dataclass, field
from enum import IntEnum
from pathlib import Path
from typing import Any

from smarticle_common import topics
from smarticle_driver.boards import BOARD_KINDS, ServoBoard, make_board
from smarticle_common.commands import check_command
from smarticle_driver.board_calibration import (FsrModel, ServoCalibration, default_config_dir,
                                          load_fsr_calibration, load_servo_calibration)
from smarticle_driver.errors import BridgeConfigError, PortUnavailable, ReplyError
from smarticle_common.facts import SERVO_SPEED
from smarticle_common.params import ROBOT_ID_PARAM, ParamSpec
from smarticle_driver.serial_link import SerialLink
from smarticle_driver.slew import SlewModel

NODE_NAME = 'servo_bridge'
SERVO_CALIBRATION_FILE = 'servo_calibration.yaml'
FSR_CALIBRATION_FILE = 'fsr_calibration.yaml'
#: Pulses closer than this (us) count as the same target (a quarter-microsecond step is 0.25 us).
PULSE_EPSILON = 0.125
#: With one_arm_at_a_time: seconds between the modelled end of one arm's stroke and the start of the other's.
STROKE_GAP = 0.005
#: With one_arm_at_a_time: a held-back target is sent at the latest this many seconds after it arrived, so a
#: gait whose strokes fill their quarters cannot fall further and further behind its own clock.
MAX_STROKE_DELAY = 0.05
#: The board moves this fraction faster than commanded: a stroke timed to fill its gait quarter at the servo
#: speed ends early on the board (8 ms for the default gait's 180 degrees in 0.4 s); the simulation keeps
#: the exact speed. The slew model (joint_states) uses the board's speed.
BOARD_SPEED_MARGIN = 0.02

_CH = (0, 23)

PARAMS: tuple[ParamSpec, ...] = (
    ROBOT_ID_PARAM,
    ParamSpec('board', 'maestro', f'servo board protocol, one of: {", ".join(BOARD_KINDS)}'),
    ParamSpec('port', '/dev/ttyACM0', 'serial port of the board (Maestro command port; smarticle-fake-board '
              'prints its own)'),
    ParamSpec('baud', 115200, 'serial baud rate (ignored by USB command ports)', 300, 250000),
    ParamSpec('arm1_channel', 0, 'board channel of the arm1 servo', *_CH),
    ParamSpec('arm2_channel', 1, 'board channel of the arm2 servo', *_CH),
    ParamSpec('fsr_arm1_front_channel', 2, 'analog input channel of the arm1_front FSR', *_CH),
    ParamSpec('fsr_arm1_back_channel', 3, 'analog input channel of the arm1_back FSR', *_CH),
    ParamSpec('fsr_arm2_front_channel', 4, 'analog input channel of the arm2_front FSR', *_CH),
    ParamSpec('fsr_arm2_back_channel', 5, 'analog input channel of the arm2_back FSR', *_CH),
    ParamSpec('fsr_rate_hz', 100.0, 'FSR sampling rate, also the joint_states rate (Hz)', 100.0, 1000.0),
    ParamSpec('watchdog_timeout', 0.5, 'hold the arms where they are when no valid joint command arrives '
              'for this many seconds', 0.02, 60.0),
    ParamSpec('default_speed', SERVO_SPEED, 'speed limit (rad/s) for commands without a valid '
              'velocity', 0.01, 100.0),
    ParamSpec('max_speed', SERVO_SPEED, "the servo's top speed (rad/s): higher speed limits are clamped to it",
              0.01, 100.0),
    ParamSpec('calibration_dir', '', f'folder of this robot\'s calibration, as smarticle-board-calibrate --out '
              f'writes it: {SERVO_CALIBRATION_FILE} and {FSR_CALIBRATION_FILE} are read from it (a part it lacks '
              "comes from the package's config folder); empty = the package's config folder"),
    ParamSpec('servo_calibration_file', '', f'servo calibration YAML; empty = {SERVO_CALIBRATION_FILE} in '
              "calibration_dir, else in the package's config folder"),
    ParamSpec('fsr_calibration_file', '', f'FSR calibration YAML; empty = {FSR_CALIBRATION_FILE} in '
              "calibration_dir, else in the package's config folder"),
    ParamSpec('reply_timeout', 0.02, 'seconds to wait for a board reply before counting it short',
              0.001, 1.0),
    ParamSpec('reconnect_initial', 0.1, 'first wait (s) before reopening a vanished port; doubles per failed '
              'attempt', 0.01, 60.0),
    ParamSpec('reconnect_max', 2.0, 'longest wait (s) between reopen attempts', 0.01, 600.0),
    ParamSpec('diagnostics_period', 1.0, 'seconds between /diagnostics messages and board error polls',
              0.1, 60.0),
    ParamSpec('one_arm_at_a_time', True, 'a new target for one arm waits until the other arm has reached its '
              f'target (by the slew model) plus {STROKE_GAP * 1e3:g} ms, at most {MAX_STROKE_DELAY * 1e3:g} ms, '
              "so the square gait's arms never move together on the board; holds are never delayed; false = "
              'send every target at once'),
    ParamSpec('autostart', True, 'bring the lifecycle node to active by itself: configure (open the port, '
              'retried every reconnect_max seconds until it opens) then activate; false = wait for '
              'lifecycle transitions (ros2 lifecycle set)'),
)


@dataclass(frozen=True)
class BridgeConfig:
    """Checked settings of one servo bridge (see PARAMS for the meaning of each)."""

    port: str
    robot_id: int = 0
    board: str = 'maestro'
    baud: int = 115200
    servo_channels: tuple[int, int] = (0, 1)
    fsr_channels: tuple[int, int, int, int] = (2, 3, 4, 5)
    fsr_rate_hz: float = 100.0
    watchdog_timeout: float = 0.5
    default_speed: float = SERVO_SPEED
    max_speed: float = SERVO_SPEED
    servo_calibration_file: str = ''
    fsr_calibration_file: str = ''
    calibration_dir: str = ''
    reply_timeout: float = 0.02
    reconnect_initial: float = 0.1
    reconnect_max: float = 2.0
    diagnostics_period: float = 1.0
    one_arm_at_a_time: bool = True
    autostart: bool = True

    def __post_init__(self) -> None:
        channels = self.servo_channels + self.fsr_channels
        if len(set(channels)) != len(channels):
            raise BridgeConfigError(f'servo and FSR channels must all differ, got servos '
                                    f'{self.servo_channels} and FSRs {self.fsr_channels}')
        if self.board not in BOARD_KINDS:
            raise BridgeConfigError(f'board must be one of {", ".join(BOARD_KINDS)}, got {self.board!r}')
        if self.reconnect_initial > self.reconnect_max:
            raise BridgeConfigError(f'reconnect_initial ({self.reconnect_initial} s) must not exceed '
                                    f'reconnect_max ({self.reconnect_max} s)')
        if not self.port:
            raise BridgeConfigError('port must name a serial device, got an empty string')
        if self.default_speed > self.max_speed:
            raise BridgeConfigError(f'default_speed ({self.default_speed} rad/s) must not exceed max_speed '
                                    f'({self.max_speed} rad/s)')
        if self.calibration_dir:
            folder = Path(self.calibration_dir).absolute()
            if not folder.is_dir():
                raise BridgeConfigError(f'calibration_dir {folder} is not a folder (smarticle-board-calibrate '
                                        '--out FOLDER writes one)')
            if not any((folder / name).is_file() for name in (SERVO_CALIBRATION_FILE, FSR_CALIBRATION_FILE)):
                raise BridgeConfigError(f'calibration_dir {folder} has neither {SERVO_CALIBRATION_FILE} nor '
                                        f'{FSR_CALIBRATION_FILE} (smarticle-board-calibrate --out FOLDER writes them)')

    @classmethod
    def from_values(cls, values: dict[str, Any]) -> BridgeConfig:
        """Build the config from checked parameter values (as returned by params.declare_and_read)."""
        fsr = [values[f'fsr_{face}_channel'] for face in topics.FSR_FACES]
        return cls(port=values['port'], robot_id=max(values['robot_id'], 0), board=values['board'],
                   baud=values['baud'], servo_channels=(values['arm1_channel'], values['arm2_channel']),
                   fsr_channels=(fsr[0], fsr[1], fsr[2], fsr[3]),
                   fsr_rate_hz=values['fsr_rate_hz'], watchdog_timeout=values['watchdog_timeout'],
                   default_speed=values['default_speed'], max_speed=values['max_speed'],
                   servo_calibration_file=values['servo_calibration_file'],
                   fsr_calibration_file=values['fsr_calibration_file'],
                   calibration_dir=values['calibration_dir'], reply_timeout=values['reply_timeout'],
                   reconnect_initial=values['reconnect_initial'], reconnect_max=values['reconnect_max'],
                   diagnostics_period=values['diagnostics_period'],
                   one_arm_at_a_time=values['one_arm_at_a_time'], autostart=values['autostart'])

    def servo_calibration_path(self) -> Path:
        """Return the servo calibration file to load: the file set, else calibration_dir's, else the package's."""
        return self._calibration_path(self.servo_calibration_file, SERVO_CALIBRATION_FILE)

    def fsr_calibration_path(self) -> Path:
        """Return the FSR calibration file to load: the file set, else calibration_dir's, else the package's."""
        return self._calibration_path(self.fsr_calibration_file, FSR_CALIBRATION_FILE)

    def _calibration_path(self, given: str, name: str) -> Path:
        if given:
            return Path(given)
        if self.calibration_dir and (Path(self.calibration_dir) / name).is_file():
            return (Path(self.calibration_dir) / name).absolute()
        return default_config_dir() / name


@dataclass
class Counters:
    """Everything the bridge counts; shown in /diagnostics."""

    commands: int = 0
    rejected_commands: int = 0
    nonfinite_targets: int = 0
    clamped_targets: int = 0
    bad_speeds: int = 0
    clamped_speeds: int = 0
    unknown_joints: int = 0
    short_reply: int = 0
    garbage: int = 0
    malformed: int = 0
    bad_reply: int = 0
    board_errors: int = 0
    watchdog_trips: int = 0
    fsr_samples: int = 0

    def add(self, name: str, count: int = 1) -> None:
        """Add ``count`` to counter ``name``."""
        setattr(self, name, getattr(self, name) + count)

    def as_dict(self) -> dict[str, int]:
        """Return the counters by name."""
        return asdict(self)


class Level(IntEnum):
    """Diagnostic levels (the values of diagnostic_msgs/DiagnosticStatus)."""

    OK = 0
    WARN = 1
    ERROR = 2


@dataclass(frozen=True)
class BridgeStatus:
    """A diagnostic summary: level, one-line message, key/value details."""

    level: Level
    message: str
    values: dict[str, str]


@dataclass
class StepResult:
    """What one bridge step produced; ``None`` fields mean nothing to publish."""

    joint_positions: tuple[float, ...] | None = None
    joint_velocities: tuple[float, ...] | None = None
    fsr_newtons: tuple[float, ...] | None = None
    fsr_counts: tuple[int, ...] | None = None
    warnings: list[str] = field(default_factory=list)
    events: list[str] = field(default_factory=list)


class _Joint:
    """Per-joint state: calibration, channel, wanted target and speed, what the board was sent, model."""

    def __init__(self, name: str, channel: int, calibration: ServoCalibration) -> None:
        self.name = name
        self.channel = channel
        self.cal = calibration
        self.target: float | None = None       # wanted angle (rad), clamped
        self.speed = 0.0                       # wanted speed limit (rad/s)
        self.sent_pulse: float | None = None   # what the board has (us), None = unknown
        self.sent_rate: float | None = None
        self.model = SlewModel()               # pulse (us) over time, at the board's speed limit
        self.hold = False                      # stop where the model says the arm is when the target is sent
        self.target_time = 0.0                 # when the wanted target arrived (clock s)


def load_calibration(config: BridgeConfig) -> tuple[dict[str, ServoCalibration], dict[str, FsrModel]]:
    """Read the servo and FSR calibration files of ``config`` (CalibrationError names file and field)."""
    return load_servo_calibration(config.servo_calibration_path()), load_fsr_calibration(config.fsr_calibration_path())


class ServoBridgeCore:
    """Joint commands in, Maestro bytes out; slew-model joint states and FSR newtons back."""

    def __init__(self, config: BridgeConfig, servos: dict[str, ServoCalibration], fsrs: dict[str, FsrModel],
                 link: SerialLink, board: ServoBoard, clock: Callable[[], float] = time.monotonic) -> None:
        self.config = config
        #: The clock of the ``now`` arguments: a hold is taken at the time it is written to the board.
        self.clock = clock
        self.link = link
        self.board = board
        self.fsrs = [fsrs[face] for face in topics.FSR_FACES]
        self.joints = [_Joint(name, ch, servos[name])
                       for name, ch in zip(topics.JOINT_NAMES, config.servo_channels, strict=True)]
        self.limits = {j.name: j.cal.angle_limits() for j in self.joints}
        self.counters = Counters()
        self.last_command_time: float | None = None
        self.holding = False
        self.last_board_errors: list[str] = []
        self.last_reply_error = ''
        self._reported_reply_errors = 0
        #: Serialises the board and all the state above; held for one board transaction at a time.
        self.lock: AbstractContextManager[Any] = threading.Lock()
        self._closed = False
        #: When a target held back by one_arm_at_a_time is due (clock s), None = nothing held back.
        self._stroke_due: float | None = None
        #: The port state the last step reported: a loss found by any thread (a command, the error poll)
        #: is reported once, by the next step.
        self._reported_open = False

    @classmethod
    def from_config(cls, config: BridgeConfig,
                    calibration: tuple[dict[str, ServoCalibration], dict[str, FsrModel]] | None = None
                    ) -> ServoBridgeCore:
        """Build the link and board (the port opens on ``open`` or the first step), loading the calibration
        files unless ``calibration`` (from ``load_calibration``) is given."""
        servos, fsrs = calibration or load_calibration(config)
        link = SerialLink(config.port, config.baud, config.reply_timeout, config.reconnect_initial,
                          config.reconnect_max)
        return cls(config, servos, fsrs, link, make_board(config.board, link))

    def open(self, now: float) -> tuple[bool, list[str]]:
        """Open the port now and seed the joint models from the board's pulses: (opened, warnings).

        The lifecycle node's configure: False (with the port's error) when the port cannot be opened.
        """
        with self.lock:
            if self.link.is_open:
                return True, []
            if self.link.poll():
                self._reported_open = True
                return True, self._on_open(now)
            return False, [self.link.last_error]

    def hold(self, now: float) -> list[str]:
        """Hold the arms where they are now (the lifecycle node's deactivate); warnings if the port failed."""
        with self.lock:
            self._hold_all()
            self.holding = True
            error = self._sync(now)
        return [error] if error else []

    def handle_command(self, names: Sequence[str], positions: Sequence[float], velocities: Sequence[float],
                       now: float) -> list[str]:
        """Take one joint command; send what changed at once; return warnings about the message.

        Waits for at most the one board transaction that may be in progress in another thread.
        """
        checked = check_command(names, positions, velocities, self.limits, self.config.default_speed,
                                self.config.max_speed)
        with self.lock:
            self.counters.add('commands')
            for counter, count in checked.counts.items():
                self.counters.add(counter, count)
            if checked.targets:
                previous = {joint.name: joint.target for joint in self.joints}
                for joint in self.joints:
                    if joint.name in checked.targets:
                        joint.target = checked.targets[joint.name]
                        joint.speed = checked.speeds[joint.name]
                        joint.hold = False
                        if joint.target != previous.get(joint.name):
                            joint.target_time = now
                self.last_command_time = now
                self.holding = False
                port_error = self._sync(now)
                if port_error:
                    checked.warnings.append(port_error)
        return checked.warnings

    def step(self, now: float) -> StepResult:
        """Reconnect if due, run the watchdog, send pending targets, sample the FSRs, model the joints.

        Takes the lock three times (reconnect + watchdog + sync, the FSR transaction, the readout), so
        commands from another thread get to the board between them.
        """
        result = self.service(now)
        counts = self._read_fsrs(result)
        if counts is not None:
            result.fsr_counts = tuple(counts)
            result.fsr_newtons = tuple(m.newtons(c) for m, c in zip(self.fsrs, counts, strict=True))
        with self.lock:
            if self._closed:
                return result
            if self._reported_open and not self.link.is_open:
                result.events.append(f'port {self.link.port} lost ({self.link.last_error}); '
                                     'reopening with back-off')
            self._reported_open = self.link.is_open
            if self.link.is_open and all(j.model.known for j in self.joints):
                result.joint_positions = tuple(j.cal.pulse_to_angle(j.model.position(now)) for j in self.joints)
                result.joint_velocities = tuple(j.model.velocity(now) / j.cal.us_per_rad for j in self.joints)
        return result

    def service(self, now: float) -> StepResult:
        """Reconnect if due, run the watchdog and send pending targets (the first part of ``step``).

        The node also calls it on its own at ``next_deadline``, between two steps.
        """
        result = StepResult()
        with self.lock:
            if self._closed:
                return result
            if self.link.poll():
                result.events.append(f'port {self.link.port} opened')
                result.warnings.extend(self._on_open(now))
            self._watchdog(now, result)
            self._sync(now)    # a port lost here is reported as an event by step
        return result

    def next_deadline(self) -> float | None:
        """When ``service`` must run next (clock s), between steps: the watchdog's timeout or a stroke held back
        by one_arm_at_a_time; None = no need."""
        with self.lock:
            if self._closed:
                return None
            due = [t for t in (self._stroke_due, None if self.holding or self.last_command_time is None
                               else self.last_command_time + self.config.watchdog_timeout) if t is not None]
            return min(due) if due else None

    def poll_board_errors(self) -> list[str]:
        """Read and clear the board's error flags; return warnings (empty when all is well)."""
        with self.lock:
            if self._closed or not self.link.is_open:
                return []
            try:
                errors = self.board.get_errors()
            except ReplyError as err:
                return [self._count_reply_error(err)]
            except PortUnavailable as err:
                return [str(err)]
            if errors:
                self.counters.add('board_errors')
                self.last_board_errors = errors
                return [f'board reports errors: {", ".join(errors)}']
            return []

    def status(self, now: float) -> BridgeStatus:
        """Summarise port, watchdog and counters for /diagnostics."""
        with self.lock:
            return self._status(now)

    def close(self) -> None:
        """Close the serial port for good: later steps do nothing (waits for a transaction in progress)."""
        with self.lock:
            self._closed = True
            self.link.close()

    def _read_fsrs(self, result: StepResult) -> list[int] | None:
        """Sample the four FSR inputs in one board transaction, under the lock; None if it failed."""
        with self.lock:
            if self._closed or not self.link.is_open:
                return None
            try:
                counts = self.board.read_analog(self.config.fsr_channels)
            except ReplyError as err:
                result.warnings.append(self._count_reply_error(err))
                return None
            except PortUnavailable:
                return None    # reported as an event by step
            self.counters.add('fsr_samples')
            return counts

    def _status(self, now: float) -> BridgeStatus:
        link = self.link
        counts = self.counters.as_dict()
        reply_errors = sum(counts[k] for k in ('short_reply', 'garbage', 'malformed', 'bad_reply'))
        new_reply_errors = reply_errors - self._reported_reply_errors
        self._reported_reply_errors = reply_errors
        age = None if self.last_command_time is None else now - self.last_command_time
        if not link.is_open:
            level = Level.ERROR
            message = (f'port {link.port} down ({link.last_error}); '
                       f'next attempt in {link.seconds_to_retry():.2f} s')
        elif self.holding and age is not None and age > self.config.watchdog_timeout:
            level = Level.WARN
            message = f'watchdog: no joint command for {age:.2f} s, arms held'
        elif self.holding:
            level = Level.OK
            message = 'port open, arms held'
        elif new_reply_errors:
            level = Level.WARN
            message = f'{new_reply_errors} bad board replies since the last report ({self.last_reply_error})'
        elif self.last_command_time is None:
            level = Level.OK
            message = 'port open, waiting for the first joint command'
        else:
            level = Level.OK
            message = 'port open, arms following joint commands'
        values = {
            'port': link.port,
            'port_state': link.state.value,
            'port_opens': str(link.opens),
            'port_disconnects': str(link.disconnects),
            'failed_opens': str(link.failed_opens),
            'discarded_bytes': str(link.discarded_bytes),
            'last_port_error': link.last_error,
            'watchdog': 'holding' if self.holding else 'ok',
            'watchdog_timeout_s': f'{self.config.watchdog_timeout:g}',
            'last_command_age_s': 'never' if age is None else f'{age:.3f}',
            'last_board_errors': ', '.join(self.last_board_errors) or 'none',
            'last_reply_error': self.last_reply_error or 'none',
        }
        values.update({k: str(v) for k, v in self.counters.as_dict().items()})
        return BridgeStatus(level, message, values)

    def _watchdog(self, now: float, result: StepResult) -> None:
        """Hold the arms where the model says they are when commands have stopped."""
        if self.holding or self.last_command_time is None:
            return
        if now - self.last_command_time < self.config.watchdog_timeout:
            return
        self.holding = True
        self.counters.add('watchdog_trips')
        self._hold_all()
        result.events.append(f'watchdog: no joint command for {now - self.last_command_time:.2f} s '
                             f'(timeout {self.config.watchdog_timeout:g} s); holding the arms')

    def _hold_all(self) -> None:
        """Make every joint with a known position stop where it is when its target is next sent."""
        for joint in self.joints:
            if joint.model.known:
                joint.hold = True
                if joint.target is None:
                    joint.target = joint.cal.pulse_to_angle(joint.model.target)

    def _on_open(self, now: float) -> list[str]:
        """After (re)opening: forget what the board was sent and seed the models from its pulses."""
        warnings: list[str] = []
        for joint in self.joints:
            joint.sent_pulse = None
            joint.sent_rate = None
            joint.model.forget()
            try:
                pulse = self.board.read_pulse(joint.channel)
            except ReplyError as err:
                warnings.append(self._count_reply_error(err))
                continue
            except PortUnavailable as err:
                warnings.append(str(err))
                break
            if pulse > 0.0:
                joint.model.set_target(pulse, now)
        return warnings

    def _sync(self, now: float) -> str:
        """Send speeds and targets that differ from what the board has; return '' or the port error.

        The board's models are advanced at the time of sending (the clock, never before ``now``); a hold
        takes the modelled position of that moment, so an arm moving while this thread waited (for the
        lock, for the CPU) is stopped where it is, not where it was.
        """
        if not self.link.is_open:
            return ''
        self._stroke_due = None
        try:
            for joint in self.joints:
                if joint.target is None:
                    continue
                if joint.hold:
                    if not joint.model.known:      # lost with the port: nothing to hold
                        joint.hold = False
                        continue
                    t = max(now, self.clock())
                    joint.target = joint.cal.pulse_to_angle(joint.model.position(t))
                    pulse = joint.model.position(t)
                    joint.hold = False
                    if joint.sent_pulse is None or abs(pulse - joint.sent_pulse) > PULSE_EPSILON:
                        joint.model.set_target(self.board.set_target(joint.channel, pulse), t)
                        joint.sent_pulse = pulse
                    continue
                rate = joint.cal.rate_to_pulse_rate(joint.speed) * (1.0 + BOARD_SPEED_MARGIN)
                if joint.sent_rate is None or abs(rate - joint.sent_rate) > 1e-9:
                    actual_rate = self.board.set_speed(joint.channel, rate)
                    joint.model.set_rate(actual_rate, max(now, self.clock()))
                    joint.sent_rate = rate
                pulse = min(max(joint.cal.angle_to_pulse(joint.target), joint.cal.min_us), joint.cal.max_us)
                if joint.sent_pulse is None or abs(pulse - joint.sent_pulse) > PULSE_EPSILON:
                    due = self._other_arm_done(joint, max(now, self.clock()))
                    if due is not None:
                        self._stroke_due = due if self._stroke_due is None else min(due, self._stroke_due)
                        continue
                    actual = self.board.set_target(joint.channel, pulse)
                    joint.model.set_target(actual, max(now, self.clock()))
                    joint.sent_pulse = pulse
        except PortUnavailable as err:
            return str(err)
        return ''

    def _other_arm_done(self, joint: _Joint, t: float) -> float | None:
        """With one_arm_at_a_time: when ``joint`` may start a stroke if another arm is still moving at ``t``
        (its modelled end + STROKE_GAP); None = now."""
        if not self.config.one_arm_at_a_time:
            return None
        due = max((other.model.end_time() + STROKE_GAP for other in self.joints
                   if other is not joint and other.model.known), default=None)
        if due is None:
            return None
        due = min(due, joint.target_time + MAX_STROKE_DELAY)
        return due if due > t else None

    def _count_reply_error(self, err: ReplyError) -> str:
        self.counters.add(err.kind)
        self.last_reply_error = str(err)
        return f'bad reply from the board ({err.kind}): {err}'
