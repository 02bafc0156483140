"""The main demo: the stack in the loop with the sim, showing gliders and the tactile feedback acting.

Two labelled parts, each a run of ``smarticle_bringup/launch/sim.launch.xml`` through the project's launcher
(the file ``ros2 launch`` reads on a board): the sim bridge in lock-step, one gait node per robot (and one
feedback node per robot in part 2) composed in one process on one executor, the live glider monitor and a bag
recorder each in a process of its own (``--separate``: every node its own process); with ``--view`` also the
Foxglove live view. The demo
listens to ``/smarticles/poses``, the joint states and the halts like any other node would, then finds the
gliders with the glider analysis core, prints a table and writes figures, an animation, the poses and an mcap
bag per part to ``out/demo/``.

1. **gliders**: two small robots at P5's start, robot 1's gait a tenth of a period ahead, open loop
   (``demo_scenes.GLIDERS``; ``--scene dense|random`` puts the paper's dense or a random start here instead);
2. **feedback**: two of the paper's larger feedback robots side by side, a quarter period apart, with the
   impact controller (``demo_scenes.FEEDBACK``).

Usage: ``./demo.sh [--seed 1] [--periods 40] [--feedback-periods 12] [--only gliders|feedback] [--scene pair]
[--phase-offset 0.1] [--clock-noise] [--no-feedback] [--no-animation] [--separate] [--view]``; docs/demo.md.
"""

from __future__ import annotations

import argparse
import functools
import math
import shutil
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
from smarticle_common.cli import SeedSyntaxError, add_version, parse_seeds
from smarticle_common.facts import GAIT_PERIOD, RobotSpec
from smarticle_common.runs import Recording, save_npz

from .demo_scenes import FEEDBACK, GLIDERS, MIN_PERIODS, TRAVEL_MIN_W_PER_100, DemoScene, travelling

#: Where the demo's choice and its evidence are written up (relative to the repository root).
DEMO_DOC = 'docs/demo.md'
#: The physics page: what the sim reproduces of the paper and what it does not.
PHYSICS_DOC = 'docs/sim_calibration.md'
#: The one line of the demo's choice: what it runs and why.
CHOICE = ("[demo] chose: two small robots with robot 1's gait 0.1 period ahead (P5's start, seeded jitter), because in "
          'this model two robots exactly in phase settle still while a pair a tenth of a period apart glides, and the '
          "offset stands in for the real robots' phase drift (resonator clocks, 0.29 % sd: docs/sim_core.md; "
          f"{PHYSICS_DOC}); then the feedback on the paper's larger feedback robot, whose collisions reach the impact "
          f"window (the small robot's stay below it); why, and the 10-seed table: {DEMO_DOC}")
#: One sentence on what the sim does not reproduce.
LIMITS = ("[demo] not reproduced: the paper's robots start in phase and form travelling gliders in 64 % of its dense "
          "trials, and its feedback lengthens a C2 glider's life; in this model, as in the authors' own engine, robots "
          f'exactly in phase settle still, and a halt does not hold a C2 pair together: {PHYSICS_DOC}')


class _Parser(argparse.ArgumentParser):
    """argparse whose refusal is one line, ``PROG: error: ...``, and exit code 2."""

    def error(self, message: str) -> NoReturn:
        """Print ``prog: error: message`` on one line and exit 2."""
        sys.stderr.write(f'{self.prog}: error: {message}\n')
        raise SystemExit(2)


def one_seed(text: str) -> int:
    """A seed as the stack's seed syntax takes it (a whole number >= 0; argparse ``type=``)."""
    try:
        seeds = parse_seeds(text)
    except SeedSyntaxError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    if len(seeds) != 1:
        raise argparse.ArgumentTypeError(f'one seed, got {text!r}')
    return seeds[0]


def build_parser(prog: str = 'smarticle-demo') -> argparse.ArgumentParser:
    """Command-line options of the demo; ``prog`` is the name the user typed (``demo.sh`` or ``smarticle-demo``)."""
    parser = _Parser(prog=prog, description=__doc__.split('\n')[0] if __doc__ else None)
    add_version(parser, 'smarticle_bringup')
    parser.add_argument('--seed', type=one_seed, default=1,
                        help='seed of both starts (the jitter of the pair coordinates; default 1)')
    parser.add_argument('--periods', type=float, default=GLIDERS.periods,
                        help=f'part 1 (gliders): gait periods to run (default {GLIDERS.periods:g})')
    parser.add_argument('--feedback-periods', type=float, default=FEEDBACK.periods,
                        help=f'part 2 (feedback): gait periods to run (default {FEEDBACK.periods:g})')
    parser.add_argument('--only', choices=('gliders', 'feedback'), default=None,
                        help='run one part only (default: both)')
    parser.add_argument('--scene', choices=('pair', 'dense', 'random'), default='pair',
                        help="part 1's start: pair (default: P5's pair, robot 1 --phase-offset ahead), dense (the "
                             "paper's densely packed start, Fig. 1(c)) or random")
    parser.add_argument('--phase-offset', type=float, default=GLIDERS.start.phases[1],
                        help='pair: robot 1\'s gait ahead of robot 0\'s by this many periods (default '
                             f'{GLIDERS.start.phases[1]:g}; 0 = exactly in phase, where the pair settles still)')
    parser.add_argument('--robots', type=int, default=7, help='dense and random starts: number of robots (default 7)')
    parser.add_argument('--phase-jitter', type=float, default=0.05,
                        help='dense start: seeded gait-phase offsets in +-this many periods (default 0.05)')
    parser.add_argument('--alpha-max', type=float, default=90.0, help='gait amplitude in degrees (default 90)')
    parser.add_argument('--clock-noise', action='store_true',
                        help="each robot's board clock runs fast or slow by a seeded draw of the cited resonator "
                             'spread (0.29 %% sd; the clock_rate_sd of noise: paper), the same draws as the batch '
                             'path for this seed; its gait and feedback nodes take it as clock_rate_offset')
    parser.add_argument('--feedback', action=argparse.BooleanOptionalAction, default=True,
                        help='part 2 runs the tactile feedback node of each robot (impact window from '
                             'config/stack.yaml; default on); --no-feedback runs the same robots open loop')
    parser.add_argument('--animation', action=argparse.BooleanOptionalAction, default=True,
                        help='write the animation out/demo/demo.gif (default on)')
    parser.add_argument('--frame-step', type=float, default=0.2,
                        help='animation: sim seconds between frames (default 0.2)')
    parser.add_argument('--separate', action='store_true',
                        help='run every node as its own process (default: the stack composed in one process '
                             'on one executor, smarticle-compose; same trajectories, faster)')
    parser.add_argument('--view', action='store_true',
                        help='serve the live view to Foxglove on ws://localhost:8765 (smarticle-view; open it in '
                             'Foxglove with smarticle_bringup/config/foxglove_layout.json)')
    parser.add_argument('--view-port', type=int, default=8765, help='WebSocket port of --view (default 8765)')
    parser.add_argument('--preset', default=None, metavar='FILE',
                        help="a preset file (smarticle-calibrate's preset.yaml) for every part's robots "
                        "(default: each part's own preset)")
    parser.add_argument('--out', type=Path, default=Path('out/demo'), help='output folder (default out/demo)')
    return parser


def option_problem(args: argparse.Namespace) -> str | None:
    """The first bad option as one line, or None. An option that becomes a node's parameter is checked with that
    parameter's own range (the sim bridge's table; the gait's amplitude range is the same ``ALPHA_MAX_RANGE_DEG``),
    so the demo refuses what the nodes would refuse, before anything starts."""
    from smarticle_common.params import ParameterError, ParamSpec
    from smarticle_sim.bridge import PARAMS as BRIDGE_PARAMS

    bridge = {spec.name: spec for spec in BRIDGE_PARAMS}
    for option in ('--periods', '--feedback-periods', '--frame-step'):
        value = getattr(args, option[2:].replace('-', '_'))
        if not (math.isfinite(value) and value > 0):
            return f'{option} must be a number > 0, got {value:g}'
    if args.preset is not None:
        from smarticle_sim.config_builder import build_config, is_preset_file
        from smarticle_sim.errors import ConfigError

        if not is_preset_file(args.preset):
            return f'--preset must be a preset file (.yaml), got {args.preset!r}'
        try:
            build_config(args.preset)
        except ConfigError as err:
            return f'--preset: {err}'
    sim = 'the sim bridge parameter'
    checks: list[tuple[str, str, ParamSpec, Any]] = [
        ('--alpha-max', 'the gait and sim bridge parameter', bridge['alpha_max_deg'], args.alpha_max),
        ('--periods', sim, bridge['duration'], args.periods * GAIT_PERIOD),
        ('--feedback-periods', sim, bridge['duration'], args.feedback_periods * GAIT_PERIOD),
        ('--seed', sim, bridge['seed'], args.seed),
        ('--robots', sim, bridge['robots'], args.robots),
        ('--phase-jitter', sim, bridge['phase_jitter'], args.phase_jitter),
        ('--phase-offset', 'the gait and sim bridge parameter', bridge['pair_phase_1'], args.phase_offset)]
    if args.view:
        from .view_node import PARAMS as VIEW_PARAMS

        checks.append(('--view-port', 'the live view parameter', next(s for s in VIEW_PARAMS if s.name == 'port'),
                       args.view_port))
    for option, node, spec, value in checks:
        try:
            spec.check(value, source=node)
        except ParameterError as err:
            return f'{option}: {err}'
    return None


@dataclass(frozen=True)
class Part:
    """One part of the demo as the stack runs it."""

    key: str                              # output subfolder and label: 'gliders' or 'feedback'
    title: str
    spec: RobotSpec
    scene_kind: str                       # the sim bridge's scene: pair, dense or random
    robots: int
    periods: float
    feedback: bool
    bridge: dict[str, Any]                # /sim_bridge parameters besides the launch file's
    own: list[dict[str, Any]]             # each robot's gait / feedback parameters (phase, clock offset)
    start: str                            # how the robots start, one phrase
    demo_scene: DemoScene | None          # the pair scene of demo_scenes, None for dense / random


def clock_offsets(robots: int, seed: int) -> np.ndarray:
    """Each robot's board-clock rate offset for ``--clock-noise``: the batch path's draws (``noise.clock_rates``)
    of the cited clock spread for the trial seed ``seed``, so a ROS run and a batch run of the seed agree."""
    from smarticle_sim.noise import clock_rates
    from smarticle_sim.settings import CLOCK_RATE_SD, NoiseConfig

    return clock_rates(NoiseConfig(clock_rate_sd=CLOCK_RATE_SD, servo_jitter=0.0, friction_sd=0.0), robots, seed)


def pair_part(scene: DemoScene, args: argparse.Namespace, periods: float, feedback: bool) -> Part:
    """A part running one of ``demo_scenes``' pair scenes for the seed of ``args``."""
    start = scene.start_for(args.seed)
    offsets = clock_offsets(2, args.seed) if args.clock_noise else None
    ahead = (start.phases[1] - start.phases[0]) % 1.0
    how = (f'{scene.spec.name} robots, r {start.r_bl:.2f} BL, theta {start.theta_deg:.0f}, phi {start.phi_deg:.0f} '
           f'deg, robot 1 {ahead:g} period ahead, {"feedback" if feedback else "open loop"}')
    title = scene.title if feedback or not scene.feedback else \
        f'{scene.spec.name} robots collide, the controller off (--no-feedback): no halts, for comparison'
    return Part(scene.key, title, scene.spec, 'pair', 2, periods, feedback, scene.bridge_params(args.seed),
                scene.robot_params(args.seed, offsets), how, scene)


def crowd_part(args: argparse.Namespace) -> Part:
    """Part 1 with the dense or random start of the sim bridge (``--scene dense|random``), open loop."""
    from smarticle_sim.bridge import BridgeSettings

    preset = args.preset or 'small'
    robots = BridgeSettings.defaults(alpha_max_deg=args.alpha_max, robots=args.robots, scene=args.scene,
                                     seed=args.seed, phase_jitter=args.phase_jitter, preset=preset).scene().robots
    offsets = clock_offsets(len(robots), args.seed) if args.clock_noise else None
    own = []
    for k, robot in enumerate(robots):
        values: dict[str, Any] = {'phase': float(robot.gait.phase) if robot.gait is not None else 0.0}
        if offsets is not None:
            values['clock_rate_offset'] = float(offsets[k])
        own.append(values)
    jitter = f', phases +-{args.phase_jitter:g} period' if args.scene == 'dense' else ''
    spec = replace(GLIDERS, preset=preset).spec
    return Part('gliders', f'gliders from a {args.scene} start (open loop)', spec, args.scene,
                args.robots, args.periods, False, {'preset': preset, 'phase_jitter': float(args.phase_jitter)},
                own, f'{args.robots} small robots, {args.scene} start{jitter}, open loop', None)


def plan_parts(args: argparse.Namespace) -> list[Part]:
    """The parts to run, in order."""
    parts = []
    if args.only in (None, 'gliders'):
        if args.scene == 'pair':
            scene = replace(GLIDERS, alpha_max_deg=args.alpha_max, preset=args.preset or GLIDERS.preset,
                            start=replace(GLIDERS.start, phases=(0.0, args.phase_offset % 1.0)))
            parts.append(pair_part(scene, args, args.periods, False))
        else:
            parts.append(crowd_part(args))
    if args.only in (None, 'feedback'):
        feedback = replace(FEEDBACK, alpha_max_deg=args.alpha_max, preset=args.preset or FEEDBACK.preset)
        parts.append(pair_part(feedback, args, args.feedback_periods, args.feedback))
    return parts


def shown(path: Path) -> str:
    """``path`` as the demo prints it: relative to the working directory when it lies below it."""
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def report_graph(names: list[str], path: Path) -> None:
    """Print the ROS graph seen during the run and write it to ``path``; name any node name used twice."""
    seen = sorted(names)
    twice = sorted({n for n in seen if seen.count(n) > 1})
    path.write_text('\n'.join(seen) + '\n', encoding='utf-8')
    print(f'[demo] ROS graph: {len(seen)} nodes, ' + (f'names used twice: {", ".join(twice)}' if twice else
                                                       'every fully qualified name distinct') + f' ({shown(path)})')


#: Exit code of the sim bridge when the physics hit trouble (SimTrouble): the run stopped early.
SIM_TROUBLE_EXIT = 3


def write_params(part: Part, args: argparse.Namespace, path: Path) -> dict[str, Any]:
    """The part's parameter file: the shared stack.yaml with the demo's amplitude, plus the part's own.

    ``/**`` is the shipped ``config/stack.yaml`` with ``alpha_max_deg`` replaced; ``/sim_bridge`` gets the
    part's robot preset and start (``Part.bridge``); ``/smarticle_<k>/gait`` and ``/smarticle_<k>/feedback``
    their robot's phase and, with ``--clock-noise``, its clock rate offset (the gait also the preset's servo
    speed); ``/glider_monitor`` the demo's glider rule in this robot's body length; ``/view`` (with ``--view``)
    the preset whose outline it draws.
    Returns the shared settings (period, start_at, ...).
    """
    import yaml
    from smarticle_common.facts import R_BIND_BL

    from .launch_files import package_share

    stack = yaml.safe_load((package_share('smarticle_bringup') / 'config' / 'stack.yaml').read_text(encoding='utf-8'))
    shared = dict(stack['/**']['ros__parameters'], alpha_max_deg=float(args.alpha_max))
    bl = part.spec.body_length
    data: dict[str, Any] = {'/**': {'ros__parameters': shared},
                            '/sim_bridge': {'ros__parameters': dict(part.bridge)},
                            '/glider_monitor': {'ros__parameters': {'min_periods': MIN_PERIODS, 'body_length': bl,
                                                                    'r_bind': R_BIND_BL * bl,
                                                                    'travel_min_w_per_100': TRAVEL_MIN_W_PER_100}},
                            '/view': {'ros__parameters': {'preset': part.spec.name}}}
    for k, own in enumerate(part.own):
        data[f'/smarticle_{k}/gait'] = {'ros__parameters': dict(own, servo_speed=float(part.spec.servo_speed))}
        data[f'/smarticle_{k}/feedback'] = {'ros__parameters': dict(own)}
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding='utf-8')
    return shared


def node_names(node: Any) -> list[str]:
    """The fully qualified names of the nodes ``node`` sees in the ROS graph now."""
    return [f'{ns.rstrip("/")}/{name}' for name, ns in node.get_node_names_and_namespaces()]


@dataclass
class StackRun:
    """What the demo received from one part's run: times (s after the gait start), poses (T, N, 3), arm angles
    (T, N, 2; NaN where no joint state came), halts (s after the start, robot, face), speed and trouble."""

    times: np.ndarray
    poses: np.ndarray
    arms: np.ndarray
    halts: list[tuple[float, int, str]]
    rtf: float
    wall: float
    trouble: str


def run_stack(part: Part, args: argparse.Namespace, folder: Path) -> StackRun:
    """Run sim.launch.xml for ``part`` and listen to it; return what arrived."""
    import os

    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseArray
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from smarticle_bags.metadata import read_metadata
    from smarticle_common import topics
    from smarticle_common.launching import DomainReservation, isolated_ros_env
    from smarticle_common.messages import planar_poses
    from std_msgs.msg import Header

    from .launch_files import package_share, resolve
    from .launcher import Launch

    log_dir = folder / 'logs'
    reservation = None if 'ROS_DOMAIN_ID' in os.environ else DomainReservation()
    env = isolated_ros_env(reservation.domain_id if reservation else None)
    saved = {k: os.environ.get(k) for k in ('ROS_DOMAIN_ID', 'ROS_AUTOMATIC_DISCOVERY_RANGE')}
    os.environ.update({k: env[k] for k in saved})
    log_dir.mkdir(parents=True, exist_ok=True)
    params = folder / 'params.yaml'
    shared = write_params(part, args, params)
    start_at, period = shared['start_at'], shared['period']
    duration = start_at + part.periods * period
    samples: dict[int, np.ndarray] = {}
    joints: dict[int, np.ndarray] = {}
    halts: list[tuple[float, int, str]] = []
    live: dict[str, Any] = {}
    n = part.robots

    def stamp_of(msg: Any) -> int:
        return int(msg.header.stamp.sec) * 10**9 + int(msg.header.stamp.nanosec)

    def on_poses(msg: Any) -> None:
        samples[stamp_of(msg)] = planar_poses(msg)

    def on_joints(robot: int, msg: Any) -> None:
        row = joints.setdefault(stamp_of(msg), np.full((n, 2), np.nan))
        for name, angle in zip(msg.name, msg.position, strict=False):
            if name in topics.JOINT_NAMES:
                row[robot, topics.JOINT_NAMES.index(name)] = angle

    def on_halt(robot: int, msg: Any) -> None:
        halts.append(((msg.stamp.sec * 10**9 + msg.stamp.nanosec) * 1e-9 - start_at, robot, msg.frame_id))

    def on_gliders(msg: Any) -> None:
        live['gliders'] = msg

    bag = folder / 'bag'
    if bag.exists():
        shutil.rmtree(bag)  # the previous demo run's bag
    listeners = 2 + (1 if args.view else 0)   # the monitor, this demo (and the view); record:=true adds the recorder
    plan = resolve(package_share('smarticle_bringup') / 'launch' / 'sim.launch.xml', {
        'robots': str(n), 'scene': part.scene_kind, 'seed': str(args.seed), 'duration': repr(float(duration)),
        'feedback': str(part.feedback).lower(), 'composed': str(not args.separate).lower(),
        'wait_for_subscribers': str(listeners), 'record': 'true', 'bag': str(bag),
        'view': str(args.view).lower(), 'view_port': str(args.view_port), 'params_file': str(params)})
    rclpy.init()
    node = rclpy.create_node('demo_listener')
    deep = QoSProfile(depth=5000, reliability=ReliabilityPolicy.BEST_EFFORT)  # keep every sample we are sent
    node.create_subscription(PoseArray, topics.topic('poses'), on_poses, deep)
    node.create_subscription(DiagnosticArray, topics.topic('gliders'), on_gliders,
                             topics.qos_profile(topics.spec_of('gliders').qos))
    joint_state = topics.message_class(topics.spec_of('joint_states').type)
    for k in range(n):
        node.create_subscription(joint_state, topics.topic('joint_states', k), functools.partial(on_joints, k), deep)
        if part.feedback:
            node.create_subscription(Header, topics.topic('halt', k), functools.partial(on_halt, k),
                                     topics.qos_profile(topics.spec_of('halt').qos))
    launch = Launch(plan, log_dir, env)
    try:
        launch.start()
        driver = next(r for r in launch.running if r.node.on_exit_shutdown)   # the sim bridge, or its host
        feedback = f' + {n} feedback nodes' if part.feedback else ''
        how = 'as separate processes, + glider monitor' if args.separate else \
            'composed in one process (smarticle-compose), + glider monitor'
        print(f'\n[demo] {part.key}: sim.launch.xml: sim bridge + {n} gait nodes{feedback} {how}'
              f' + recorder{" + live view on ws://localhost:" + str(args.view_port) if args.view else ""} '
              f'(domain {env["ROS_DOMAIN_ID"]}, logs in {shown(log_dir)}); simulating {part.periods:g} periods = '
              f'{duration:.1f} s', flush=True)
        wall0 = time.monotonic()
        last = wall0
        graph: list[str] = []
        expected_nodes = n * (2 if part.feedback else 1) + 4 + (1 if args.view else 0)
        while driver.proc.poll() is None:
            rclpy.spin_once(node, timeout_sec=0.05)
            if len(graph) < expected_nodes:     # the fullest view of the graph, from the start (a short run on a
                # loaded machine can end before discovery has shown every node that was up while it waited)
                now_seen = node_names(node)
                graph = now_seen if len(now_seen) > len(graph) else graph
            if time.monotonic() - last > 5.0 and samples:
                last = time.monotonic()
                sim = max(samples) * 1e-9
                print(f'[demo] {part.key}: sim time {sim:6.1f} / {duration:.1f} s  ({sim / duration:4.0%}), '
                      f'{sim / (last - wall0):.1f}x real time', flush=True)
        for _ in range(20):
            rclpy.spin_once(node, timeout_sec=0.02)
        wall = time.monotonic() - wall0
        deadline = time.monotonic() + 2.0   # the monitor and the recorder outlive the bridge until launch.stop()
        while len(graph) < expected_nodes and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.05)
            now_seen = node_names(node)
            graph = now_seen if len(now_seen) > len(graph) else graph + [n for n in now_seen if n not in graph]
        trouble = ''
        code = driver.proc.returncode
        if code == SIM_TROUBLE_EXIT:   # the physics stopped: keep what arrived, say why
            lines = [line for line in launch.output(driver).splitlines() if 'sim trouble' in line]
            trouble = lines[-1].split('sim trouble: ', 1)[-1] if lines else 'sim trouble'
        elif code != 0:
            raise RuntimeError(f'{driver.node.full_name} exited with code {code}:\n' + launch.output(driver)[-2000:])
        launch.stop()                                  # SIGINT: the recorder closes the bag
        info = read_metadata(bag)
        print(f'[demo] {part.key}: recorded {info.message_count} messages of {len(info.topics)} topics, '
              f'{info.duration * 1e-9:.1f} s of sim time, to {shown(bag)} (smarticle-bag info {shown(bag)})')
        report_graph(graph, folder / 'nodes.txt')
        report = live.get('gliders')
        pairs = [f'{s.name} ({s.message})' for s in report.status] if report is not None else []
        print(f'[demo] {part.key}: live glider monitor, last report: {len(pairs)} pair(s) bound now'
              + (': ' + ', '.join(pairs) if pairs else ''))
    finally:
        launch.stop()
        node.destroy_node()
        rclpy.try_shutdown()
        if reservation is not None:
            reservation.close()
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
    stamps = np.array(sorted(samples), dtype=np.int64)
    poses = np.array([samples[s] for s in stamps]).reshape(len(stamps), n, 3)
    arms = np.array([joints.get(int(s), np.full((n, 2), np.nan)) for s in stamps]).reshape(len(stamps), n, 2)
    times = stamps * 1e-9 - start_at
    rtf = (stamps[-1] * 1e-9) / wall if len(stamps) else 0.0
    keep = times >= -1e-9
    return StackRun(times[keep], poses[keep], arms[keep], sorted(halts), rtf, wall, trouble)


def glider_lines(gliders: Any, width: float) -> str:
    """The table of bound pairs the demo prints: pair, what it is (class and kind), mean phi, lifetime, travel in W
    and per 100 periods, whether it travels (a glider)."""
    if not gliders:
        return '  none'
    rows = [('pair', 'what', 'mean phi [deg]', 'from period', 'lifetime [periods]', 'bound at the end', 'r [BL]',
             'travel [W]', 'W per 100 periods', f'travels (>= {TRAVEL_MIN_W_PER_100:g} W per 100 periods)')]
    for g in gliders:
        rows.append((f'{g.i}-{g.j}', g.label, f'{math.degrees(g.phi_mean):.0f}', str(g.start_period),
                     str(g.lifetime_periods), 'yes' if g.ongoing else 'no', f'{g.r_mean / width:.2f}',
                     f'{g.distance / width:.2f}', f'{g.travel_w_per_100:.1f}', 'yes' if travelling(g) else 'no'))
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
    return '\n'.join('  ' + '  '.join(cell.rjust(w) for cell, w in zip(r, widths, strict=True)) for r in rows)


def report_part(part: Part, run: StackRun, out: Path) -> tuple[Any, list[str]]:
    """Analyse one part's run, print its summary lines, write its figures; return the analysis and the files."""
    from smarticle_tracking.gliders import GliderConfig
    from smarticle_tracking.report import glider_report

    from .demo_figures import plot_halts, plot_trajectories

    width = part.spec.body_length
    recording = Recording.from_poses(run.times, run.poses, width,
                                     {'source': 'demo: /smarticles/poses and joint states over DDS',
                                      'periods': part.periods, 'part': part.key, 'trouble': run.trouble})
    save_npz(replace(recording, arm_angles=run.arms, meta={**recording.meta, 'arm_angles_recorded': True}),
             out / 'poses.npz')
    config = part.demo_scene.glider_config() if part.demo_scene else GliderConfig(min_periods=MIN_PERIODS)
    report = glider_report(run.times, run.poses, config, out / 'gliders.png')
    (out / 'gliders.txt').write_text(report.table + '\n', encoding='utf-8')
    received = run.times[-1] / GAIT_PERIOD if len(run.times) else 0.0
    print(f'[demo] part {part.key}: {part.title}\n[demo]   {part.start}; {received:.0f} periods received over '
          f'DDS, {run.rtf:.1f}x real time ({run.wall:.0f} s)')
    if run.trouble:
        print(f'[demo]   THE SIMULATION STOPPED EARLY: {run.trouble}; the analysis covers the run up to then')
    print(f'[demo]   {report.summary}:\n[demo]   ({report.rule}; travel = net displacement of its centre '
          f'in W = BL = {width * 100:.1f} cm)')
    print(glider_lines(report.analysis.gliders, width))
    written = [plot_trajectories(run.times, run.poses, width, out / 'trajectories.png', part.key)]
    if report.figure is not None:
        written.append(report.figure)
    if part.feedback:
        per = [sum(1 for _, k, _ in run.halts if k == robot) for robot in range(part.robots)]
        first = f' (first at {run.halts[0][0]:.2f} s after the start)' if run.halts else ''
        print('[demo]   feedback halts per robot: ' + ', '.join(f'{k}: {c}' for k, c in enumerate(per)) + first)
        written.append(plot_halts(run.times, run.poses, run.halts, width, out / 'halts.png',
                                  f'{part.key}: r of the pair and the halts ({sum(per)})'))
    return report.analysis, [shown(p) for p in written]


def main(argv: list[str] | None = None, prog: str = 'smarticle-demo') -> int:
    """Run the demo; return the exit code."""
    import matplotlib

    matplotlib.use('Agg')
    from smarticle_sim.errors import SceneError

    from smarticle_tracking.gliders import running_labels

    from .demo_figures import AnimatedPart, GliderSpan, write_animation

    args = build_parser(prog).parse_args(argv)
    problem = option_problem(args)
    if problem is not None:
        print(f'{prog}: error: {problem}', file=sys.stderr)
        return 2
    try:
        parts = plan_parts(args)
    except SceneError as err:
        print(f'{prog}: error: {err}', file=sys.stderr)
        return 2
    if args.scene == 'pair' and args.only != 'feedback':
        print(CHOICE, flush=True)
    else:
        print(f'[demo] as asked: {", ".join(p.start for p in parts)}; the default scene and why: {DEMO_DOC}',
              flush=True)
    args.out = args.out.resolve()   # launch files resolve relative paths against their own folder
    wall0 = time.monotonic()
    animated = []
    files: list[str] = []
    for index, part in enumerate(parts):
        folder = args.out / part.key
        folder.mkdir(parents=True, exist_ok=True)
        run = run_stack(part, args, folder)
        analysis, written = report_part(part, run, folder)
        files += written
        width = part.spec.body_length
        spans = [GliderSpan(g.i, g.j, g.glider_class.value, g.start_time, g.end_time, g.distance / width,
                            running_labels(analysis, g)) for g in analysis.gliders]
        animated.append(AnimatedPart(f'part {index + 1} ({part.key}): {part.start}', part.spec, run.times,
                                     run.poses, run.arms, spans, run.halts, [o['phase'] for o in part.own]))
    if args.animation and animated:
        files.append(shown(write_animation(animated, args.out / 'demo.gif', step=args.frame_step)))
    print('\n' + LIMITS)
    print(f'[demo] wrote {", ".join(files)} (and per part poses.npz, bag/, params.yaml, logs/) in '
          f'{time.monotonic() - wall0:.0f} s')
    return 0


def entry() -> None:
    """Console-script entry point (``smarticle-demo``)."""
    raise SystemExit(main())


if __name__ == '__main__':   # run by demo.sh
    raise SystemExit(main(prog='demo.sh'))
