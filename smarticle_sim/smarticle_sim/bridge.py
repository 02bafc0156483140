"""The simulation bridge without ROS: physics driven by external joint commands, with lock-step bookkeeping.

The sim bridge node (``sim_bridge_node.py``) turns messages into calls on ``SimBridgeCore`` and its
outputs back into messages; everything here is plain Python and NumPy, so tests and benchmarks can
drive the same code without ROS.

Timing. The core advances in *publish periods*: a whole number of control ticks after which the node
publishes ``/clock``, joint states, FSR and poses. In lock-step mode the core advances from sim time
``t_k`` only once every robot has sent a joint command stamped ``t_k`` or later (the gait node in
``lockstep`` mode answers every ``/clock`` message with exactly one such command), so a run depends
only on the seed and the commands, never on process scheduling.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from smarticle_common import topics
from smarticle_common.commands import CheckedCommand, check_command
from smarticle_common.facts import GAIT_PERIOD, PRESETS, TAG_DICTIONARY, TAG_SIZE
from smarticle_common.gait import ALPHA_MAX_RANGE_DEG, GaitConfig
from smarticle_common.params import ParamSpec

from .camera import BACKENDS, CameraConfig, OverheadCamera
from .errors import ConfigError
from .scenes import SCENE_KINDS, Scene, build_scene
from .config_builder import build_config
from .settings import FRICTION_LENGTH, PhysicsConfig, SimConfig
from .physics import FsrReading, Physics
from .runner import Runner

NODE_NAME = 'sim_bridge'
#: Default wall seconds the lock-step bridge waits for a tick's joint commands (the first tick: the nodes' start).
TICK_TIMEOUT, START_TIMEOUT = 10.0, 120.0
_PHYSICS = PhysicsConfig()
#: The parameters that are PhysicsConfig and NoiseConfig fields of the same names (``build_config``).
BRIDGE_PHYSICS = ('time_step', 'control_tick', 'solver_iterations')
BRIDGE_NOISE = ('friction_sd', 'friction_length')

#: Every parameter of the sim bridge node, declared once (node) and shipped as config/sim_bridge.yaml.
PARAMS: tuple[ParamSpec, ...] = (
    ParamSpec('preset', 'small', f'robot preset: {", ".join(sorted(PRESETS))}'),
    ParamSpec('scene', 'dense', f'scene kind: {", ".join(SCENE_KINDS)}'),
    ParamSpec('robots', 7, 'number of robots (dense and random scenes)', 1, 200),
    ParamSpec('seed', 1, 'seed of the scene builder (a whole number >= 0)', 0),
    ParamSpec('alpha_max_deg', 90.0, "amplitude of the robots' start shape in degrees: use the gait "
              "nodes' alpha_max_deg", ALPHA_MAX_RANGE_DEG[0], ALPHA_MAX_RANGE_DEG[1]),
    ParamSpec('period', GAIT_PERIOD, "gait period of the start shape (s): use the gait nodes' period", 0.05, 60.0),
    ParamSpec('phase_jitter', 0.0, "dense scene: each robot's gait phase is offset by a seeded draw in "
              "+-this many periods (a stand-in for the robots' phase drift); give every gait node its "
              "robot's phase (BridgeSettings.scene() tells them; the demo does)", 0.0, 0.5),
    ParamSpec('friction_sd', 0.0, 'relative standard deviation of the body-plate friction across the plate '
              '(a seeded smooth random field from the scene seed; 0 = uniform; the cited figure is 0.06, '
              'docs/sim_core.md "Noise with a cause")', 0.0, 0.2),
    ParamSpec('friction_length', FRICTION_LENGTH, 'correlation length of the friction field (m)', 0.005, 1.0),
    ParamSpec('pair_r', 1.3, 'pair scene: centre distance in body lengths', 0.1, 10.0),
    ParamSpec('pair_theta_deg', 0.0, "pair scene: polar angle of robot 1 from robot 0's body x axis (deg)"),
    ParamSpec('pair_phi_deg', 180.0, 'pair scene: heading of robot 1 minus heading of robot 0 (deg)'),
    ParamSpec('pair_phase_0', 0.0, 'pair scene: gait phase of robot 0 (fraction of a period)', 0.0, 0.999999),
    ParamSpec('pair_phase_1', 0.0, 'pair scene: gait phase of robot 1 (fraction of a period)', 0.0, 0.999999),
    ParamSpec('time_step', _PHYSICS.time_step, 'physics time step (s)', 1e-5, 0.1),
    ParamSpec('control_tick', _PHYSICS.control_tick, 'control tick (s): a whole number of time steps',
              1e-5, 1.0),
    ParamSpec('solver_iterations', _PHYSICS.solver_iterations, 'PyBullet solver iterations', 1, 1000),
    ParamSpec('publish_period', 0.05, 'sim seconds between publications of /clock, joint states, FSR and '
              'poses (a whole number of control ticks); in lock-step also the command barrier', 1e-4, 1.0),
    ParamSpec('mode', 'lockstep', "'lockstep' (deterministic; waits for every robot's command) or 'free'"),
    ParamSpec('real_time_factor', 0.0, 'free mode: target sim seconds per wall second (0 = as fast as '
              'possible)', 0.0, 1000.0),
    ParamSpec('duration', 0.0, 'sim seconds to run before exiting (0 = until stopped)', 0.0, 1e7),
    ParamSpec('start_at', 0.5, 'publish /smarticles/start with this sim time (s); negative = do not', -1.0,
              1e7),
    ParamSpec('pose_noise_xy', 0.0, 'standard deviation of Gaussian noise on published positions (m)',
              0.0, 1.0),
    ParamSpec('pose_noise_heading_deg', 0.0, 'standard deviation of noise on published headings (deg)',
              0.0, 180.0),
    ParamSpec('noise_seed', 0, 'seed of the pose noise'),
    ParamSpec('wait_for_subscribers', 0, 'before stepping, wait until /smarticles/poses has this many '
              'subscribers (lets a recorder or a test connect first)', 0, 100),
    ParamSpec('joint_limit_deg', 125.0, 'joint commands beyond +-this angle are clamped (deg)', 1.0, 180.0),
    ParamSpec('camera_rate', 20.0, 'overhead frames per sim second, rendered only while '
              '/overhead_camera/image_raw has subscribers (0 = no camera); frames are taken at publish '
              'times, so at most one per publish period',
              0.0, 1000.0),
    ParamSpec('camera_width', 1920, 'overhead camera image width (px)', 16, 8192),
    ParamSpec('camera_height', 1080, 'overhead camera image height (px)', 16, 8192),
    ParamSpec('camera_view', 0.6, 'metres of the plate seen across the shorter image side', 0.01, 10.0),
    ParamSpec('camera_elevation', 1.5, 'camera height above the plate (m)', 0.1, 100.0),
    ParamSpec('camera_tag_size', TAG_SIZE, "side of each robot's ArUco tag (m); the tracker's tag_size", 0.001, 0.1),
    ParamSpec('camera_dictionary', TAG_DICTIONARY, "ArUco dictionary of the tags (robot k carries tag k)"),
    ParamSpec('camera_noise', 0.0, 'Gaussian pixel noise, standard deviation in grey levels', 0.0, 255.0),
    ParamSpec('camera_blur', 0.0, 'Gaussian blur sigma (px)', 0.0, 50.0),
    ParamSpec('camera_lighting', 0.0, 'uneven lighting: brightness loss from the centre to a corner '
              '(fraction)', 0.0, 0.95),
    ParamSpec('camera_backend', 'opencv', f'rendering path: {", ".join(BACKENDS)} (opencv is faster)'),
    ParamSpec('camera_seed', 0, 'seed of the camera noise'),
    ParamSpec('tick_timeout', TICK_TIMEOUT, 'lock-step: wall seconds to wait for a robot\'s joint command of a tick '
              '(after the first); then the bridge stops with one line naming the node and the tick '
              '(exit code 4; 0 = wait forever)', 0.0, 3600.0),
    ParamSpec('start_timeout', START_TIMEOUT, 'lock-step: the same for the first tick, which also waits for '
              'the nodes to start (0 = wait forever)', 0.0, 3600.0),
    ParamSpec('hold', False, 'lock-step: also wait at every tick until /sim_bridge/run_until allows it (a '
              'std_msgs/Header whose stamp is the sim time to run up to): a test steps the sim to a time'),
    ParamSpec('wait_for_camera_subscribers', 0, 'before stepping, also wait until /overhead_camera/image_raw '
              'has this many subscribers', 0, 100),
)


@dataclass(frozen=True)
class BridgeSettings:
    """Checked values of PARAMS as one frozen object (SI units inside)."""

    sim: SimConfig
    scene_kind: str
    robots: int
    seed: int
    gait: GaitConfig
    phase_jitter: float
    pair: tuple[float, float, float, float, float]   # r (BL), theta (rad), phi (rad), phase 0, phase 1
    publish_period: float
    lockstep: bool
    real_time_factor: float
    duration: float
    start_at: float
    pose_noise: tuple[float, float]                  # (m, rad)
    noise_seed: int
    joint_limit: float
    wait_for_subscribers: int
    camera: CameraConfig
    camera_rate: float
    wait_for_camera_subscribers: int
    tick_timeout: float = TICK_TIMEOUT     # wall s; 0 = forever
    start_timeout: float = START_TIMEOUT   # wall s; 0 = forever
    hold: bool = False

    @property
    def ticks_per_publish(self) -> int:
        """Control ticks per publish period."""
        ratio = self.publish_period / self.sim.physics.control_tick
        n = round(ratio)
        if n < 1 or abs(ratio - n) > 1e-6 * ratio:
            raise ConfigError(f'{NODE_NAME}.publish_period: {self.publish_period!r} s is not a whole number '
                              f'of control ticks of {self.sim.physics.control_tick!r} s')
        return n

    @classmethod
    def from_values(cls, values: dict[str, Any]) -> BridgeSettings:
        """Build and validate settings from checked parameter values (ConfigError names the field)."""
        if values['mode'] not in ('lockstep', 'free'):
            raise ConfigError(f"{NODE_NAME}.mode must be 'lockstep' or 'free', got {values['mode']!r}")
        if values['scene'] not in SCENE_KINDS:
            raise ConfigError(f'{NODE_NAME}.scene must be one of {", ".join(SCENE_KINDS)}, '
                              f'got {values["scene"]!r}')
        # the friction field is physics, so the bridge applies it; clock rates and servo timing belong to
        # the gait nodes and the boards on this path (docs/sim_core.md, "Noise with a cause")
        sim = build_config(values['preset'], {name: values[name] for name in BRIDGE_PHYSICS},
                           noise={name: values[name] for name in BRIDGE_NOISE})
        gait = GaitConfig.from_degrees(values['alpha_max_deg'], values['period'], sim.robot.servo_speed)
        try:
            camera = CameraConfig(
                width=values['camera_width'], height=values['camera_height'], view=values['camera_view'],
                elevation=values['camera_elevation'], tag_size=values['camera_tag_size'],
                dictionary=values['camera_dictionary'], noise=values['camera_noise'],
                blur=values['camera_blur'], lighting=values['camera_lighting'], seed=values['camera_seed'],
                backend=values['camera_backend'], plate_size=sim.physics.plate_size, robot=sim.robot)
        except ConfigError as err:
            raise ConfigError(f'{NODE_NAME} camera_* parameters: {err}') from err
        settings = cls(
            sim, values['scene'], values['robots'], values['seed'], gait, values['phase_jitter'],
            (values['pair_r'], math.radians(values['pair_theta_deg']), math.radians(values['pair_phi_deg']),
             values['pair_phase_0'], values['pair_phase_1']),
            values['publish_period'], values['mode'] == 'lockstep', values['real_time_factor'],
            values['duration'], values['start_at'],
            (values['pose_noise_xy'], math.radians(values['pose_noise_heading_deg'])),
            values['noise_seed'], math.radians(values['joint_limit_deg']), values['wait_for_subscribers'],
            camera, values['camera_rate'], values['wait_for_camera_subscribers'],
            tick_timeout=values['tick_timeout'], start_timeout=values['start_timeout'], hold=values['hold'])
        settings.ticks_per_publish  # noqa: B018 - validates publish_period against the control tick
        return settings

    def scene(self) -> Scene:
        """The scene these settings describe (robot placements and each robot's gait phase)."""
        r, theta, phi, p0, p1 = self.pair
        return build_scene(self.scene_kind, self.sim.robot, self.gait, self.robots, seed=self.seed, r=r,
                           theta=theta, phi=phi, phases=(p0, p1), phase_jitter=self.phase_jitter)

    @classmethod
    def defaults(cls, **changes: Any) -> BridgeSettings:
        """Settings from the PARAMS defaults with some values changed (by parameter name)."""
        values = {spec.name: spec.default for spec in PARAMS}
        unknown = set(changes) - set(values)
        if unknown:
            raise ConfigError(f'unknown sim bridge parameter(s): {", ".join(sorted(unknown))}')
        values.update(changes)
        for spec in PARAMS:
            values[spec.name] = spec.check(values[spec.name], f'{NODE_NAME} parameter')
        return cls.from_values(values)


def poses_digest(poses: np.ndarray) -> str:
    """SHA-256 (hex) of an (N, 3) pose array as float64 bytes: equal digests, equal poses bit for bit."""
    return hashlib.sha256(np.ascontiguousarray(poses, dtype=np.float64).tobytes()).hexdigest()


class SimBridgeCore:
    """Physics whose robots follow external joint commands, advanced one publish period at a time."""

    def __init__(self, settings: BridgeSettings) -> None:
        self.settings = settings
        scene = settings.scene()
        self.physics = Physics(settings.sim, scene)
        self.runner = Runner(self.physics)   # no controllers: the commands come from outside
        self.n_robots = self.physics.n_robots
        self.limits = {name: (-settings.joint_limit, settings.joint_limit) for name in topics.JOINT_NAMES}
        self.command_stamp_ns = np.full(self.n_robots, -1, dtype=np.int64)
        self._targets = self.physics.arm_angles().copy()
        self._noise = np.random.default_rng(settings.noise_seed)
        self.ticks_per_publish = settings.ticks_per_publish
        self._camera: OverheadCamera | None = None
        self._next_frame_ns = 0
        self._fsr_watch: list[int] = []
        self._fsr_reading: FsrReading | None = None   # of the robots in _fsr_watch, while there are any
        #: Per robot: joint commands applied, and contacts begun (touching another robot at a publication
        #: after not touching one at the previous): the run's summary.
        self.commands = np.zeros(self.n_robots, dtype=np.int64)
        self.contacts = np.zeros(self.n_robots, dtype=np.int64)
        self._touching: np.ndarray = np.zeros(self.n_robots, dtype=bool)

    def _fsr_step(self, _: Runner) -> None:
        self._fsr_reading.step()  # type: ignore[union-attr]   # hooked only while the reading exists

    def fsr_sample(self, robots: list[int]) -> np.ndarray:
        """(len(robots), 4) FSR sample of ``robots``: each face's peak force since the previous sample.

        The same sample as the batch path's ``FeedbackController`` (collisions are kicks shorter than a
        control tick). The peak is tracked for the robots of the previous call; for others (a new
        listener) the sample is the force at this instant. With nobody to sample (``robots`` empty) the
        per-step hook is removed and the physics steps a tick at once again.
        """
        peak = self._fsr_reading.take_peak() if self._fsr_reading is not None else None
        if peak is not None and list(robots) == self._fsr_watch:   # the peak of the readings, which include
            now = peak                                                # this instant's step
        else:
            now = self.physics.fsr(robots)
            if peak is not None:
                for row, k in enumerate(robots):
                    if k in self._fsr_watch:
                        now[row] = peak[self._fsr_watch.index(k)]
        if list(robots) != self._fsr_watch:   # a new set of robots: a new reading (its average starts from zero)
            self._fsr_reading = FsrReading(self.physics, robots) if robots else None
        self._fsr_watch = list(robots)
        hooked = self._fsr_step in self.runner.step_hooks
        if robots and not hooked:
            self.runner.step_hooks.append(self._fsr_step)
        elif not robots and hooked:
            self.runner.step_hooks.remove(self._fsr_step)
        return now

    @property
    def time(self) -> float:
        """Sim time (s)."""
        return self.physics.time

    @property
    def time_ns(self) -> int:
        """Sim time in integer nanoseconds (the stamp of what is published now)."""
        return round(self.physics.time * 1e9)

    def apply_command(self, robot: int, names: list[str], positions: list[float],
                      velocities: list[float], stamp_ns: int) -> CheckedCommand:
        """Check a joint command for ``robot`` and hand its usable part to the physics."""
        if stamp_ns > self.time_ns:   # a command for a time not reached: lock-step would skip that tick
            out = CheckedCommand()
            out.flag('future_stamps', f'joint command stamped {stamp_ns * 1e-9:.6f} s, after the sim time '
                                      f'{self.time_ns * 1e-9:.6f} s: ignored')
            return out
        servo = self.settings.sim.robot.servo_speed
        checked = check_command(names, positions, velocities, self.limits, servo, servo)
        if checked.targets:
            for j, name in enumerate(topics.JOINT_NAMES):
                if name in checked.targets:
                    self._targets[robot, j] = checked.targets[name]
            speed = min(checked.speeds.values())
            self.physics.command(robot, (float(self._targets[robot, 0]), float(self._targets[robot, 1])),
                                         speed)
        self.command_stamp_ns[robot] = max(self.command_stamp_ns[robot], stamp_ns)
        self.commands[robot] += 1
        return checked

    def waiting_for(self) -> list[int]:
        """Robots whose command for the current time has not arrived (lock-step barrier)."""
        return [int(k) for k in np.flatnonzero(self.command_stamp_ns < self.time_ns)]

    def advance(self) -> None:
        """Run one publish period of control ticks (SimTrouble propagates); count the contacts begun."""
        self.runner.run(self.ticks_per_publish)
        touching: np.ndarray = np.asarray(self.physics.robot_contacts().any(axis=1), dtype=bool)
        self.contacts += touching & ~self._touching
        self._touching = touching

    def summary(self, robot: int) -> dict[str, int]:
        """What ``robot`` did in this run: joint commands applied, contacts begun with other robots."""
        return {'commands': int(self.commands[robot]), 'contacts': int(self.contacts[robot])}

    def poses(self) -> np.ndarray:
        """(N, 3) published poses: ground truth plus the configured Gaussian noise."""
        poses = self.physics.poses()
        sigma_xy, sigma_heading = self.settings.pose_noise
        if sigma_xy == 0.0 and sigma_heading == 0.0:
            return poses
        noise = self._noise.normal(size=poses.shape) * np.array([sigma_xy, sigma_xy, sigma_heading])
        return poses + noise

    def poses_digest(self) -> str:
        """SHA-256 of the ground-truth poses now (float64 bytes): one run against another, bit for bit."""
        return poses_digest(self.physics.poses())

    def frame_due(self) -> bool:
        """True when the camera is on and the current sim time has reached the next frame time."""
        return self.settings.camera_rate > 0.0 and self.time_ns >= self._next_frame_ns

    def skip_frame(self) -> None:
        """Schedule the next frame one camera period after the current time (whether rendered or not)."""
        period_ns = round(1e9 / self.settings.camera_rate)
        self._next_frame_ns = (self.time_ns // period_ns + 1) * period_ns

    @property
    def camera(self) -> OverheadCamera:
        """The overhead camera (created at its first use, so a run without subscribers never loads OpenCV)."""
        if self._camera is None:
            self._camera = OverheadCamera(self.settings.camera)
        return self._camera

    def render_frame(self) -> np.ndarray:
        """A mono8 overhead frame of the ground truth now (robots, arms, tags); schedules the next one."""
        state = self.physics.state()
        frame = self.camera.render(state.poses, state.arm_angles, physics=self.physics)
        if self.settings.camera_rate > 0.0:
            self.skip_frame()
        return frame

    def close(self) -> None:
        """Release the physics client."""
        self.physics.close()
