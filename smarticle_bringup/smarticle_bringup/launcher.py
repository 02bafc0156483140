"""``smarticle-launch``: start a ROS 2 XML launch file's nodes without ``ros2 launch`` (the PyPI path).

Usage::

    smarticle-launch smarticle_bringup sim.launch.xml robots:=3 duration:=20.0
    smarticle-launch path/to/file.launch.xml name:=value ... [--log-dir DIR] [--show]

Reads the file with ``launch_files.resolve`` (the same files ``ros2 launch`` reads on a board), checks
everything first, then starts every node as its own process through ``smarticle_common.launching``'s
``ProcessGroup`` (each process's output goes to ``<log-dir>/<executable>-<i>.log``). It runs until
Ctrl-C / SIGTERM, until a node marked ``on_exit="shutdown"`` (a required node) ends (the launcher then
stops the rest and exits with that node's code), until every node has ended, or, while a required node
runs, until every node of one robot's namespace ``/smarticle_<k>`` has ended (a lock-step sim would wait
for that robot's commands). A process that exits with an error is reported on the terminal with its
reason (its last traceback's message and frame, else its last error line) and its log's path. At the end
the nodes' exit summaries are printed: one line per robot (commands, halts or stops, contacts) and the
glider report. A bad file, argument, package, executable or parameter file is one line on stderr naming
the file and line, exit code 2, and nothing is started. ``--show`` prints the command lines and starts
nothing.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

from smarticle_common import topics
from smarticle_common.launching import ProcessGroup, failure_reason, gather_summaries

from .launch_files import LaunchFileError, LaunchPlan, NodeAction, plan_from_command_line
from smarticle_common.cli import add_version, closed_pipe_safe


def executable_path(node: NodeAction) -> str:
    """The program of ``node``, looked up in its package's own install only (never elsewhere on PATH).

    ``<prefix>/lib/<pkg>/<exec>`` of a ROS install (``AMENT_PREFIX_PATH``, as ``ros2 run`` looks), else the
    console script ``<exec>`` that the package's Python distribution installed (pip, or ``lib/<pkg>`` of a
    colcon build); LaunchFileError, one line naming where it looked, if neither has it.
    """
    looked: list[str] = []
    for prefix in (p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p):
        folder = Path(prefix) / 'lib' / node.package
        candidate = folder / node.executable
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
        looked.append(str(folder))
    script = package_script(node.package, node.executable)
    if script is not None:
        return script
    looked.append(f'the console scripts of the Python distribution {node.package!r}')
    raise LaunchFileError(f'{node.where}: executable {node.executable!r} of package {node.package!r} not found '
                          f'(looked in {", ".join(looked)}); a renamed package needs its new name in setup.cfg '
                          'and setup.py too (docs/own_controller.md)')


def package_script(package: str, name: str) -> str | None:
    """The installed console script ``name`` of the Python distribution ``package``, or None.

    Only a file the distribution itself installed counts (its RECORD), in the interpreter's own scripts
    folder or in ``lib/<package>`` (ament_python's ``script_dir``): a program of the same name elsewhere on
    PATH is never taken for it.
    """
    try:
        dist = importlib.metadata.distribution(package)
    except importlib.metadata.PackageNotFoundError:
        return None
    if name not in {ep.name for ep in dist.entry_points if ep.group == 'console_scripts'}:
        return None
    for file in dist.files or ():
        if file.name == name and file.parent.name in ('bin', 'Scripts', package):
            path = Path(str(file.locate())).resolve()
            if path.is_file() and os.access(path, os.X_OK):
                return str(path)
    beside = Path(sys.executable).parent / name          # an editable install's script (pip install -e)
    if beside.is_file() and os.access(beside, os.X_OK):
        return str(beside)
    return None


@dataclass
class Running:
    """One started node, its process and its log."""

    node: NodeAction
    proc: subprocess.Popen[bytes]
    log: Path


class Launch:
    """The processes of a plan, started together and stopped together."""

    def __init__(self, plan: LaunchPlan, log_dir: Path, env: Mapping[str, str] | None = None) -> None:
        self.plan = plan
        self.programs = [executable_path(node) for node in plan.nodes]   # every program checked first
        for node in plan.nodes:     # and what a composing host will read: its file, arguments, parameter files
            if (node.package, node.executable) == ('smarticle_bringup', 'smarticle-compose'):
                from .compose import file_words, plan_nodes

                plan_nodes(file_words(node.args))
        self.group = ProcessGroup(log_dir, dict(env) if env is not None else None)
        self.running: list[Running] = []

    def start(self) -> list[Running]:
        """Start every node of the plan, in file order."""
        for node, program in zip(self.plan.nodes, self.programs, strict=True):
            proc = self.group.start(program, *node.command_arguments())
            self.running.append(Running(node, proc, self.group.log_of(proc)))
        return self.running

    def poll(self) -> tuple[Running | None, list[Running]]:
        """(a shutdown node that has ended, or None; every node that has ended)."""
        ended = [r for r in self.running if r.proc.poll() is not None]
        return next((r for r in ended if r.node.on_exit_shutdown), None), ended

    def output(self, running: Running) -> str:
        """What one node has printed so far."""
        return running.log.read_text(errors='replace')

    def ended_line(self, running: Running) -> str:
        """How a node ended: its exit code and, for a failure, its reason and its log (one or two lines)."""
        code = running.proc.returncode
        line = f'[launch] {running.node.full_name} ended with exit code {code}'
        if code in (0, None) or code < 0 and -code in (signal.SIGINT, signal.SIGTERM):
            return line
        reason = failure_reason(self.output(running))
        return line + (f': {reason}' if reason else '') + f'\n[launch]   its output: {running.log}'

    def robot_without_nodes(self) -> str | None:
        """While a required node runs: the line of a robot whose every node has ended (else None)."""
        if not any(r.node.on_exit_shutdown and r.proc.poll() is None for r in self.running):
            return None
        by_robot: dict[int, list[Running]] = {}
        for r in self.running:
            robot = topics.robot_of_namespace(r.node.namespace)
            if robot is not None:
                by_robot.setdefault(robot, []).append(r)
        for robot, nodes in sorted(by_robot.items()):
            if all(r.proc.poll() is not None for r in nodes):
                names = ', '.join(r.node.full_name for r in nodes)
                return (f'[launch] every node of robot {robot} has ended ({names}): nothing answers for it, '
                        'ending the launch')
        return None

    def stop(self, grace: float = 10.0) -> None:
        """SIGINT every process still running, SIGKILL what is left after ``grace`` seconds."""
        self.group.stop_all(grace)

    def summary(self) -> list[str]:
        """The nodes' exit summaries: one line per robot, then the other reports (the glider report)."""
        robots, others = gather_summaries([self.output(r) for r in self.running if r.log.is_file()])
        return ([f'[launch] robot {k}: ' + ', '.join(f'{key} {value}' for key, value in counts.items())
                 for k, counts in robots.items()] + [f'[launch] {line}' for line in others])

    def wait(self, poll: float = 0.1) -> int:
        """Run until a shutdown node ends (its exit code), every node ends (0), every node of a robot ends
        while a shutdown node runs (1, or the first failed node's code) or SIGINT/SIGTERM (0); then stop
        the rest and print the summaries."""
        stopping: list[int] = []

        def on_signal(signum: int, _frame: FrameType | None) -> None:
            stopping.append(signum)
        previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
        reported: set[int] = set()
        code = 0
        try:
            while not stopping:
                shutdown, ended = self.poll()
                for r in ended:
                    if id(r) not in reported:
                        reported.add(id(r))
                        print(self.ended_line(r), flush=True)
                if shutdown is not None:
                    code = int(shutdown.proc.returncode or 0)
                    break
                if len(ended) == len(self.running):
                    break
                orphan = self.robot_without_nodes()
                if orphan is not None:
                    print(orphan, flush=True)
                    code = next((r.proc.returncode for r in ended if r.proc.returncode), 1)
                    break
                time.sleep(poll)
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)
            self.stop()
        for line in self.summary():
            print(line, flush=True)
        return code


def build_parser() -> argparse.ArgumentParser:
    """Command-line options of smarticle-launch."""
    parser = argparse.ArgumentParser(prog='smarticle-launch', description=__doc__.split('\n')[0] if __doc__ else None)
    add_version(parser, 'smarticle_bringup')
    parser.add_argument('words', nargs='+', metavar='[PACKAGE] FILE [name:=value ...]',
                        help='a launch file (or a package and the name of a file in its launch/ folder) and '
                             'its arguments')
    parser.add_argument('--log-dir', type=Path, default=None,
                        help='folder of the nodes\' output (default: out/launch/<file>-<time>)')
    parser.add_argument('--show', action='store_true', help='print the command lines and start nothing')
    return parser


@closed_pipe_safe
def main(argv: list[str] | None = None) -> int:
    """Run the launcher; return the exit code."""
    args = build_parser().parse_args(argv)
    try:
        plan = plan_from_command_line(args.words)
        stem = plan.path.name.split('.')[0]
        log_dir = args.log_dir or Path('out/launch') / f'{stem}-{time.strftime("%Y%m%d-%H%M%S")}'
        launch = Launch(plan, log_dir)
    except LaunchFileError as err:
        print(f'smarticle-launch: {err}', file=sys.stderr)
        return 2
    if args.show:
        for node, program in zip(plan.nodes, launch.programs, strict=True):
            print(' '.join([program, *node.command_arguments()]))
        return 0
    print(f'[launch] {plan.path.name}: {len(plan.nodes)} node(s), output in {log_dir}', flush=True)
    for running in launch.start():
        print(f'[launch] started {running.node.full_name} ({running.node.executable}, pid {running.proc.pid})',
              flush=True)
    return launch.wait()


def entry() -> None:
    """Console-script entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
