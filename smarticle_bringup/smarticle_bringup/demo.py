"""The main demo: a sim-in-the-loop run of the stack with its default settings.

Starts ``smarticle_bringup/launch/sim.launch.xml`` through the project's launcher (the file ``ros2 launch``
reads on a board): the sim bridge, one gait and one feedback node per robot and the live glider monitor,
composed in one process on one executor (``--separate``: each its own process), a bag recorder and, with
``--view``, the Foxglove live view; all talk over DDS in lock-step, so the physics is reproducible. The
demo listens to ``/smarticles/poses`` like any other node would, then finds the gliders with the glider
analysis core, prints a table and writes figures, the poses and an mcap bag to ``out/demo/``.
Usage: ``./demo.sh [--robots 7] [--periods 60] [--alpha-max 90] [--seed 1] [--no-feedback] [--separate]
[--view]``.
"""

from __future__ import annotations

import argparse
import functools
import math
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_common.facts import GAIT_PERIOD, SMALL
from smarticle_common.runs import Recording, save_npz
from smarticle_common.cli import add_version



def build_parser() -> argparse.ArgumentParser:
    """Command-line options of the demo."""
    parser = argparse.ArgumentParser(prog='demo.sh', description=__doc__.split('\n')[0] if __doc__ else None)
    add_version(parser, 'smarticle_bringup')
    parser.add_argument('--robots', type=int, default=7, help='number of robots (default 7, as in the paper)')
    parser.add_argument('--scene', choices=('dense', 'random', 'pair'), default='dense',
                        help="starting arrangement (default: densely packed, the paper's Fig. 1(c))")
    parser.add_argument('--periods', type=float, default=60.0,
                        help='gait periods to run (default 60)')
    parser.add_argument('--alpha-max', type=float, default=90.0, help='gait amplitude in degrees (default 90)')
    parser.add_argument('--seed', type=int, default=1, help='seed of the starting arrangement')
    parser.add_argument('--phase-jitter', type=float, default=0.05,
                        help='dense scene: seeded gait-phase offsets in +-this many periods, a stand-in for the '
                             "real robots' phase drift (default 0.05; 0 = perfectly in phase, where the sim's "
                             'pairs bind but hardly glide: docs/sim_calibration.md)')
    parser.add_argument('--clock-noise', action='store_true',
                        help="each robot's board clock runs fast or slow by a seeded draw of the cited resonator "
                             'spread (0.29 %% sd; the clock_rate_sd of noise: paper), the same draws as the batch '
                             'path for this seed; its gait and feedback nodes take it as clock_rate_offset')
    parser.add_argument('--feedback', action=argparse.BooleanOptionalAction, default=True,
                        help='run the tactile feedback node of every robot (impact window from '
                             'smarticle_feedback/config/feedback.yaml; default on); the sim then publishes FSR '
                             'forces. --no-feedback runs the open-loop gait only')
    parser.add_argument('--separate', action='store_true',
                        help='run every node as its own process (default: the stack composed in one process '
                             'on one executor, smarticle-compose; same trajectories, faster)')
    parser.add_argument('--view', action='store_true',
                        help='serve the live view to Foxglove on ws://localhost:8765 (smarticle-view; open it in '
                             'Foxglove with smarticle_bringup/config/foxglove_layout.json)')
    parser.add_argument('--view-port', type=int, default=8765, help='WebSocket port of --view (default 8765)')
    parser.add_argument('--min-periods', type=int, default=30,
                        help='a pair bound this many periods is a glider (default 30, as in the paper)')
    parser.add_argument('--out', type=Path, default=Path('out/demo'), help='output folder')
    return parser


def report_graph(names: list[str], path: Path) -> None:
    """Print the ROS graph seen during the run and write it to ``path``; name any node name used twice."""
    seen = sorted(names)
    twice = sorted({n for n in seen if seen.count(n) > 1})
    path.write_text('\n'.join(seen) + '\n', encoding='utf-8')
    print(f'[demo] ROS graph: {len(seen)} nodes, ' + (f'names used twice: {", ".join(twice)}' if twice else
                                                       'every fully qualified name distinct') + f' ({path})')


#: Exit code of the sim bridge when the physics hit trouble (SimTrouble): the run stopped early.
SIM_TROUBLE_EXIT = 3


def clock_offsets(robots: int, seed: int) -> np.ndarray:
    """Each robot's board-clock rate offset for ``--clock-noise``: the batch path's draws (``noise.clock_rates``)
    of the cited clock spread for the trial seed ``seed``, so a ROS run and a batch run of the seed agree."""
    from smarticle_sim.noise import clock_rates
    from smarticle_sim.settings import CLOCK_RATE_SD, NoiseConfig

    return clock_rates(NoiseConfig(clock_rate_sd=CLOCK_RATE_SD, servo_jitter=0.0, friction_sd=0.0), robots, seed)


def write_params(args: argparse.Namespace, path: Path) -> dict[str, Any]:
    """The run's parameter file: the shared stack.yaml with the demo's amplitude, plus per-robot phases.

    ``/**`` is the shipped ``config/stack.yaml`` with ``alpha_max_deg`` replaced; ``/sim_bridge`` gets the
    phase jitter and ``/smarticle_<k>/gait`` and ``/smarticle_<k>/feedback`` their robot's phase (from the
    sim bridge's own scene, so the start shape and the gaits agree) and, with ``--clock-noise``, its clock
    rate offset (``clock_offsets``); ``/glider_monitor`` the glider length.
    Returns the shared settings (period, start_at, ...).
    """
    import yaml
    from smarticle_sim.bridge import BridgeSettings

    from .launch_files import package_share

    stack = yaml.safe_load((package_share('smarticle_bringup') / 'config' / 'stack.yaml').read_text(encoding='utf-8'))
    shared = dict(stack['/**']['ros__parameters'], alpha_max_deg=float(args.alpha_max))
    scene = {'robots': args.robots, 'scene': args.scene, 'seed': args.seed, 'phase_jitter': args.phase_jitter}
    robots = BridgeSettings.defaults(alpha_max_deg=args.alpha_max, period=shared['period'], **scene).scene().robots
    data: dict[str, Any] = {'/**': {'ros__parameters': shared},
                            '/sim_bridge': {'ros__parameters': {'phase_jitter': float(args.phase_jitter)}},
                            '/glider_monitor': {'ros__parameters': {'min_periods': args.min_periods}}}
    offsets = clock_offsets(len(robots), args.seed) if args.clock_noise else None
    for k, robot in enumerate(robots):
        phase = float(robot.gait.phase) if robot.gait is not None else 0.0
        own: dict[str, Any] = {'phase': phase}
        if offsets is not None:
            own['clock_rate_offset'] = float(offsets[k])
        for node in ('gait', 'feedback'):
            data[f'/smarticle_{k}/{node}'] = {'ros__parameters': dict(own)}
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding='utf-8')
    return shared


def run_stack(args: argparse.Namespace, log_dir: Path) -> tuple[np.ndarray, np.ndarray, float, str]:
    """Run sim.launch.xml and listen; return sample times (s after the start), poses (T, N, 3), RTF, trouble."""
    import os

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from smarticle_bags.metadata import read_metadata
    from smarticle_common import topics
    from smarticle_common.launching import DomainReservation, isolated_ros_env
    from smarticle_common.messages import planar_poses

    from .launch_files import package_share, resolve
    from .launcher import Launch

    reservation = None if 'ROS_DOMAIN_ID' in os.environ else DomainReservation()
    env = isolated_ros_env(reservation.domain_id if reservation else None)
    os.environ.update({k: env[k] for k in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')})
    log_dir.mkdir(parents=True, exist_ok=True)
    params = log_dir.parent / 'params.yaml'
    shared = write_params(args, params)
    start_at, period = shared['start_at'], shared['period']
    duration = start_at + args.periods * period
    samples: dict[int, np.ndarray] = {}

    def on_poses(msg: Any) -> None:
        stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        samples[stamp] = planar_poses(msg)

    live: dict[str, Any] = {}

    def on_gliders(msg: Any) -> None:
        live['gliders'] = msg

    bag = log_dir.parent / 'bag'
    if bag.exists():
        shutil.rmtree(bag)  # the previous demo run's bag
    listeners = 3 + (1 if args.view else 0)   # the monitor, the recorder, this demo (and the live view)
    plan = resolve(package_share('smarticle_bringup') / 'launch' / 'sim.launch.xml', {
        'robots': str(args.robots), 'scene': args.scene, 'seed': str(args.seed), 'duration': repr(float(duration)),
        'feedback': str(args.feedback).lower(), 'composed': str(not args.separate).lower(),
        'wait_for_subscribers': str(listeners), 'record': 'true', 'bag': str(bag),
        'view': str(args.view).lower(), 'view_port': str(args.view_port), 'params_file': str(params)})
    rclpy.init()
    node = rclpy.create_node('demo_listener')
    deep = QoSProfile(depth=5000, reliability=ReliabilityPolicy.BEST_EFFORT)  # keep every sample we are sent
    node.create_subscription(PoseArray, topics.topic('poses'), on_poses, deep)
    node.create_subscription(DiagnosticArray, topics.topic('gliders'), on_gliders,
                             topics.qos_profile(topics.spec_of('gliders').qos))
    halts = [0] * args.robots

    def count_halt(robot: int, _msg: Any) -> None:
        halts[robot] += 1
    if args.feedback:
        from std_msgs.msg import Header

        for k in range(args.robots):
            node.create_subscription(Header, topics.topic('halt', k), functools.partial(count_halt, k),
                                     topics.qos_profile(topics.spec_of('halt').qos))
    launch = Launch(plan, log_dir, env)
    try:
        launch.start()
        driver = next(r for r in launch.running if r.node.on_exit_shutdown)   # the sim bridge, or its host
        feedback = f'{args.robots} feedback nodes + ' if args.feedback else ''
        how = 'as separate processes' if args.separate else 'composed in one process (smarticle-compose)'
        print(f'[demo] sim.launch.xml: sim bridge + {args.robots} gait nodes + {feedback}glider monitor {how}, '
              f'+ recorder{" + live view on ws://localhost:" + str(args.view_port) if args.view else ""} '
              f'(domain {env["ROS_DOMAIN_ID"]}, logs in {log_dir}); simulating {args.periods:g} periods = '
              f'{duration:.1f} s', flush=True)
        wall0 = time.monotonic()
        last = wall0
        graph: list[str] = []
        expected_nodes = args.robots * (2 if args.feedback else 1) + 4 + (1 if args.view else 0)
        while driver.proc.poll() is None:
            rclpy.spin_once(node, timeout_sec=0.05)
            if samples and len(graph) < expected_nodes:     # keep the fullest view of the graph
                now_seen = [f'{ns.rstrip("/")}/{name}' for name, ns in node.get_node_names_and_namespaces()]
                graph = now_seen if len(now_seen) > len(graph) else graph
            if time.monotonic() - last > 5.0 and samples:
                last = time.monotonic()
                sim = max(samples) * 1e-9
                print(f'[demo] sim time {sim:6.1f} / {duration:.1f} s  ({sim / duration:4.0%}), '
                      f'{sim / (last - wall0):.1f}x real time', flush=True)
        for _ in range(20):
            rclpy.spin_once(node, timeout_sec=0.02)
        wall = time.monotonic() - wall0
        trouble = ''
        code = driver.proc.returncode
        if code == SIM_TROUBLE_EXIT:   # the physics stopped: keep what arrived, say why
            lines = [line for line in launch.output(driver).splitlines() if 'sim trouble' in line]
            trouble = lines[-1].split('sim trouble: ', 1)[-1] if lines else 'sim trouble'
        elif code != 0:
            raise RuntimeError(f'{driver.node.full_name} exited with code {code}:\n' + launch.output(driver)[-2000:])
        launch.stop()                                  # SIGINT: the recorder closes the bag
        info = read_metadata(bag)
        print(f'[demo] recorded {info.message_count} messages of {len(info.topics)} topics to {bag} '
              f'(smarticle-bag info {bag})')
        if args.feedback:
            print('[demo] feedback halts per robot: ' + ', '.join(f'{k}: {n}' for k, n in enumerate(halts)))
        report_graph(graph, log_dir.parent / 'nodes.txt')
        report = live.get('gliders')
        pairs = [status.name for status in report.status] if report is not None else []
        print(f'[demo] live glider monitor, last report: {len(pairs)} bound pair(s) '
              + (', '.join(pairs) if pairs else ''))
    finally:
        launch.stop()
        node.destroy_node()
        rclpy.try_shutdown()
        if reservation is not None:
            reservation.close()
    stamps = np.array(sorted(samples))
    poses = np.array([samples[s] for s in stamps])
    rtf = (stamps[-1] * 1e-9) / wall if len(stamps) else 0.0
    return stamps * 1e-9 - start_at, poses, rtf, trouble


def main(argv: list[str] | None = None) -> int:
    """Run the demo; return the exit code."""
    import matplotlib

    matplotlib.use('Agg')
    from smarticle_tracking.gliders import GliderConfig
    from smarticle_tracking.report import glider_report

    args = build_parser().parse_args(argv)
    if args.robots < 1 or args.periods <= 0:
        print('demo: --robots must be >= 1 and --periods > 0', file=sys.stderr)
        return 2
    args.out = args.out.resolve()   # launch files resolve relative paths against their own folder
    args.out.mkdir(parents=True, exist_ok=True)
    times, poses, rtf, trouble = run_stack(args, args.out / 'logs')
    if trouble:
        print(f'[demo] THE SIMULATION STOPPED EARLY: {trouble}\n[demo] the analysis below covers the run up to '
              'that point (the physics at the default settings is not yet stable: docs/physics_study.md)')
    keep = times >= 0.0
    times, poses = times[keep], poses[keep]
    save_npz(Recording.from_poses(times, poses, SMALL.body_length,
                                  {'source': 'demo: /smarticles/poses over DDS', 'periods': args.periods,
                                   'seed': args.seed, 'scene': args.scene, 'trouble': trouble}),
             args.out / 'poses.npz')
    config = GliderConfig(min_periods=args.min_periods)
    report = glider_report(times, poses, config, args.out / 'gliders.png')
    print(f'\n[demo] {args.robots} robots, {args.scene} start, alpha_max {args.alpha_max:g} deg, '
          f'{times[-1] / GAIT_PERIOD:.0f} periods received over DDS, {rtf:.1f}x real time')
    print(f'[demo] gliders (pairs bound >= {args.min_periods} periods; bound = centre distance under '
          f'{config.r_bind / config.body_length:.1f} BL in some frame of each period, from poses alone (the one '
          'rule of docs/gliders.md); isolated = no third robot within 2 W in >= 90 % of its periods):')
    print(report.table)
    moved = np.linalg.norm(poses[-1, :, :2] - poses[0, :, :2], axis=1) / config.width
    print('[demo] net displacement of each robot (W): ' + ', '.join(f'{k}: {d:.2f}' for k, d in enumerate(moved)))
    plot_trajectories(times, poses, config.width, args.out / 'trajectories.png')
    written = [args.out / 'trajectories.png', args.out / 'poses.npz']
    if report.figure is not None:
        written.append(report.figure)
    print('[demo] wrote ' + ', '.join(str(p) for p in written))
    return 0


def plot_trajectories(times: np.ndarray, poses: np.ndarray, width: float, path: Path) -> None:
    """Draw every robot's body-centre path (in W) with start and end markers."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6, 6), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    xy = poses[:, :, :2] / width
    for k in range(xy.shape[1]):
        line, = ax.plot(xy[:, k, 0], xy[:, k, 1], lw=0.8, label=f'robot {k}')
        ax.plot(*xy[0, k], 'o', color=line.get_color(), ms=4)
        ax.plot(*xy[-1, k], 's', color=line.get_color(), ms=5)
        ax.annotate('', xy=xy[-1, k] + 0.4 * np.array([math.cos(poses[-1, k, 2]), math.sin(poses[-1, k, 2])]),
                    xytext=xy[-1, k], arrowprops={'arrowstyle': '->', 'color': line.get_color()})
    ax.set_aspect('equal')
    ax.set_xlabel('x (W)')
    ax.set_ylabel('y (W)')
    ax.set_title(f'sim-in-the-loop: {xy.shape[1]} robots, {times[-1]:.0f} s (o start, square end, arrow heading)',
                 fontsize=9)
    ax.legend(fontsize=7)
    fig.savefig(path)


def entry() -> None:
    """Console-script entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
