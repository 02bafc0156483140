"""The node helper every node uses: parameters declared from a table, /diagnostics, and the Jazzy main.

The one module of ``smarticle_common`` that imports rclpy. A node is built the ros2/demos way (one class,
everything created in the constructor) and started with ``run_node``::

    def main(args: list[str] | None = None) -> None:
        raise SystemExit(run_node(GaitNode, NODE_NAME, args))

``run_node`` also answers ``--help`` (usage, the node's purpose and its parameter table: names, types,
defaults, ranges and descriptions) and ``--version`` before ``--ros-args``, without starting the node.
"""

from __future__ import annotations

import os
import signal
import sys
import textwrap
import threading
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.exceptions import InvalidParameterTypeException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter

from . import topics
from .cli import version_of
from .params import ParameterError, ParamSpec, check_params_file, params_files

#: Diagnostic levels (diagnostic_msgs/DiagnosticStatus).
OK, WARN, ERROR = 0, 1, 2

Config = TypeVar('Config')


def descriptor_of(spec: ParamSpec) -> ParameterDescriptor:
    """The ROS descriptor of ``spec``: its description, its range, and read-only unless it may change at run time.

    Parameters are read once into a frozen config, so a change at run time could not take effect: ROS
    refuses ``ros2 param set`` on them with "read-only" instead of accepting and ignoring it. A value out
    of a declared range is refused by ROS with the range.
    """
    descriptor = ParameterDescriptor(description=spec.description, read_only=not spec.runtime,
                                     type=Parameter.Type.from_parameter_value(spec.default).value)
    if spec.minimum is not None and spec.maximum is not None and not isinstance(spec.default, bool):
        if isinstance(spec.default, int):
            descriptor.integer_range = [IntegerRange(from_value=int(spec.minimum), to_value=int(spec.maximum),
                                                     step=0)]
        elif isinstance(spec.default, float):
            descriptor.floating_point_range = [FloatingPointRange(from_value=float(spec.minimum),
                                                                  to_value=float(spec.maximum), step=0.0)]
    return descriptor


def declare_and_read(node: Any, specs: tuple[ParamSpec, ...]) -> dict[str, Any]:
    """Declare ``specs`` on an rclpy node and return their checked values by name (ParameterError if bad).

    Each value is checked by its ``ParamSpec`` first (the message names the parameter and the bound it
    breaks), then the full descriptor (range, read-only) is applied.
    """
    values: dict[str, Any] = {}
    where = f'node {node.get_name()} parameter'
    for spec in specs:
        try:
            param = node.declare_parameter(spec.name, spec.default,
                                           ParameterDescriptor(description=spec.description))
        except InvalidParameterTypeException as err:
            raise ParameterError(f'{where} {spec.name!r}: expected {type(spec.default).__name__} ({err})') from None
        values[spec.name] = spec.check(param.value, where)
        node.set_descriptor(spec.name, descriptor_of(spec))
    return values


def read_config(node: Any, specs: tuple[ParamSpec, ...], build: Callable[[dict[str, Any]], Config]) -> Config:
    """The one way a node gets its settings: declare ``specs``, check the values, ``build`` the frozen config.

    A value of the wrong type or out of range, or a ValueError of ``build`` (settings that contradict
    each other), becomes a ParameterError that names the node; ``run_node`` turns it into exit code 2.
    """
    values = declare_and_read(node, specs)
    try:
        return build(values)
    except ParameterError:
        raise
    except ValueError as err:
        raise ParameterError(f'node {node.get_name()}: {err}') from err


def accept_runtime_changes(node: Any, specs: tuple[ParamSpec, ...],
                           apply: Callable[[dict[str, Any]], None]) -> None:
    """Let ``ros2 param set`` change the parameters of ``specs`` marked ``runtime``; refuse everything else.

    Registers a set-parameters callback (call it after ``read_config``: rclpy runs these callbacks for
    declarations too). A change of a parameter that is not ``runtime`` is refused as read-only, a value
    of the wrong type or out of range with the bound it breaks, and a set the node cannot use
    (``apply`` raises ValueError, e.g. a window whose minimum exceeds its maximum) with that reason; in
    every refused case the node is unchanged. ``apply`` gets the checked new values by name and must
    take them all or raise. Parameters outside ``specs`` (``use_sim_time``) are left to rclpy.
    """
    by_name = {spec.name: spec for spec in specs}
    where = f'node {node.get_name()} parameter'

    def on_set(params: list[Parameter]) -> SetParametersResult:
        changes: dict[str, Any] = {}
        for param in params:
            spec = by_name.get(param.name)
            if spec is None:
                continue
            if not spec.runtime:
                return SetParametersResult(successful=False, reason=f'{param.name} is read-only: it is read once '
                                           'at start-up; restart the node to change it')
            try:
                changes[param.name] = spec.check(param.value, where)
            except ParameterError as err:
                return SetParametersResult(successful=False, reason=str(err))
        if changes:
            try:
                apply(changes)
            except ValueError as err:
                return SetParametersResult(successful=False, reason=f'{where}s {", ".join(changes)}: {err}')
            node.get_logger().info('parameters changed: ' + ', '.join(f'{k} = {v!r}' for k, v in changes.items()))
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(on_set)


def resolve_robot_id(node: Any, robot_id: int) -> int:
    """The robot a per-robot node serves: its ``robot_id`` parameter and its namespace must agree.

    Started as ``--ros-args -r __ns:=/smarticle_3`` the node serves robot 3 (its fully qualified name is
    ``/smarticle_3/<name>``, so seven gait nodes never share a name); ``robot_id`` -1 follows the namespace,
    and outside a ``/smarticle_<k>`` namespace it means robot 0. ParameterError if the two disagree.
    """
    namespace = node.get_namespace()
    from_namespace = topics.robot_of_namespace(namespace)
    if robot_id < 0:
        return 0 if from_namespace is None else from_namespace
    if from_namespace is not None and from_namespace != robot_id:
        raise ParameterError(f'node {node.get_fully_qualified_name()}: robot_id {robot_id} disagrees with its '
                             f'namespace {namespace} (robot {from_namespace}); give one or the other')
    return robot_id


class DiagnosticsPublisher:
    """A node's status on /diagnostics: one DiagnosticStatus (name, hardware id) with key/value counters."""

    def __init__(self, node: Node, name: str, hardware_id: str = '') -> None:
        spec = topics.spec_of('diagnostics')
        self.node, self.name, self.hardware_id = node, name, hardware_id
        self.publisher = node.create_publisher(DiagnosticArray, spec.resolve(), topics.qos_profile(spec.qos))

    def publish(self, level: int, message: str, values: Mapping[str, object] | None = None) -> None:
        """Publish one status now; ``values`` become KeyValue pairs (as text)."""
        status = DiagnosticStatus(level=bytes([level]), name=self.name, message=message,
                                  hardware_id=self.hardware_id)
        status.values = [KeyValue(key=str(k), value=str(v)) for k, v in (values or {}).items()]
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.node.get_clock().now().to_msg()
        try:
            self.publisher.publish(array)
        except RuntimeError:        # rclpy's RCLError: the context ended under us (Ctrl-C, SIGTERM)
            if self.node.context.ok():
                raise


def _default(value: Any) -> str:
    return repr(value) if isinstance(value, str) else str(value).lower() if isinstance(value, bool) else str(value)


def node_help(prog: str, node_name: str, description: str, specs: Sequence[ParamSpec]) -> str:
    """The ``--help`` text of a node executable: usage, what it does, and its parameters."""
    lines = [f'usage: {prog} [-h] [--version] [--ros-args [-p NAME:=VALUE] [--params-file FILE] '
             '[-r __ns:=/smarticle_<k>] ...]', '']
    if description:
        lines += [textwrap.fill(' '.join(description.split()), 100), '']
    lines.append(f'Runs the ROS 2 node `{node_name}`. Parameters (set them after --ros-args with -p NAME:=VALUE '
                 'or --params-file FILE):')
    for spec in specs:
        kind = type(spec.default).__name__
        limits = ('' if spec.minimum is None and spec.maximum is None
                  else f', {spec.minimum if spec.minimum is not None else ""}..'
                       f'{spec.maximum if spec.maximum is not None else ""}')
        runtime = ', settable at run time' if spec.runtime else ''
        lines.append(f'  {spec.name} ({kind}, default {_default(spec.default)}{limits}{runtime})')
        lines += textwrap.wrap(spec.description, 100, initial_indent=' ' * 6, subsequent_indent=' ' * 6)
    lines += ['', 'options:', '  -h, --help  show this help and exit without starting the node',
              '  --version   print the version and exit']
    return '\n'.join(lines) + '\n'


def _answer_help_or_version(factory: Callable[[], Node], node_name: str, args: Sequence[str] | None,
                            params: Sequence[ParamSpec] | None) -> bool:
    """Print ``--help`` or ``--version`` if asked before ``--ros-args``; True if it did (do not start)."""
    argv = list(sys.argv if args is None else args)
    words = argv[1:]
    if '--ros-args' in words:
        words = words[:words.index('--ros-args')]
    if not {'-h', '--help', '--version'} & set(words):
        return False
    module = sys.modules.get(getattr(factory, '__module__', '') or '')
    distribution = (module.__name__ if module else node_name).split('.')[0]
    prog = os.path.basename(argv[0]) if argv else node_name
    if '--version' in words and not {'-h', '--help'} & set(words):
        print(f'{prog} {version_of(distribution)}')
        return True
    if params is None:     # the module's one parameter table (PARAMS, TRACKER_PARAMS, ...)
        tables = [v for k, v in vars(module or {}).items() if k.endswith('PARAMS') and isinstance(v, tuple)
                  and v and all(isinstance(x, ParamSpec) for x in v)] if module else []
        params = tables[0] if len(tables) == 1 else ()
    description = ((module.__doc__ or '') if module else '').strip().split('\n\n')[0]
    print(node_help(prog, node_name, description, params), end='')
    return True


#: How long (s) an rclpy error may precede the context's shutdown and still count as the signal's doing:
#: rclpy's signal thread shuts contexts down about a millisecond after the signal, and a signal landing in
#: a message's conversion surfaces first as pybind11's "Unable to convert call argument".
_SIGNAL_SHUTDOWN_S = 1.0


def ended_by_signal(timeout: float = _SIGNAL_SHUTDOWN_S) -> bool:
    """True once rclpy's default context is shut down, waiting at most ``timeout`` seconds: whether an rclpy
    error just raised came from a signal's shutdown (then the context is down, or goes down within a second)."""
    deadline = time.monotonic() + timeout
    while rclpy.ok():
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.005)
    return True


#: Seconds a node has, after SIGINT or SIGTERM, for its executor to return before the process ends anyway.
SIGNAL_GRACE_S = 0.7


class SigintShutsDown:
    """SIGINT (Ctrl-C) ends a node like SIGTERM, and either ends it within a second even if a callback is busy.

    rclpy's own handler shuts the context down and wakes the executor, and Python raises no
    KeyboardInterrupt inside rclpy's code (where it surfaces as pybind11's "Unable to convert call
    argument", as "Exception ignored in Future.__del__" or as an unstarted callback). A callback that does
    not return (a stuck driver call, a loop) would keep the executor, and the process, alive: after either
    signal a watchdog gives the executor ``grace`` seconds to return (``returned``), then logs one line
    saying a callback was still busy and ends the process with exit code 0, as a signal's end is. A second
    Ctrl-C raises KeyboardInterrupt at once, for a callback that does not return.

    Installed before ``rclpy.init``, which chains its handlers to these; the previous handlers are put back
    on exit. Outside the main thread (where Python allows no handler) it does nothing.
    """

    def __init__(self, name: str = 'node', grace: float = SIGNAL_GRACE_S) -> None:
        self.name, self.grace = name, grace
        self.previous: dict[int, Any] = {}
        self.presses = 0
        self._watchdog: threading.Timer | None = None
        self._returned = threading.Event()

    def __enter__(self) -> SigintShutsDown:
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                self.previous[signum] = signal.signal(signum, self._on_signal)
        return self

    def _on_signal(self, signum: int, frame: Any) -> None:
        if self._watchdog is None and not self._returned.is_set():
            self._watchdog = threading.Timer(self.grace, self._expire, (signal.Signals(signum).name,))
            self._watchdog.daemon = True
            self._watchdog.start()
        if signum == signal.SIGINT:
            self.presses += 1
            if self.presses > 1:
                raise KeyboardInterrupt

    def returned(self) -> None:
        """The executor has returned: the watchdog stands down (the node's own clean-up may take its time)."""
        self._returned.set()
        if self._watchdog is not None:
            self._watchdog.cancel()

    def _expire(self, signame: str) -> None:
        """The grace has passed and the executor has not returned: end the process (exit code 0)."""
        if self._returned.is_set():
            return
        message = (f'{signame}: a callback was still busy {self.grace:g} s after the signal; ending the process '
                   'without waiting for it')
        try:
            rclpy.logging.get_logger(self.name).warning(message)
        except (RuntimeError, ValueError):    # rcutils logging already gone: the line goes to stderr instead
            print(f'[WARN] [{self.name}]: {message}', file=sys.stderr)
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(0)

    def __exit__(self, *exc: object) -> None:
        self.returned()
        for signum, handler in self.previous.items():
            signal.signal(signum, handler)


def run_node(factory: Callable[[], Node], node_name: str, args: list[str] | None = None,
             startup_errors: tuple[type[BaseException], ...] = (ParameterError,),
             params: Sequence[ParamSpec] | None = None,
             executor_factory: Callable[[], Any] | None = None) -> int:
    """Run a node the Jazzy way (init, spin until Ctrl-C or shutdown, destroy, try_shutdown); return the exit code.

    ``--help`` / ``-h`` and ``--version`` before ``--ros-args`` print the node's help (its parameter
    table: ``params``, else the one ``*PARAMS`` table of the factory's module) or version and return 0
    without starting anything.

    A node with a ``run(executor) -> int`` method drives its own loop (the sim bridge's lock-step) on an
    executor of ``executor_factory`` (default rclpy's SingleThreadedExecutor) and its return value is the exit
    code; any other node is spun. An error of ``startup_errors`` raised
    while the node is being built (a bad parameter or file) is logged as fatal and ends the process with
    exit code 2; the same error later propagates. An rclpy error raised because a signal shut the
    context down under the executor, or is about to (Jazzy's races, e.g. "failed to initialize wait set",
    or pybind11's "Unable to convert call argument" when the signal lands in a message's conversion), is a
    clean exit, like KeyboardInterrupt: it counts if the context is shut down within a second of the error.
    Ctrl-C shuts the context down as SIGTERM does (a second one raises KeyboardInterrupt); after either, a
    callback that keeps the executor from returning for ``SIGNAL_GRACE_S`` ends the process (exit code 0).
    """
    if _answer_help_or_version(factory, node_name, args, params):
        return 0
    with SigintShutsDown(node_name) as signals:
        return _init_and_run(factory, node_name, args, startup_errors, signals, executor_factory)


def _init_and_run(factory: Callable[[], Node], node_name: str, args: list[str] | None,
                  startup_errors: tuple[type[BaseException], ...], signals: SigintShutsDown,
                  executor_factory: Callable[[], Any] | None = None) -> int:
    """``run_node`` once its signal handler is in place: init, build, run or spin, destroy, shut down."""
    try:     # a malformed parameter file: one line naming the file and line, not rcl's traceback
        for path in params_files(sys.argv if args is None else args):
            check_params_file(path)
    except ParameterError as err:
        rclpy.logging.get_logger(node_name).fatal(f'cannot start: {err}')
        return 2
    rclpy.init(args=args)
    # A signal that lands while rclpy's executor is handing a message to a callback leaves that callback's
    # coroutine unstarted; Python reports it when it is collected at exit. The message arrived during
    # shutdown and is dropped with the node, so the report is noise, not a lost command.
    warnings.filterwarnings('ignore', message="coroutine 'await_or_execute' was never awaited",
                            category=RuntimeWarning)
    node = None
    code = 0
    try:
        node = factory()
        run = getattr(node, 'run', None)
        if callable(run):
            executor = (executor_factory or SingleThreadedExecutor)()
            executor.add_node(node)
            code = int(run(executor))
        else:
            rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except startup_errors as err:
        if node is not None:
            raise
        rclpy.logging.get_logger(node_name).fatal(f'cannot start: {err}')
        code = 2
    except RuntimeError:    # rclpy's RCLError and pybind11 errors of a context that a signal just ended
        if node is None or not ended_by_signal():
            raise
    finally:
        signals.returned()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code
