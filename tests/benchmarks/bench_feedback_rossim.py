"""The feedback through the ROS sim-in-the-loop path against the batch path, same C2 starts.

ROS path: sim_bridge (lock-step, publish_period = one control tick, so an FSR sample is published every
tick as the batch loop reads it) + one gait node (lockstep, use_sim_time) and one feedback node
(use_sim_time) per robot, separate processes over DDS. Batch path: ``run_pair_trial`` (Runner + gait
cores + controller calling GaitController.halt, halt applied before the next tick). For each seed it prints halts,
the lifetime and r at the end, and writes CSV under out/benchmarks/.
The gait nodes wait for their feedback node's decision on each tick's FSR sample (``wait_for_feedback``,
feedback ``lockstep``), so a halt lands on the tick of its sample and the two paths give the same run
(tests/smarticle_feedback/test_feedback_lockstep.py checks it bit for bit); this script shows the
figures side by side over more seeds and periods.
Usage: python tests/benchmarks/bench_feedback_rossim.py [--seeds 3] [--periods 10]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import rclpy
from smarticle_common import topics
from smarticle_common.launching import DomainReservation, ProcessGroup, isolated_ros_env

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))   # the repository root: tests.* helpers
from smarticle_sim.config_builder import build_config
from smarticle_experiments.p6 import COLLIDING_START, Condition, c2_start, pair_lifetime, run_pair_trial
from tests.benchmarks._common import markdown_table, out_path, write_csv

START_AT = 0.5
TICK = 1.0 / 60.0
BL = 0.065
SERVO_SPEED = build_config('feedback').robot.servo_speed


def ros_trial(seed: int, periods: float, workdir: Path, probe: object) -> dict[str, float]:
    """One seed through the ROS path; returns halts, lifetime and final r."""
    r, theta, phi = c2_start(seed, COLLIDING_START)
    phases = COLLIDING_START[3]
    duration = START_AT + periods * 1.6
    poses: list[tuple[float, np.ndarray]] = []
    halts: list[tuple[float, str]] = []
    pose_type = topics.message_class('geometry_msgs/msg/PoseArray')
    header = topics.message_class('std_msgs/msg/Header')

    def on_poses(msg: object) -> None:
        arr = np.array([[p.position.x, p.position.y, 2.0 * math.atan2(p.orientation.z, p.orientation.w)]
                        for p in msg.poses])   # type: ignore[attr-defined]
        poses.append((msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, arr))  # type: ignore[attr-defined]

    subs = [probe.create_subscription(pose_type, topics.topic('poses'), on_poses,  # type: ignore[attr-defined]
                                      topics.qos_profile(topics.Qos.SENSOR))]
    for k in range(2):
        subs.append(probe.create_subscription(  # type: ignore[attr-defined]
            header, topics.topic('halt', k),
            lambda m, k=k: halts.append((m.stamp.sec + m.stamp.nanosec * 1e-9, k)),
            topics.qos_profile(topics.Qos.COMMAND)))
    with ProcessGroup(workdir, dict(os.environ)) as procs:
        for k in range(2):
            procs.start('gait', '--ros-args', '-r', f'__node:=gait_{k}', '-p', f'robot_id:={k}', '-p', 'lockstep:=true',
                        '-p', 'wait_for_feedback:=true', '-p', 'alpha_max_deg:=90.0',
                        '-p', f'servo_speed:={SERVO_SPEED}', '-p', f'phase:={phases[k]}',
                        '-p', f'start_at:={START_AT}')
            procs.start('feedback', '--ros-args', '-r', f'__node:=feedback_{k}', '-p', f'robot_id:={k}',
                        '-p', 'lockstep:=true', '-p', f'phase:={phases[k]}', '-p', f'start_at:={START_AT}')
        bridge = procs.start('sim_bridge', '--ros-args', '-p', 'preset:=feedback', '-p', 'scene:=pair',
                             '-p', f'pair_r:={r}', '-p', f'pair_theta_deg:={theta}', '-p', f'pair_phi_deg:={phi}',
                             '-p', f'pair_phase_0:={phases[0]}', '-p', f'pair_phase_1:={phases[1]}',
                             '-p', 'alpha_max_deg:=90.0', '-p', f'publish_period:={TICK}',
                             '-p', f'start_at:={START_AT}', '-p', f'duration:={duration}',
                             '-p', 'wait_for_subscribers:=1')
        deadline = time.time() + 600
        while bridge.poll() is None and time.time() < deadline:
            rclpy.spin_once(probe, timeout_sec=0.05)
        for _ in range(20):
            rclpy.spin_once(probe, timeout_sec=0.05)
    for sub in subs:
        probe.destroy_subscription(sub)  # type: ignore[attr-defined]
    poses.sort(key=lambda p: p[0])
    times = np.array([t for t, _ in poses])
    arr = np.stack([p for _, p in poses])
    life, _ = pair_lifetime(times, arr, 1.6, BL, t0=START_AT)
    final_r = float(np.linalg.norm(arr[-1, 1, :2] - arr[-1, 0, :2]) / BL)
    return {'halts': len(halts), 'lifetime': life, 'final_r': final_r, 'samples': len(times)}


def main() -> None:
    """Run both paths per seed and print the comparison."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', type=int, default=3)
    parser.add_argument('--periods', type=float, default=10.0)
    args = parser.parse_args()
    domain = DomainReservation()
    os.environ.update({k: v for k, v in isolated_ros_env(domain.domain_id).items()
                       if k in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')})
    rclpy.init()
    probe = rclpy.create_node('feedback_rossim_probe')
    rows = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for seed in range(args.seeds):
                ros = ros_trial(seed, args.periods, Path(tmp) / f'seed{seed}', probe)
                batch = run_pair_trial(Condition(90.0, True), seed, args.periods, start_time=START_AT,
                                       base=COLLIDING_START)
                rows.append({'seed': seed, 'batch_halts': len(batch.halts), 'ros_halts': ros['halts'],
                             'batch_lifetime': batch.lifetime_periods, 'ros_lifetime': ros['lifetime'],
                             'batch_final_r': float(batch.r[-1]), 'ros_final_r': ros['final_r']})
                print(rows[-1], flush=True)
    finally:
        probe.destroy_node()
        rclpy.try_shutdown()
        domain.close()
    write_csv(out_path('feedback_rossim.csv'), rows)
    print(markdown_table(rows, [('seed', 'seed', 'd'), ('batch_halts', 'halts batch', 'd'),
                                ('ros_halts', 'halts ROS', 'd'), ('batch_lifetime', 'lifetime batch', 'd'),
                                ('ros_lifetime', 'lifetime ROS', 'd'), ('batch_final_r', 'final r batch (BL)', '.3f'),
                                ('ros_final_r', 'final r ROS (BL)', '.3f')]))


if __name__ == '__main__':
    main()
