"""``smarticle-launch``: start a ROS 2 XML launch file's nodes without ``ros2 launch`` (the PyPI path).

Usage::

    smarticle-launch smarticle_bringup sim.launch.xml robots:=3 duration:=20.0
    smarticle-launch path/to/file.launch.xml name:=value ... [--log-dir DIR] [--show]

Reads the file with ``launch_files.resolve`` (the same files ``ros2 launch`` reads on a board), checks
everything first, then starts every node as its own process through ``smarticle_common.launching``'s
``ProcessGroup`` (each process's output goes to ``<log-dir>/<executable>-<i>.log``). It runs until
Ctrl-C / SIGTERM, until a node marked ``on_exit="shutdown"`` ends (the launcher then stops the rest and
exits with that node's code), or until every node has ended. A bad file, argument, package, executable
or parameter file is one line on stderr naming the file and line, exit code 2, and nothing is started.
``--show`` prints the command lines and starts nothing.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import FrameType

from smarticle_common.launching import ProcessGroup, executable

from .launch_files import LaunchFileError, LaunchPlan, NodeAction, find_launch_file, parse_arguments, resolve
from smarticle_common.cli import add_version, closed_pipe_safe


def executable_path(node: NodeAction) -> str:
    """The program of ``node``: ``<prefix>/lib/<pkg>/<exec>`` of a ROS install, else the console script."""
    for prefix in (p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p):
        candidate = Path(prefix) / 'lib' / node.package / node.executable
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
    try:
        return executable(node.executable)
    except FileNotFoundError as err:
        raise LaunchFileError(f'{node.where}: {err}') from None


def plan_from_command_line(words: list[str]) -> LaunchPlan:
    """``[PACKAGE] FILE [name:=value ...]`` as a checked plan (LaunchFileError if anything is wrong)."""
    if not words:
        raise LaunchFileError('give a launch file, or a package and a launch file name, then name:=value arguments')
    if words[0].endswith('.xml') or Path(words[0]).is_file() or len(words) == 1 or ':=' in words[1]:
        path, rest = Path(words[0]), words[1:]
    else:
        path, rest = find_launch_file(words[0], words[1]), words[2:]
    return resolve(path, parse_arguments(rest))


@dataclass
class Running:
    """One started node and its process."""

    node: NodeAction
    proc: subprocess.Popen[bytes]


class Launch:
    """The processes of a plan, started together and stopped together."""

    def __init__(self, plan: LaunchPlan, log_dir: Path, env: Mapping[str, str] | None = None) -> None:
        self.plan = plan
        self.programs = [executable_path(node) for node in plan.nodes]   # every program checked first
        self.group = ProcessGroup(log_dir, dict(env) if env is not None else None)
        self.running: list[Running] = []

    def start(self) -> list[Running]:
        """Start every node of the plan, in file order."""
        for node, program in zip(self.plan.nodes, self.programs, strict=True):
            self.running.append(Running(node, self.group.start(program, *node.command_arguments())))
        return self.running

    def poll(self) -> tuple[Running | None, list[Running]]:
        """(a shutdown node that has ended, or None; every node that has ended)."""
        ended = [r for r in self.running if r.proc.poll() is not None]
        return next((r for r in ended if r.node.on_exit_shutdown), None), ended

    def output(self, running: Running) -> str:
        """What one node has printed so far."""
        return self.group.output(running.proc)

    def stop(self, grace: float = 10.0) -> None:
        """SIGINT every process still running, SIGKILL what is left after ``grace`` seconds."""
        self.group.stop_all(grace)

    def wait(self, poll: float = 0.1) -> int:
        """Run until a shutdown node ends (its exit code), every node ends (0) or SIGINT/SIGTERM (0)."""
        stopping: list[int] = []

        def on_signal(signum: int, _frame: FrameType | None) -> None:
            stopping.append(signum)
        previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
        reported: set[int] = set()
        try:
            while not stopping:
                shutdown, ended = self.poll()
                for r in ended:
                    if id(r) not in reported:
                        reported.add(id(r))
                        print(f'[launch] {r.node.full_name} ended with exit code {r.proc.returncode}', flush=True)
                if shutdown is not None:
                    return int(shutdown.proc.returncode or 0)
                if len(ended) == len(self.running):
                    return 0
                time.sleep(poll)
            return 0
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)
            self.stop()


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
