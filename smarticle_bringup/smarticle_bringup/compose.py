"""``smarticle-compose``: many of the stack's nodes in one process on one executor, as ROS 2 composition does.

Usage::

    smarticle-compose smarticle_bringup/launch/sim_stack.launch.xml robots:=7 duration:=20.0
    smarticle-compose smarticle_bringup sim_stack.launch.xml robots:=7 [--executor events] [--ros-args ...]

A launch file says which nodes to host (``launch_files.resolve``: the same file ``sim.launch.xml``
includes as separate processes when ``composed:=false``). Each ``<node>`` becomes an instance of **the
same node class** that its executable runs (``COMPONENTS``: the stack's registry of composable nodes,
as rclcpp_components registers plugins), built with its own command-line arguments (name, namespace,
parameter files and values, remappings; the host's global ROS arguments are not applied to them). All
of them go on one executor (``--executor``: ``single``, rclpy's ``SingleThreadedExecutor``, the default,
or ``events``, rclpy's experimental ``EventsExecutor``; ``EXECUTORS``). A node with a ``run(executor)``
method (the lock-step sim bridge) drives that executor, so every hosted node's callbacks run inside its
loop, and the host exits with its code when it returns; otherwise the host spins until Ctrl-C. A message
from one hosted node to another is handed over in-process, without the middleware, while nobody outside the
host subscribes to its topic (``local_delivery``: rclpy has no intra-process path of its own); a topic
someone outside subscribes to goes through the middleware to everyone, as between processes.

A file with a node that is not composable, or any other bad input, is a one-line error and exit code 2,
and nothing is started; a node that cannot start (a bad parameter) ends the host with exit code 2.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Sequence
from typing import Any
from smarticle_common.cli import version_of

#: (package, executable) -> "module:Class" of every node that may be hosted (each class takes rclpy
#: Node options as keyword arguments).
COMPONENTS: dict[tuple[str, str], str] = {
    ('smarticle_driver', 'gait'): 'smarticle_driver.gait_node:GaitNode',
    ('smarticle_driver', 'servo_bridge'): 'smarticle_driver.servo_bridge_node:ServoBridgeNode',
    ('smarticle_feedback', 'feedback'): 'smarticle_feedback.feedback_node:FeedbackNode',
    ('smarticle_sim', 'sim_bridge'): 'smarticle_sim.sim_bridge_node:SimBridgeNode',
    ('smarticle_tracking', 'glider_monitor'): 'smarticle_tracking.glider_monitor_node:GliderMonitorNode',
    ('smarticle_tracking', 'tracker'): 'smarticle_tracking.tracker_node:TrackerNode',
}

NAME = 'smarticle-compose'

#: --executor choices: name -> "module:Class" of an rclpy executor.
EXECUTORS: dict[str, str] = {
    'single': 'rclpy.executors:SingleThreadedExecutor',
    'events': 'rclpy.experimental:EventsExecutor',
}


def executor_class(name: str) -> Callable[[], Any]:
    """The executor class of ``--executor name`` (KeyError if unknown)."""
    module, _, cls = EXECUTORS[name].partition(':')
    return getattr(importlib.import_module(module), cls)


def component_class(package: str, executable: str) -> Callable[..., Any]:
    """The node class of ``package``/``executable`` (KeyError if it is not composable)."""
    module, _, cls = COMPONENTS[(package, executable)].partition(':')
    return getattr(importlib.import_module(module), cls)


def plan_nodes(words: Sequence[str]) -> list[Any]:
    """The checked NodeActions of ``[PACKAGE] FILE [name:=value ...]`` (LaunchFileError if any is bad)."""
    from .launch_files import LaunchFileError, plan_from_command_line

    plan = plan_from_command_line(list(words))
    for node in plan.nodes:
        if (node.package, node.executable) not in COMPONENTS:
            raise LaunchFileError(f'{node.where}: {node.package}/{node.executable} cannot be composed (composable: '
                                  + ', '.join(f'{p}/{e}' for p, e in sorted(COMPONENTS)) + ')')
    return list(plan.nodes)


def file_words(words: Sequence[str]) -> list[str]:
    """The ``[PACKAGE] FILE [name:=value ...]`` part of the host's command line (``--executor NAME`` and
    ``--ros-args ...`` left out)."""
    words = list(words)
    if '--ros-args' in words:
        words = words[:words.index('--ros-args')]
    if '--executor' in words:
        at = words.index('--executor')
        words = words[:at] + words[at + 2:]
    return words


def host(actions: Sequence[Any], args: list[str] | None = None,
         executor_factory: Callable[[], Any] | None = None) -> int:
    """Build every node of ``actions`` in this process, run them on one executor; return the exit code.

    The Jazzy idiom, for many nodes: ``rclpy.init``; build; run or spin; on Ctrl-C (which shuts the
    context down, as in ``run_node``; a callback still busy 0.7 s after the signal ends the process) or
    external shutdown stop quietly; finally destroy every node and
    ``try_shutdown``. A startup error of a node (bad parameter, a file or port that cannot be opened) is
    logged as fatal and gives exit code 2.
    """
    from smarticle_common.node import SigintShutsDown

    with SigintShutsDown(NAME) as signals:
        return _init_and_host(actions, args, executor_factory, signals)


def _init_and_host(actions: Sequence[Any], args: list[str] | None,
                   executor_factory: Callable[[], Any] | None, signals: Any) -> int:
    """``host`` once its signal handler is in place."""
    import rclpy
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
    from smarticle_common.node import ended_by_signal
    from smarticle_common.params import ParameterError

    from smarticle_driver.errors import DriverError

    from .local_delivery import connect, hosted_topics, share_clock

    rclpy.init(args=args)
    nodes: list[Any] = []
    code = 0
    building = True
    try:
        for action in actions:
            cls = component_class(action.package, action.executable)
            nodes.append(cls(cli_args=action.ros_arguments(), use_global_arguments=False))
        building = False
        executor = (executor_factory or SingleThreadedExecutor)()
        for node in nodes:
            executor.add_node(node)
        runners = [node for node in nodes if callable(getattr(node, 'run', None))]
        share_clock(nodes)   # one /clock subscription sets every hosted sim-time clock
        delivery = connect(nodes)
        rclpy.logging.get_logger(NAME).info(f'hosting {len(nodes)} nodes on one executor: '
                                            + ', '.join(n.get_fully_qualified_name() for n in nodes)
                                            + f'; {hosted_topics(delivery)}')
        if len(runners) > 1:
            raise ParameterError('more than one hosted node drives its own loop: '
                                 + ', '.join(n.get_fully_qualified_name() for n in runners))
        if runners:
            code = int(runners[0].run(executor))
        else:
            executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ParameterError, DriverError) as err:
        if not building:
            raise
        rclpy.logging.get_logger(NAME).fatal(f'cannot start: {err}')
        code = 2
    except RuntimeError:      # rclpy's errors of a context that a signal just ended, or is about to
        if not ended_by_signal():
            raise
    finally:
        signals.returned()     # the watchdog of a busy callback stands down: clean-up may take its time
        for node in reversed(nodes):
            node.destroy_node()
        rclpy.try_shutdown()
    return code


def main(argv: list[str] | None = None) -> int:
    """Run the host; return the exit code."""
    from .launch_files import LaunchFileError

    argv = sys.argv[1:] if argv is None else argv
    # the host's own ROS arguments start at --ros-args; everything before is the file and name:=value words
    # (rclpy would take those for legacy remapping rules, so they never reach rclpy.init)
    cut = argv.index('--ros-args') if '--ros-args' in argv else len(argv)
    words, ros_args = argv[:cut], argv[cut:]
    if not words or words[0] in ('-h', '--help'):
        print(__doc__)
        return 0 if words else 2
    if words[0] == '--version':
        print(f'smarticle-compose {version_of("smarticle_bringup")}')
        return 0
    executor = 'single'
    if '--executor' in words:
        at = words.index('--executor')
        if at + 1 >= len(words) or words[at + 1] not in EXECUTORS:
            print(f'{NAME}: --executor takes one of: {", ".join(EXECUTORS)}', file=sys.stderr)
            return 2
        executor = words[at + 1]
        words = words[:at] + words[at + 2:]
    try:
        actions = plan_nodes(words)
    except LaunchFileError as err:
        print(f'{NAME}: {err}', file=sys.stderr)
        return 2
    return host(actions, [NAME, *ros_args], executor_class(executor))


def entry() -> None:
    """Console-script entry point."""
    raise SystemExit(main())


if __name__ == '__main__':
    entry()
