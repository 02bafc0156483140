"""Regenerate the sample bags in bags/samples/ with the project's own sim, recorded by the real recorder.

Each sample is a lock-step run (reproducible: the same seed gives the same poses) of ``sim_bridge``
plus one ``gait`` node per robot, recorded by ``smarticle-bag record``, every one a separate process
talking over DDS in a domain of its own. The bridge waits for two subscribers of /smarticles/poses:
the recorder and a gate in this script that subscribes only once the recorder has subscribed to every
chosen topic, so each bag holds the run from its first step.

  pair_c1   scene pair (r = 1.3 BL, theta = 0, phi = 180 deg: a C1-like start), 2 robots, 30 s:
            /clock, /smarticles/poses, /smarticles/start, joint states, FSR and joint commands of both
  dense7    scene dense (the paper's Fig. 1(c)), 7 robots, 45 s: /clock, /smarticles/poses,
            /smarticles/start, joint states of all seven

Log time is the recorder's wall-clock receive time (like ``ros2 bag record``); header stamps are sim
time. Usage: ``.venv/bin/python bags/scripts/make_samples.py [--only pair_c1] [--out bags/samples]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from smarticle_common.launching import DomainReservation, ProcessGroup, isolated_ros_env

from smarticle_bags.info import format_info
from smarticle_bags.reader import BagReader
from smarticle_bags.recording import start_recording
from smarticle_common.facts import GAIT_PERIOD

ROOT = Path(__file__).resolve().parents[2]
ALPHA_MAX, PERIOD, START_AT = 90.0, GAIT_PERIOD, 0.5


@dataclass(frozen=True)
class Sample:
    """One sample bag: scene, robots, sim seconds, topics and extra sim bridge parameters."""

    name: str
    scene: str
    robots: int
    duration: float
    per_robot: tuple[str, ...]
    bridge: tuple[str, ...] = ()

    def topics(self) -> list[str]:
        """The recorded topics."""
        names = ['/clock', '/smarticles/poses', '/smarticles/start']
        return names + [f'/smarticle_{k}/{leaf}' for k in range(self.robots) for leaf in self.per_robot]


SAMPLES = (
    Sample('pair_c1', 'pair', 2, 30.0, ('joint_states', 'fsr', 'joint_commands'),
           ('-p', 'pair_r:=1.3', '-p', 'pair_theta_deg:=0.0', '-p', 'pair_phi_deg:=180.0')),
    Sample('dense7', 'dense', 7, 45.0, ('joint_states',)),
)


def record(sample: Sample, out: Path, log_dir: Path) -> None:
    """Run the sim for ``sample`` and record it into ``out`` (must not exist)."""
    import rclpy
    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    common = ['-p', f'alpha_max_deg:={ALPHA_MAX}', '-p', f'period:={PERIOD}']
    rclpy.init()
    gate = rclpy.create_node('sample_gate')
    try:
        with ProcessGroup(log_dir) as group:
            for k in range(sample.robots):
                group.start('gait', '--ros-args', '-p', f'robot_id:={k}', '-p', 'lockstep:=true',
                            '-p', 'use_sim_time:=true', *common)
            rec = start_recording(group, out, sample.topics())
            bridge = group.start('sim_bridge', '--ros-args', '-p', f'scene:={sample.scene}',
                                 '-p', f'robots:={sample.robots}', '-p', 'seed:=1',
                                 '-p', f'duration:={sample.duration}', '-p', f'start_at:={START_AT}',
                                 '-p', 'wait_for_subscribers:=2', *common, *sample.bridge)
            if not rec.wait_subscribed(timeout=60.0):
                missing = set(sample.topics()) - rec.subscribed()
                raise RuntimeError(f'the recorder never subscribed to {sorted(missing)}:\n'
                                   + group.output(rec.proc)[-2000:])
            time.sleep(2.0)  # discovery: every publisher matches the recorder before the gate opens
            gate.create_subscription(PoseArray, '/smarticles/poses', lambda _msg: None,
                                     QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
            while bridge.poll() is None:
                rclpy.spin_once(gate, timeout_sec=0.1)
            if bridge.returncode != 0:
                raise RuntimeError(f'sim bridge exited with {bridge.returncode}:\n' + group.output(bridge)[-2000:])
            time.sleep(0.5)  # the last messages reach the recorder
            rec.stop()
    finally:
        gate.destroy_node()
        rclpy.try_shutdown()


def main(argv: list[str] | None = None) -> int:
    """Regenerate the chosen samples; print ``info`` of each."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--out', type=Path, default=ROOT / 'bags' / 'samples', help='folder of the samples')
    parser.add_argument('--only', nargs='+', choices=[s.name for s in SAMPLES], help='make only these')
    args = parser.parse_args(argv)
    reservation = DomainReservation()
    os.environ.update(isolated_ros_env(reservation.domain_id))
    try:
        for sample in SAMPLES:
            if args.only and sample.name not in args.only:
                continue
            target = args.out / sample.name
            work = args.out / f'.{sample.name}.new'
            shutil.rmtree(work, ignore_errors=True)
            logs = ROOT / 'out' / 'samples_logs' / sample.name
            shutil.rmtree(logs, ignore_errors=True)
            print(f'[samples] {sample.name}: {sample.robots} robots, scene {sample.scene}, '
                  f'{sample.duration:g} s (logs in {logs})', flush=True)
            started = time.monotonic()
            record(sample, work / sample.name, logs)
            shutil.rmtree(target, ignore_errors=True)
            (work / sample.name).rename(target)
            work.rmdir()
            print(f'[samples] {sample.name} made in {time.monotonic() - started:.0f} s', flush=True)
            print(format_info(BagReader(target, strict=True)), flush=True)
    finally:
        reservation.close()
    return 0


if __name__ == '__main__':
    sys.exit(main())
