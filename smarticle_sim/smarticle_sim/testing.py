"""Test a controller in the simulation: the lock-step sim bridge and the user's nodes, started for one test.

The pytest plugin of ``smarticle_sim`` (entry point ``pytest11``, so any test run in an environment where
the package is installed has it) gives the fixture ``sim_world``::

    def test_my_controller(sim_world):
        sim_world.start(scene='pair', seed=3, controller='smarticle_example_controller/square_stop')
        sim_world.step_to(4.0)                       # sim seconds; the bridge then holds
        assert sim_world.poses()[0, 0] != sim_world.poses(0.0)[0, 0]

``SimWorld.start`` starts the sim bridge (lock-step, ``hold:=true``) with a scene, robots, seed and preset,
and a controller per robot (the stack's gait by default, or ``package/executable``) with an optional
feedback node, each as a real process in a DDS domain of its own with localhost discovery. ``step_to``
lets the lock-step run up to a sim time and waits there; ``poses``, ``fsr``, ``halts``, ``glider_reports``
and ``counters`` (the bridge's bad-input counters) read what happened. The fixture stops every process,
the probe node and the domain at the end of the test, failed or not.

A node that misses a tick: the bridge waits ``tick_timeout`` wall seconds, then stops with one line
naming the node and the tick; ``step_to`` raises ``SimStopped`` with that line, which the fixture turns
into the test's failure message.
"""

from __future__ import annotations

import functools
import math
import os
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from smarticle_common import topics
from smarticle_common.launching import DomainReservation, ProcessGroup, executable, isolated_ros_env

from .errors import SimError

#: The stack's lock-step controller and feedback node, as ``package/executable``.
GAIT = 'smarticle_driver/gait'
FEEDBACK = 'smarticle_feedback/feedback'

#: Wall seconds ``step_to`` waits, by default, per sim second to run (plus STEP_SLACK): generous, the
#: machine may be shared.
STEP_WALL_PER_SIM, STEP_SLACK = 20.0, 60.0


class SimStopped(SimError):
    """The sim bridge ended before the time a test stepped to (its last error line is the message)."""


@dataclass
class Sample:
    """Everything the probe received, by stamp (ns)."""

    poses: dict[int, np.ndarray] = field(default_factory=dict)              # stamp -> (N, 3) x, y, heading
    fsr: dict[int, dict[int, np.ndarray]] = field(default_factory=dict)     # robot -> stamp -> (4,) N
    joint_states: dict[int, dict[int, np.ndarray]] = field(default_factory=dict)   # robot -> stamp -> (2,) rad
    halts: list[tuple[int, int, str]] = field(default_factory=list)         # (stamp, robot, face)
    gliders: list[tuple[int, list[dict[str, str]]]] = field(default_factory=list)   # (stamp, statuses)
    bridge: dict[str, str] = field(default_factory=dict)                    # the bridge's last diagnostics
    bridge_message: str = ''


def node_executable(name: str) -> str:
    """The program of ``package/executable`` (a ROS install's ``lib/<package>``, else the console script)."""
    package, _, program = name.rpartition('/')
    for prefix in (p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p and package):
        candidate = Path(prefix) / 'lib' / package / program
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
    try:
        return executable(program)
    except FileNotFoundError as err:
        raise SimError(f'cannot start {name}: {err}') from None


def ros_args(name: str | None = None, namespace: str | None = None, params: Mapping[str, Any] | None = None,
             params_file: str | Path | None = None) -> list[str]:
    """``--ros-args`` of a node: its name, namespace, a parameters file, then single parameters."""
    out = ['--ros-args']
    if name:
        out += ['-r', f'__node:={name}']
    if namespace:
        out += ['-r', f'__ns:={namespace}']
    if params_file:
        out += ['--params-file', str(params_file)]
    for key, value in (params or {}).items():
        text = str(value).lower() if isinstance(value, bool) else repr(value) if isinstance(value, float) else value
        out += ['-p', f'{key}:={text}']
    return out


def _stamp(header_stamp: Any) -> int:
    return int(header_stamp.sec) * 10**9 + int(header_stamp.nanosec)


def _heading(q: Any) -> float:
    return 2.0 * math.atan2(q.z, q.w)


class SimWorld:
    """The lock-step sim bridge, the nodes under test and a probe, in a DDS domain of their own."""

    def __init__(self, log_dir: Path) -> None:
        """Reserve a domain and make the probe node in it (nothing is started until ``start``)."""
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.log_dir = Path(log_dir)
        self.domain = DomainReservation()
        self.env = isolated_ros_env(self.domain.domain_id)
        self.procs = ProcessGroup(self.log_dir, self.env)
        self.bridge: Any = None
        self.started: dict[str, Any] = {}   # full node name -> process
        self.data = Sample()
        self.robots = 0
        previous = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE')
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'   # read by the middleware at init
        try:
            self.context = rclpy.Context()
            rclpy.init(context=self.context, domain_id=self.domain.domain_id)
        finally:
            if previous is None:
                del os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE']
            else:
                os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = previous
        self.probe = rclpy.create_node('sim_world_probe', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.probe)
        self.permit = self.probe.create_publisher(topics.message_class('std_msgs/msg/Header'),
                                                  topics.topic('run_until'),
                                                  topics.qos_profile(topics.spec_of('run_until').qos))
        self.closed = False
        self.matched: list[Any] = []   # subscriptions whose publishers must have matched before the first step

    # ------------------------------------------------------------------ starting
    def start(self, *, scene: str = 'pair', robots: int = 2, seed: int = 1, preset: str = 'small',
              duration: float = 0.0, params: Mapping[str, Any] | None = None,
              controller: str | Sequence[str] = GAIT,
              controller_params: Mapping[str, Any] | Sequence[Mapping[str, Any]] | None = None,
              controller_params_file: str | Path | None = None, feedback: str | None = None,
              feedback_params: Mapping[str, Any] | Sequence[Mapping[str, Any]] | None = None,
              fsr: bool = False, joint_states: bool = False, gliders: bool = False,
              tick_timeout: float | None = None) -> None:
        """Start the bridge (lock-step, held at t = 0) and, for every robot, ``controller`` and ``feedback``.

        ``controller``: ``package/executable`` or the path of a Python script, for every robot, or a list
        of them, one per robot.

        ``params``: more sim bridge parameters (``pair_r``, ``alpha_max_deg``, ``start_at``, ...);
        ``controller_params`` / ``controller_params_file`` and ``feedback_params`` go to every robot's
        node (a list of dicts: one per robot); each node also gets ``robot_id``, ``lockstep``,
        ``use_sim_time`` and, a controller, ``wait_for_feedback`` (true when a feedback node runs).
        ``fsr`` records every robot's FSR samples (the bridge then samples them), ``joint_states`` its arm
        angles; ``gliders`` also starts the glider monitor. ``tick_timeout``: wall seconds the bridge
        waits for a node's command of a tick (None: the bridge's default).
        """
        if self.bridge is not None:
            raise SimError('this SimWorld is started already')
        if scene == 'pair' and robots != 2:
            raise SimError('the pair scene has 2 robots')
        self.robots = robots
        self._listen(robots, fsr, joint_states, gliders, bool(feedback))

        def of_robot(value: Any, k: int) -> Any:
            return value[k] if isinstance(value, Sequence) and not isinstance(value, str) else value
        for k in range(robots):
            namespace = topics.robot_namespace(k)
            mine = of_robot(controller, k)
            if feedback:
                self.node(feedback, namespace=namespace, name='feedback' if feedback == FEEDBACK else None,
                          params={**(of_robot(feedback_params, k) or {}), 'robot_id': k, 'lockstep': True,
                                  'use_sim_time': True})
            self.node(mine, namespace=namespace, name='gait' if mine == GAIT else None,
                      params_file=controller_params_file,
                      params={**(of_robot(controller_params, k) or {}), 'robot_id': k, 'lockstep': True,
                              'wait_for_feedback': bool(feedback), 'use_sim_time': True})
        if gliders:
            self.node('smarticle_tracking/glider_monitor', params={'use_sim_time': True, 'show_arms': False})
        bridge_params = {'preset': preset, 'scene': scene, 'robots': robots, 'seed': seed, 'mode': 'lockstep',
                         'duration': float(duration), 'hold': True,
                         'wait_for_subscribers': 2 if gliders else 1,   # the probe (and the glider monitor)
                         **({} if tick_timeout is None else {'tick_timeout': float(tick_timeout)}), **(params or {})}
        self.bridge = self.procs.start(node_executable('smarticle_sim/sim_bridge'), *ros_args(params=bridge_params))
        self.started['/sim_bridge'] = self.bridge

    def node(self, spec: str, *, namespace: str | None = None, name: str | None = None,
             params: Mapping[str, Any] | None = None, params_file: str | Path | None = None,
             command: Sequence[str] | None = None) -> Any:
        """Start one more node: ``package/executable``, a Python script's path, or a ``command`` list."""
        if command is None and spec.endswith('.py'):
            command = [sys.executable, spec]
        program, *rest = list(command) if command else [node_executable(spec)]
        proc = self.procs.start(program, *rest, *ros_args(name, namespace, params, params_file))
        self.started[f'{(namespace or "").rstrip("/")}/{name or Path(spec).stem}'] = proc
        return proc

    def _listen(self, robots: int, fsr: bool, joint_states: bool, gliders: bool, halts: bool) -> None:
        """Subscribe the probe to poses, halts, the bridge's diagnostics and, if asked, FSR, arms and gliders."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy

        keep_all = QoSProfile(depth=10000, reliability=ReliabilityPolicy.BEST_EFFORT)
        message = topics.message_class
        self.probe.create_subscription(message(topics.spec_of('poses').type), topics.topic('poses'),
                                       self._on_poses, keep_all)
        for k in range(robots):
            halt = self.probe.create_subscription(
                message('std_msgs/msg/Header'), topics.topic('halt', k),
                functools.partial(self._on_halt, k), QoSProfile(depth=1000))
            if halts:   # the first step waits until the feedback nodes' halts reach the probe
                self.matched.append(halt)
            if fsr:
                self.data.fsr[k] = {}
                self.probe.create_subscription(
                    message(topics.spec_of('fsr').type), topics.topic('fsr', k),
                    functools.partial(self._on_fsr, k), keep_all)
            if joint_states:
                self.data.joint_states[k] = {}
                self.probe.create_subscription(
                    message(topics.spec_of('joint_states').type), topics.topic('joint_states', k),
                    functools.partial(self._on_joint_states, k), keep_all)
        diagnostics = topics.spec_of('diagnostics')
        self.probe.create_subscription(message(diagnostics.type), diagnostics.resolve(), self._on_diagnostics,
                                       QoSProfile(depth=1000))
        if gliders:   # the first step also waits for the glider monitor's reports to reach the probe
            self.matched.append(self.probe.create_subscription(
                message(topics.spec_of('gliders').type), topics.topic('gliders'), self._on_gliders,
                QoSProfile(depth=1000)))

    def _on_halt(self, robot: int, msg: Any) -> None:
        self.data.halts.append((_stamp(msg.stamp), robot, msg.frame_id))

    def _on_fsr(self, robot: int, msg: Any) -> None:
        self.data.fsr[robot][_stamp(msg.header.stamp)] = np.array(msg.effort)

    def _on_joint_states(self, robot: int, msg: Any) -> None:
        self.data.joint_states[robot][_stamp(msg.header.stamp)] = np.array(msg.position)

    def _on_poses(self, msg: Any) -> None:
        self.data.poses[_stamp(msg.header.stamp)] = np.array(
            [[p.position.x, p.position.y, _heading(p.orientation)] for p in msg.poses])

    def _on_diagnostics(self, msg: Any) -> None:
        for status in msg.status:
            if status.name == 'sim_bridge':
                self.data.bridge = {v.key: v.value for v in status.values}
                self.data.bridge_message = status.message

    def _on_gliders(self, msg: Any) -> None:
        self.data.gliders.append((_stamp(msg.header.stamp),
                                  [{'name': s.name, **{v.key: v.value for v in s.values}} for s in msg.status]))

    # ------------------------------------------------------------------ stepping
    def spin(self, seconds: float) -> None:
        """Let the probe receive for ``seconds`` wall seconds."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=min(0.02, max(deadline - time.monotonic(), 0.0)))

    def spin_until(self, predicate: Callable[[], bool], timeout: float) -> bool:
        """Let the probe receive until ``predicate()`` holds or ``timeout`` wall seconds pass; the predicate."""
        deadline = time.monotonic() + timeout
        while not predicate() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)
        return predicate()

    def sim_time(self) -> float:
        """The bridge's sim time (s) as its diagnostics last said (-1 before its first)."""
        return float(self.data.bridge.get('sim_time', -1.0))

    def step_to(self, t: float, timeout: float | None = None) -> None:
        """Let the lock-step run up to sim time ``t`` (s) and wait until the bridge holds there.

        Raises SimStopped with the bridge's error line if it ends first (a node missed a tick), and
        SimError if ``timeout`` wall seconds pass.
        """
        if self.bridge is None:
            raise SimError('start the SimWorld first')
        target_ns = round(t * 1e9)
        if self.matched:
            deadline = time.monotonic() + STEP_SLACK
            while any(sub.get_publisher_count() == 0 for sub in self.matched):
                if time.monotonic() > deadline:
                    raise SimError('the feedback nodes or the glider monitor did not come up in time')
                self.executor.spin_once(timeout_sec=0.05)
            self.matched = []
        header = topics.message_class('std_msgs/msg/Header')()
        header.stamp.sec, header.stamp.nanosec = divmod(target_ns, 10**9)
        self.permit.publish(header)
        limit = timeout if timeout is not None else STEP_SLACK + STEP_WALL_PER_SIM * max(t - max(self.sim_time(), 0), 0)
        deadline = time.monotonic() + limit
        while not (self.data.bridge_message == 'held' and round(self.sim_time() * 1e9) >= target_ns - 500_000):
            if self.bridge.poll() is not None:
                self.spin(0.2)
                if self.data.bridge_message == 'finished':
                    return   # the run's duration ended it first
                raise SimStopped(self.stop_line())
            if time.monotonic() > deadline:
                raise SimError(f'the sim did not reach t = {t:g} s within {limit:g} s (at {self.sim_time():g} s)')
            self.executor.spin_once(timeout_sec=0.02)
        self.spin(0.05)   # the last poses (best effort) arrive with the hold

    def stop_line(self) -> str:
        """The bridge's last error line (or its exit code when it printed none)."""
        lines = [line for line in self.procs.output(self.bridge).splitlines() if '[ERROR]' in line or 'FATAL' in line]
        if lines:
            return lines[-1].split(']: ', 1)[-1]
        return f'the sim bridge ended with exit code {self.bridge.returncode}'

    # ------------------------------------------------------------------ reading
    def poses(self, t: float | None = None) -> np.ndarray:
        """(robots, 3) poses (x m, y m, heading rad) at sim time ``t`` (default: the latest received)."""
        if not self.data.poses:
            raise SimError('no poses received yet')
        stamp = max(self.data.poses) if t is None else round(t * 1e9)
        if stamp not in self.data.poses:
            raise SimError(f'no poses stamped {t} s were received')
        return self.data.poses[stamp]

    def fsr(self, robot: int) -> dict[int, np.ndarray]:
        """FSR samples of ``robot`` by stamp (ns); start(fsr=True) records them."""
        return self.data.fsr[robot]

    def joint_states(self, robot: int) -> dict[int, np.ndarray]:
        """Arm angles (rad) of ``robot`` by stamp (ns); start(joint_states=True) records them."""
        return self.data.joint_states[robot]

    @property
    def halts(self) -> list[tuple[int, int, str]]:
        """Halts of the feedback nodes: (stamp ns, robot, face), sorted."""
        return sorted(self.data.halts)

    @property
    def glider_reports(self) -> list[tuple[int, list[dict[str, str]]]]:
        """The glider monitor's reports (stamp ns, one dict per status); start(gliders=True) starts it."""
        return self.data.gliders

    def counters(self) -> dict[str, int]:
        """The bridge's bad-input counters from its last diagnostics (nonfinite_targets, future_stamps, ...)."""
        return {k: int(v) for k, v in self.data.bridge.items() if v.lstrip('-').isdigit()}

    def output(self, name: str = '/sim_bridge') -> str:
        """What a started node (by full name, e.g. ``/smarticle_0/gait``) has printed so far."""
        return self.procs.output(self.started[name])

    # ------------------------------------------------------------------ ending
    def close(self) -> None:
        """Stop every process, then the probe and its context; release the domain (safe to call twice)."""
        if self.closed:
            return
        self.closed = True
        try:
            self.procs.stop_all()
        finally:
            self.executor.shutdown()
            self.probe.destroy_node()
            self.context.try_shutdown()
            self.domain.close()

    def __enter__(self) -> SimWorld:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@pytest.fixture
def sim_world(tmp_path: Path) -> Iterator[SimWorld]:
    """A SimWorld for one test: its processes and domain end with the test, failed or not.

    A bridge that stops early (a node missed a tick) fails the test with the bridge's line.
    """
    world = SimWorld(tmp_path / 'sim_world')
    try:
        yield world
    finally:
        world.close()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item: pytest.Item) -> Iterator[None]:
    """A SimStopped raised in a test that uses ``sim_world`` fails it with the bridge's line alone."""
    outcome: Any = yield
    if 'sim_world' not in getattr(item, 'fixturenames', ()):
        return
    excinfo = outcome.excinfo
    if excinfo is not None and issubclass(excinfo[0], SimStopped):
        outcome.force_exception(pytest.fail.Exception(str(excinfo[1]), pytrace=False))
