"""The hardware path on one machine: board emulator (in this process) + servo_bridge + gait + feedback processes.

Used by ``test_feedback_hardware_path.py`` and ``tests/benchmarks/bench_feedback_latency.py``. An FSR
"impact" is a voltage pulse on the emulator's analog input of one face; the chain under test is
emulator -> servo_bridge (/smarticle_0/fsr) -> feedback (/smarticle_0/halt) -> gait (hold on
/smarticle_0/joint_commands) -> servo_bridge -> Set Target bytes on the emulator's pty.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

from smarticle_common import topics
from smarticle_driver import maestro
from smarticle_driver.board_calibration import default_config_dir, load_fsr_calibration
from smarticle_driver.emulator import MaestroEmulator, TargetRecord
from smarticle_common.launching import ProcessGroup
from smarticle_driver.servo_bridge_core import FSR_CALIBRATION_FILE

#: Emulator channel of each FSR face (the servo bridge's defaults).
FSR_CHANNEL = dict(zip(topics.FSR_FACES, (2, 3, 4, 5), strict=False))


def volts_for(face: str, newtons: float) -> float:
    """Smallest analog input voltage that the default FSR calibration reads as at least ``newtons``."""
    model = load_fsr_calibration(default_config_dir() / FSR_CALIBRATION_FILE)[face]
    for counts in range(maestro.ANALOG_FULL_SCALE + 1):
        if model.newtons(counts) >= newtons:
            return counts * maestro.ANALOG_VOLTS / maestro.ANALOG_FULL_SCALE
    raise ValueError(f'{face} cannot read {newtons} N')


@dataclass
class Observed:
    """Messages the probe node received, with their receive times (time.time())."""

    halts: list[tuple[float, float, str]] = field(default_factory=list)          # (stamp, received, face)
    commands: list[tuple[float, float, tuple[float, ...]]] = field(default_factory=list)  # (stamp, received, targets)


class HardwareRig:
    """Start the three node processes on an emulator and a probe node that sends the start and listens."""

    def __init__(self, procs: ProcessGroup, emulator: MaestroEmulator, probe: Any, period: float = 0.8,
                 alpha_max_deg: float = 45.0, feedback_args: tuple[str, ...] = ()) -> None:
        self.procs, self.emulator, self.probe = procs, emulator, probe
        self.period, self.alpha = period, math.radians(alpha_max_deg)
        self.observed = Observed()
        self.wall_offset = time.time() - time.monotonic()   # emulator records use time.monotonic()
        header, joint_state = topics.message_class('std_msgs/msg/Header'), topics.message_class(
            'sensor_msgs/msg/JointState')
        qos = {k: topics.qos_profile(topics.spec_of(k).qos) for k in ('halt', 'joint_commands', 'start')}
        probe.create_subscription(header, topics.topic('halt', 0), self._on_halt, qos['halt'])
        probe.create_subscription(joint_state, topics.topic('joint_commands', 0), self._on_command,
                                  qos['joint_commands'])
        self.start_pub = probe.create_publisher(header, topics.topic('start'), qos['start'])
        self.Header = header
        common = ('-p', f'period:={period}')
        self.bridge = procs.start('servo_bridge', '--ros-args', '-p', f'port:={emulator.link_path}',
                                  '-p', 'watchdog_timeout:=2.0')
        self.gait = procs.start('gait', '--ros-args', *common, '-p', f'alpha_max_deg:={alpha_max_deg}')
        self.feedback = procs.start('feedback', '--ros-args', *common, *feedback_args)
        self.t0: float | None = None

    def logs(self) -> str:
        """What the three node processes have printed so far (for assertion messages)."""
        return ''.join(self.procs.output(p) for p in (self.bridge, self.gait, self.feedback))

    def _on_halt(self, msg: Any) -> None:
        self.observed.halts.append((msg.stamp.sec + msg.stamp.nanosec * 1e-9, time.time(), msg.frame_id))

    def _on_command(self, msg: Any) -> None:
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        self.observed.commands.append((stamp, time.time(), tuple(msg.position)))

    def ready(self) -> bool:
        """True when every process is connected: gait and feedback listen for the start, the gait and the probe for
        halts, commands reach the board."""
        return (self.probe.count_publishers(topics.topic('halt', 0)) >= 1
                and self.probe.count_subscribers(topics.topic('halt', 0)) >= 2
                and self.probe.count_subscribers(topics.topic('start')) >= 2
                and len(self.observed.commands) > 0 and len(self.emulator.targets()) > 0)

    def start(self, delay: float = 1.0) -> float:
        """Publish the synchronised start ``delay`` seconds from now; return the start time (time.time())."""
        self.t0 = time.time() + delay
        msg = self.Header()
        msg.stamp.sec = int(self.t0)
        msg.stamp.nanosec = int((self.t0 % 1.0) * 1e9)
        self.start_pub.publish(msg)
        return self.t0

    def period_start(self, n: int) -> float:
        """Wall time (time.time()) of the start of gait period ``n``."""
        assert self.t0 is not None
        return self.t0 + n * self.period

    def pulse(self, face: str, newtons: float, duration: float = 0.03) -> None:
        """Press ``face`` with ``newtons`` for ``duration`` seconds (blocking), then release it."""
        channel = FSR_CHANNEL[face]
        self.emulator.set_voltage(channel, volts_for(face, newtons))
        time.sleep(duration)
        self.emulator.set_voltage(channel, 0.0)

    def targets_between(self, start: float, stop: float) -> list[TargetRecord]:
        """Set Targets the emulator received between two wall times."""
        return [r for r in self.emulator.targets() if start <= r.time + self.wall_offset < stop]

    def wall(self, record: TargetRecord) -> float:
        """A target record's arrival as time.time()."""
        return record.time + self.wall_offset
