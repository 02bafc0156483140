"""``smarticle-bag``: info, record, play, analyze, export, reindex, import and clocks (``ros2 bag``'s flag names)."""

from __future__ import annotations

import argparse
import logging
import math
import sys
from pathlib import Path
from typing import Any

from .errors import BagError
from .parameters import PLAYER_PARAMS, RECORDER_PARAMS, default
from smarticle_common.facts import GAIT_PERIOD
from smarticle_common.cli import add_version, closed_pipe_safe

PROG = 'smarticle-bag'


def _split_ros_args(argv: list[str]) -> tuple[list[str], list[str] | None]:
    """Split ``argv`` at ``--ros-args`` into (our arguments, rclpy arguments or None)."""
    if '--ros-args' in argv:
        at = argv.index('--ros-args')
        return argv[:at], [PROG, *argv[at:]]
    return argv, None


def _add_record(sub: Any) -> None:
    """Add the ``record`` subcommand."""
    p = sub.add_parser('record', help='record topics into a rosbag2-compatible mcap bag',
                       description='Record topics into a bag folder (metadata.yaml + .mcap). '
                                   'Stop with Ctrl-C; a killed recorder leaves a bag readable up to the '
                                   'last flushed chunk (repair it with "smarticle-bag reindex").')
    p.add_argument('topic_names', nargs='*', metavar='TOPIC', help='topics to record')
    p.add_argument('--topics', nargs='+', default=[], metavar='TOPIC',
                   help='topics to record (same as positional)')
    p.add_argument('-a', '--all', action='store_true',
                   help='record all topics, including ones that appear later')
    p.add_argument('-e', '--regex', default=default(RECORDER_PARAMS, 'regex'),
                   help='record topics matching this regular expression')
    p.add_argument('-x', '--exclude-regex', default=default(RECORDER_PARAMS, 'exclude_regex'),
                   help='never record topics matching this regular expression')
    p.add_argument('--include-hidden-topics', action='store_true', help='let -a/-e match hidden topics')
    p.add_argument('-o', '--output', default=default(RECORDER_PARAMS, 'output'),
                   help='bag folder to create (default: rosbag2_YYYY_MM_DD-HH_MM_SS)')
    p.add_argument('-s', '--storage', default='mcap', choices=['mcap'], help='storage plugin (only mcap)')
    p.add_argument('--storage-preset-profile', default=default(RECORDER_PARAMS, 'storage_preset_profile'),
                   choices=['none', 'fastwrite', 'zstd_fast', 'zstd_small', 'lz4'],
                   help='mcap writer preset (chunk compression and size)')
    p.add_argument('--compression-format', default=default(RECORDER_PARAMS, 'compression_format'),
                   choices=['', 'zstd', 'lz4', 'none'], help='mcap chunk compression (overrides the preset)')
    p.add_argument('--chunk-size', type=int, default=default(RECORDER_PARAMS, 'chunk_size'),
                   help='mcap chunk size in bytes (0 = the preset)')
    p.add_argument('-b', '--max-bag-size', type=int, default=default(RECORDER_PARAMS, 'max_bag_size'),
                   help='split after this many bytes (0 = never)')
    p.add_argument('-d', '--max-bag-duration', type=float,
                   default=default(RECORDER_PARAMS, 'max_bag_duration'),
                   help='split after this many seconds (0 = never)')
    p.add_argument('--flush-interval', type=float, default=default(RECORDER_PARAMS, 'flush_interval'),
                   help='write the open chunk to disk at least every this many seconds')
    p.add_argument('--polling-interval', type=float,
                   default=default(RECORDER_PARAMS, 'topic_polling_interval'),
                   help='look for new topics every this many seconds')
    p.add_argument('--use-sim-time', action='store_true',
                   help='stamp log time with the sim\'s /clock (a sim run lasts its simulated time in the bag); '
                        'messages before the first /clock are held until it arrives')


def _add_play(sub: Any) -> None:
    """Add the ``play`` subcommand."""
    p = sub.add_parser('play', help='replay a bag into live nodes',
                       description='Replay a bag (folder or .mcap, ours or made by rosbag2) with its '
                                   'recorded '
                                   'timing. Pause/resume: publish std_msgs/msg/Bool on /player/pause '
                                   '(true/false), or press space in the terminal.')
    p.add_argument('bag', help='bag folder or .mcap file')
    p.add_argument('--topics', nargs='+', default=[], metavar='TOPIC', help='play only these topics')
    p.add_argument('-m', '--remap', nargs='+', default=[], metavar='OLD:=NEW', help='publish OLD under NEW')
    p.add_argument('-r', '--rate', type=float, default=default(PLAYER_PARAMS, 'rate'),
                   help='speed factor (> 0)')
    p.add_argument('-l', '--loop', action='store_true',
                   help='play again from the start when the end is reached')
    p.add_argument('--clock', type=float, nargs='?', const=40.0, default=default(PLAYER_PARAMS, 'clock'),
                   metavar='HZ', help='publish /clock from bag time (at 40 Hz if no rate is given)')
    p.add_argument('--start-offset', type=float, default=default(PLAYER_PARAMS, 'start_offset'),
                   help='start this many seconds into the bag')
    p.add_argument('--playback-duration', type=float, default=default(PLAYER_PARAMS, 'playback_duration'),
                   help='play this many seconds of bag time (0 = to the end)')
    p.add_argument('-p', '--start-paused', action='store_true', help='start paused (resume: see above)')
    p.add_argument('-d', '--delay', type=float, default=default(PLAYER_PARAMS, 'delay'),
                   help='wait this many seconds before playing (lets subscribers connect)')


def _add_import(sub: Any) -> None:
    """Add the ``import`` subcommand."""
    p = sub.add_parser('import', help='turn a CSV of tracks from another tracker into a bag of /smarticles/poses',
                       description='Import a CSV of robot tracks (motion capture, AprilTag or ArUco pixel '
                                   'tracks) as the stack\'s pose topic, so that info, analyze and '
                                   'smarticle-calibrate read it. Name the time column and each robot\'s x, y '
                                   'and heading columns; other columns are ignored. A missing value makes that '
                                   'robot unseen in that message and a long time step is reported as a gap: '
                                   'neither is filled in. Headings may be wrapped or unwrapped (read modulo a '
                                   'full turn). A cell that is not a number, a missing time or times that do '
                                   'not increase: one line each, exit code 2.')
    p.add_argument('csv', type=Path, help='CSV file with a header line naming the columns')
    p.add_argument('-o', '--output', required=True, type=Path, help='bag folder to create')
    p.add_argument('--time', required=True, metavar='COLUMN', help='the column of times')
    p.add_argument('--robot', action='append', default=[], metavar='K:X,Y,H',
                   help='robot id K and its x, y and heading columns (repeat per robot), e.g. 0:x0,y0,h0')
    p.add_argument('--pattern', default=None, metavar='X,Y,H',
                   help='every robot k whose columns match this pattern, e.g. "x{k},y{k},h{k}" or '
                        '"tag{k}_x,tag{k}_y,tag{k}_yaw"')
    p.add_argument('--unit', choices=['m', 'cm', 'mm', 'px'], default=None,
                   help='length unit of x and y (default m; px with --px-per-bl)')
    p.add_argument('--px-per-bl', type=float, default=None, metavar='N',
                   help='pixel tracks: pixels per W, the body width of --robot-preset')
    p.add_argument('--robot-preset', default='small', choices=['small', 'feedback'],
                   help='the robot whose W scales pixel lengths (default small: 5.4 cm; feedback: 6.5 cm)')
    p.add_argument('--angle', choices=['rad', 'deg'], default='rad', help='unit of the heading column (default rad)')
    p.add_argument('--heading-offset', type=float, default=0.0, metavar='DEG',
                   help='degrees added to every heading, when the tracker\'s zero is not the body normal')
    p.add_argument('--y-down', action='store_true',
                   help='the tracker\'s y axis points down (image rows): y and headings are mirrored')
    p.add_argument('--time-unit', choices=['s', 'ms', 'us', 'ns'], default='s', help='unit of the time column')
    p.add_argument('--time-offset', type=float, default=0.0, metavar='S',
                   help='seconds added to every time (the bag\'s times must be >= 0)')
    p.add_argument('--gap-factor', type=float, default=3.0, metavar='X',
                   help='report a time step longer than X median steps as a gap (default 3)')
    p.add_argument('--delimiter', default=None, help='cell delimiter (default: sniffed from the header: , ; or tab)')
    p.add_argument('--skip-rows', type=int, default=0, metavar='N',
                   help='lines before the header line to skip (an exporter\'s preamble)')


def _add_clocks(sub: Any) -> None:
    """Add the ``clocks`` subcommand."""
    p = sub.add_parser('clocks', help='each robot\'s gait clock rate and phase, from its joint commands or states',
                       description='Estimate each robot\'s gait clock from the square gait\'s quarter '
                                   'boundaries in a bag: the times its joint commands switch corners (or its '
                                   'arms pass the middle of a stroke, from joint states), fitted against the '
                                   'quarter index. Prints per robot the rate (nominal period / fitted period) '
                                   'with its 95 %% interval and the gait phase at the bag\'s start.')
    p.add_argument('bag', help='bag folder or .mcap file')
    p.add_argument('--source', choices=['auto', 'commands', 'states'], default='auto',
                   help='joint_commands, joint_states, or auto: commands where recorded, else states')
    p.add_argument('--period', type=float, default=GAIT_PERIOD,
                   help=f'the gait\'s nominal period (s) (default {GAIT_PERIOD:g})')


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser of ``smarticle-bag``."""
    parser = argparse.ArgumentParser(prog=PROG, description='Record, replay and analyse rosbag2-compatible '
                                     'mcap bags of smarticle runs (like "ros2 bag"). ROS arguments go '
                                     'after --ros-args.')
    add_version(parser, 'smarticle_bags')
    sub = parser.add_subparsers(dest='command', required=True, metavar='COMMAND')
    p = sub.add_parser('info', help='print a summary of a bag', description='Print a summary of a bag.')
    p.add_argument('bag', help='bag folder or .mcap file')
    p.add_argument('--strict', action='store_true', help='fail on a damaged file instead of salvaging it')
    _add_record(sub)
    _add_play(sub)
    p = sub.add_parser('export', help='write the topics of a bag to CSV files (and the poses as a run npz)',
                       description='Write each topic to <out>/<topic>.csv '
                                   '(poses as x, y, heading per robot); with --run, also the pose topic '
                                   'as a run file in the format of batch trials and the demo '
                                   '(smarticle_common.runs).')
    p.add_argument('bag', help='bag folder or .mcap file')
    p.add_argument('-o', '--out', required=True, type=Path, help='folder for the CSV files')
    p.add_argument('--run', type=Path, default=None, metavar='FILE.npz',
                   help='also write /smarticles/poses (or --pose-topic) as a run npz')
    p.add_argument('--pose-topic', default='/smarticles/poses', help='PoseArray topic for --run')
    p.add_argument('--topics', nargs='+', default=None, metavar='TOPIC', help='export only these topics')
    p = sub.add_parser('analyze', help='glider analysis of the poses in a bag (smarticle_tracking)',
                       description='Feed the bag\'s poses to smarticle_tracking.gliders.')
    p.add_argument('bag', help='bag folder or .mcap file')
    p.add_argument('--topic', default='/smarticles/poses', help='PoseArray topic with the robot poses')
    p.add_argument('--period', type=float, default=GAIT_PERIOD, help=f'gait period (s) (default {GAIT_PERIOD:g})')
    p.add_argument('--min-periods', type=int, default=30,
                   help='bound this many periods in a row makes a bound pair (default 30, as in the paper)')
    p.add_argument('--travel-min', type=float, default=1.0, metavar='W_PER_100',
                   help='a bound pair whose centre of mass travels (net) at least this many W per 100 periods '
                        'of its run is a glider (default 1)')
    p.add_argument('--plot', default=None, metavar='FILE.png',
                   help='also write a figure of the gliders to this PNG (without it, nothing is written)')
    p = sub.add_parser('check', help='verify every chunk CRC and record of a bag; list damaged chunks',
                       description='Check every record and chunk (CRC) of a bag. Lists each damaged chunk '
                                   'with its byte offset, log-time range and the messages lost per topic. '
                                   'Exit code 0 if the bag is intact, 2 if anything is damaged.')
    p.add_argument('bag', help='bag folder or .mcap file')
    p = sub.add_parser('reindex', help='rebuild metadata.yaml from the .mcap files, salvaging damaged ones',
                       description='Check every .mcap of a bag folder and rebuild metadata.yaml. A damaged '
                                   'file is rebuilt from its intact chunks; the repaired bag goes to a new '
                                   'folder <bag>.repaired beside the original (which is not touched) unless '
                                   '--replace is given. reindex_report.txt says what was dropped.')
    p.add_argument('bag', help='bag folder')
    p.add_argument('--replace', action='store_true',
                   help='repair in place; each damaged original is kept as <name>.mcap.damaged')
    p.add_argument('-o', '--output', type=Path, default=None,
                   help='folder for the repaired bag (default <bag>.repaired)')
    _add_import(sub)
    _add_clocks(sub)
    return parser


def _record(ns: argparse.Namespace, ros_args: list[str] | None) -> int:
    """Run the recorder in this process."""
    from . import recorder_node

    overrides = {
        'output': ns.output, 'topics': ' '.join([*ns.topic_names, *ns.topics]), 'all': ns.all,
        'regex': ns.regex, 'exclude_regex': ns.exclude_regex,
        'include_hidden_topics': ns.include_hidden_topics,
        'storage_preset_profile': ns.storage_preset_profile, 'compression_format': ns.compression_format,
        'chunk_size': ns.chunk_size, 'max_bag_size': ns.max_bag_size, 'max_bag_duration': ns.max_bag_duration,
        'flush_interval': ns.flush_interval, 'topic_polling_interval': ns.polling_interval,
    }
    if ns.use_sim_time:   # otherwise --ros-args -p use_sim_time:=true still decides
        overrides['use_sim_time'] = True
    return recorder_node.run(overrides, ros_args)


def _play(ns: argparse.Namespace, ros_args: list[str] | None) -> int:
    """Run the player in this process."""
    from . import player_node

    overrides = {
        'bag': ns.bag, 'topics': ' '.join(ns.topics), 'remap': ' '.join(ns.remap), 'rate': ns.rate,
        'loop': ns.loop, 'start_offset': ns.start_offset, 'playback_duration': ns.playback_duration,
        'start_paused': ns.start_paused, 'clock': ns.clock, 'delay': ns.delay,
    }
    return player_node.run(overrides, ros_args)


def _analyze(ns: argparse.Namespace) -> int:
    """Feed the poses of a bag to the glider analysis (smarticle_tracking.gliders): table and plots."""
    try:
        from smarticle_tracking.gliders import GliderConfig
        from smarticle_tracking.report import glider_report
    except ImportError as err:
        print(f'{PROG} analyze: the glider analysis (smarticle_tracking) is not available ({err}); '
              f'install smarticle_tracking or use "{PROG} export" and analyse the CSV files', file=sys.stderr)
        return 3
    from . import arrays
    from .reader import BagReader

    poses = arrays.read_poses(BagReader(ns.bag), ns.topic)
    if len(poses.stamp) < 2:
        print(f'{PROG} analyze: {ns.topic} has {len(poses.stamp)} message(s) in {ns.bag}; nothing to analyse',
              file=sys.stderr)
        return 2
    try:
        config = GliderConfig(period=ns.period, min_periods=ns.min_periods, travel_min_w_per_100=ns.travel_min)
    except ValueError as err:   # --period, --min-periods or --travel-min out of range
        print(f'{PROG} analyze: {err}', file=sys.stderr)
        return 2
    figure = Path(ns.plot) if ns.plot else None   # reading a bag writes nothing unless asked
    report = glider_report(poses.stamp - poses.stamp[0], poses.xyh, config, figure)
    print(f'{ns.bag}: {poses.xyh.shape[1]} robots, {len(poses.stamp)} pose messages over '
          f'{poses.stamp[-1] - poses.stamp[0]:.1f} s: {report.summary}\n({report.rule})')
    print(report.table)
    if report.figure is not None:
        print(f'wrote {report.figure}')
    elif figure is not None:
        print(f'no figure written to {figure}: no bound pair formed')
    return 0


def _import(ns: argparse.Namespace) -> int:
    """Turn a CSV of tracks into a bag of the stack's pose topic; report gaps, refuse bad rows."""
    from .csv_import import ImportSpec, parse_robot, read_header, read_tracks, robots_from_pattern, write_bag
    from .errors import CsvImportError, OptionError

    try:
        if ns.skip_rows < 0:
            raise OptionError(f'--skip-rows must be >= 0, got {ns.skip_rows}')
        if bool(ns.robot) == bool(ns.pattern):
            raise OptionError('name the robots\' columns with --robot K:X,Y,H (once per robot) or --pattern X,Y,H')
        if ns.pattern:
            header, _ = read_header(ns.csv, ns.delimiter, ns.skip_rows)
            robots = robots_from_pattern(ns.pattern, header)
        else:
            robots = tuple(parse_robot(text) for text in ns.robot)
        unit = ns.unit or ('px' if ns.px_per_bl is not None else 'm')
        spec = ImportSpec(time=ns.time, robots=robots, length_unit=unit, px_per_bl=ns.px_per_bl,
                          body_preset=ns.robot_preset, angle_unit=ns.angle, time_unit=ns.time_unit,
                          time_offset=ns.time_offset, heading_offset=math.radians(ns.heading_offset),
                          y_down=ns.y_down, gap_factor=ns.gap_factor)
        tracks = read_tracks(ns.csv, spec, ns.delimiter, ns.skip_rows)
    except CsvImportError as err:
        for line in err.problems:
            print(f'{PROG} import: error: {line}', file=sys.stderr)
        return 2
    except UnicodeDecodeError as err:
        print(f'{PROG} import: error: {ns.csv.name} is not a UTF-8 text file ({err.reason} at byte {err.start})',
              file=sys.stderr)
        return 2
    for line in tracks.gaps:
        print(f'{PROG} import: gap: {line}', file=sys.stderr)
    info = write_bag(tracks, ns.output, spec, ns.csv.name)
    print(f'wrote {ns.output}: {len(tracks.time)} /smarticles/poses messages, robots '
          f'{", ".join(str(r.robot) for r in spec.robots)}, t = {tracks.time[0]:.6g} to {tracks.time[-1]:.6g} s '
          f'({info.message_count} messages)')
    print(f'units: {spec.describe_units()}')
    print(f'gaps: {len(tracks.gaps)} (listed above; not filled in)' if tracks.gaps else 'gaps: none')
    return 0


def _gait_start(reader: Any) -> tuple[float | None, str]:
    """The stamp of the bag's last /smarticles/start (the gaits' shared start), or None if it holds none."""
    from smarticle_common import topics as contract

    topic = contract.topic('start')
    if topic not in reader.topics:
        return None, ''
    stamps = [msg.stamp.sec + 1e-9 * msg.stamp.nanosec for _, msg in reader.decoded([topic])]
    return (stamps[-1], f'the gait start ({topic})') if stamps else (None, '')


def _clocks(ns: argparse.Namespace) -> int:
    """Print each robot's gait clock rate (with its 95 % interval) and phase at the bag's start."""
    try:
        from smarticle_tracking.clocks import ClockError, estimate_clock, format_clocks
    except ImportError as err:
        print(f'{PROG} clocks: the clock estimate (smarticle_tracking) is not available ({err})', file=sys.stderr)
        return 3
    from . import arrays
    from .reader import BagReader

    if not (math.isfinite(ns.period) and ns.period > 0.0):
        print(f'{PROG} clocks: --period must be a positive number of seconds, got {ns.period}', file=sys.stderr)
        return 2
    reader = BagReader(ns.bag)
    sources = {'commands': ['joint_commands'], 'states': ['joint_states'],
               'auto': ['joint_commands', 'joint_states']}[ns.source]
    series = {key: arrays.read_robot_topic(reader, key) for key in sources}
    robots = sorted({k for found in series.values() for k in found})
    if not robots:
        topics = ' or '.join(f'/smarticle_<k>/{key}' for key in sources)
        print(f'{PROG} clocks: {ns.bag} holds no {topics}: nothing to estimate', file=sys.stderr)
        return 2
    start, where = _gait_start(reader)
    if start is None:
        stamps = [s.stamp[0] for found in series.values() for s in found.values() if len(s.stamp)]
        start, where = min(stamps), 'the first joint message'
    estimates, failures = [], []
    for k in robots:
        key = next(key for key in sources if k in series[key] and len(series[key][k].stamp) > 1)
        joints = series[key][k]
        if not {'arm1', 'arm2'} <= set(joints.names):
            failures.append(f'robot {k}: /smarticle_{k}/{key} names {", ".join(joints.names) or "no joint"}, '
                            'not arm1 and arm2')
            continue
        arms = [joints.names.index(n) for n in ('arm1', 'arm2')]
        try:
            estimates.append(estimate_clock(
                joints.stamp, joints.position[:, arms], kind='commands' if key == 'joint_commands' else 'states',
                period=ns.period, start=start, velocity=joints.velocity[:, arms], robot=k))
        except ClockError as err:
            failures.append(f'robot {k} ({key}): {err}')
    print(format_clocks(estimates, ns.period, start, where))
    for line in failures:
        print(f'{PROG} clocks: {line}', file=sys.stderr)
    return 0 if estimates else 2


@closed_pipe_safe
def main(argv: list[str] | None = None) -> None:
    """Entry point of ``smarticle-bag``."""
    ours, ros_args = _split_ros_args(list(sys.argv[1:] if argv is None else argv))
    ns = build_parser().parse_args(ours)
    logging.basicConfig(level=logging.WARNING, format=f'{PROG}: warning: %(message)s')
    try:
        code = _dispatch(ns, ros_args)
    except BagError as err:
        print(f'{PROG} {ns.command}: error: {err}', file=sys.stderr)
        raise SystemExit(2) from None
    except BrokenPipeError:
        raise      # the reader of a listing has gone: closed_pipe_safe ends quietly
    except OSError as err:
        where = f' ({err.filename})' if err.filename else ''
        print(f'{PROG} {ns.command}: error: {err.strerror or err}{where}', file=sys.stderr)
        raise SystemExit(2) from None
    raise SystemExit(code)


def _dispatch(ns: argparse.Namespace, ros_args: list[str] | None) -> int:
    """Run one subcommand and return its exit code."""
    from .reader import BagReader

    if ns.command == 'record':
        return _record(ns, ros_args)
    if ns.command == 'play':
        return _play(ns, ros_args)
    if ns.command == 'analyze':
        return _analyze(ns)
    if ns.command == 'import':
        return _import(ns)
    if ns.command == 'clocks':
        return _clocks(ns)
    if ns.command == 'info':
        from .info import format_info
        print(format_info(BagReader(ns.bag, strict=ns.strict)), end='')
        return 0
    if ns.command == 'export':
        from .export import export_bag
        reader = BagReader(ns.bag)
        report = export_bag(reader, ns.out, ns.topics)
        for topic, path in report.written.items():
            print(f'{topic} -> {path}')
        for topic, reason in report.skipped.items():
            print(f'{topic}: skipped ({reason})', file=sys.stderr)
        if ns.run is not None:
            from .export import export_run
            print(f'{ns.pose_topic} -> {export_run(reader, ns.run, ns.pose_topic)}')
        return 0
    if ns.command == 'check':
        from .info import format_check
        reader = BagReader(ns.bag, verify=True)
        text, intact = format_check(reader)
        print(text, end='')
        return 0 if intact else 2
    from .reindex import reindex
    repair = reindex(ns.bag, replace=ns.replace, output=ns.output)
    for line in repair.problems:
        print(f'found: {line}')
    for line in repair.dropped:
        print(f'dropped: {line}')
    for line in repair.repaired:
        print(f'repaired: {line}')
    if repair.repaired:
        print(repair.lost_line())
    out = repair.output or Path(ns.bag)
    print(f'wrote {out / "metadata.yaml"}: {repair.info.message_count} messages in '
          f'{len(repair.info.files)} files, {len(repair.info.topics)} topics')
    if repair.report_path is not None:
        print(f'report: {repair.report_path}')
    return 0
