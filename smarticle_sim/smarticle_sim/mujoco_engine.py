"""The same scene in a second physics engine (MuJoCo): a cross-check of what Bullet's contact model does.

PyBullet is the simulation of this project. This module steps a ``Scene`` in MuJoCo instead, to tell
what the robots, their gait and their start do from what Bullet's rigid contacts do (issue #11: in Bullet
two robots in phase never glide; is that Bullet's?). It is built from the same facts and returns the same
``Recording`` as ``batch.run_trial``, so the glider analysis and the experiment reports read it unchanged.

What is the same as the Bullet sim: the robot (``RobotSpec``: body and arm boxes, masses with the inertia of
uniform boxes, hinges at the body's ends, arms ``arm_clearance`` above the plate, arms of one robot never
colliding with each other), the scene (positions, headings, starting arm angles), the gait (each robot's
``SquareGait`` gives the speed-limited reference its servos follow) and the friction coefficients.

What differs, on purpose: MuJoCo's contacts are soft (a spring-damper of time constant
``MujocoSettings.contact_timeconst`` and damping ratio ``contact_dampratio``: 1 absorbs the impact, lower
values rebound) with an elliptic, isotropic friction cone (Bullet's multibody solver uses a pyramid; ``friction_cone``
'pyramidal' gives MuJoCo's pyramid instead), at about the
authors' 1e-4 s step (1/9600 s). The servo is Bullet's: a velocity motor whose speed goal is the gait's
target (the corner being approached) times ``PhysicsConfig.servo_bandwidth``, capped at the gait's speed and
updated every ``servo_update`` (the default Bullet step); MuJoCo drives the joint toward that speed with a
velocity actuator of gain ``servo_kv`` (N m s/rad, integrated implicitly, so a large gain is a stiff motor)
and the robot's torque limit (``RobotSpec.servo_torque``). A large torque limit makes it the authors' rigid
speed-driven motor. A contact
pair takes the larger of the two geoms' friction (MuJoCo's rule): robot-robot pairs get
``friction_robot_robot``, body-plate pairs the larger of that and ``friction_body_plate`` (both 0.3 by default).

Not modelled here: noise (``NoiseConfig``), FSR forces, feedback, Bullet's trouble checks (a non-finite state or
a body tipped past ``PhysicsConfig.max_tilt`` ends the run with ``meta['trouble']`` set, as in Bullet).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from smarticle_common.gait import TIME_EPS, SquareGait
from smarticle_common.poses import body_headings_and_tilts
from smarticle_common.runs import Recording
from smarticle_common.topics import FSR_FACES

from .batch import check_run_request, scene_period
from .errors import SimError
from .scenes import Scene
from .settings import SimConfig

if TYPE_CHECKING:
    import mujoco


@dataclass(frozen=True)
class MujocoSettings:
    """The MuJoCo side of a cross-engine run (SI units)."""

    time_step: float = 1.0 / 9600.0      # about the authors' 1e-4 s Chrono step, 10 to a default Bullet step
    contact_timeconst: float = 0.002     # s, the contact spring-damper's time constant (>= 2 steps)
    contact_dampratio: float = 1.0       # 1: no rebound; below 1 the impact rebounds
    servo_kv: float = 0.1                # N m s / rad: the velocity actuator's gain (a stiff motor)
    servo_update: float = 1.0 / 960.0    # s between servo reference updates (whole steps; the Bullet step)
    noslip_iterations: int = 0           # MuJoCo's post-solve that removes creep under static friction
    friction_cone: str = 'elliptic'      # 'elliptic' (isotropic) or 'pyramidal' (Bullet's kind of cone)

    def __post_init__(self) -> None:
        for name in ('time_step', 'contact_timeconst', 'contact_dampratio', 'servo_kv', 'servo_update'):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
                raise SimError(f'MujocoSettings.{name} must be a positive number, got {value!r}')
        if self.contact_timeconst < 2.0 * self.time_step:
            raise SimError(f'MujocoSettings.contact_timeconst: {self.contact_timeconst:g} s is under two steps '
                           f'({2.0 * self.time_step:g} s); MuJoCo cannot resolve a stiffer contact')
        if abs(self.servo_update / self.time_step - round(self.servo_update / self.time_step)) > 1e-6:
            raise SimError(f'MujocoSettings.servo_update: {self.servo_update:g} s is not a whole number of '
                           f'{self.time_step:g} s steps')
        if isinstance(self.noslip_iterations, bool) or not isinstance(self.noslip_iterations, int) \
                or self.noslip_iterations < 0:
            raise SimError(f'MujocoSettings.noslip_iterations must be an integer >= 0, got {self.noslip_iterations!r}')

        if self.friction_cone not in ('elliptic', 'pyramidal'):
            raise SimError("MujocoSettings.friction_cone must be 'elliptic' or 'pyramidal', "
                           f'got {self.friction_cone!r}')

    @property
    def steps_per_update(self) -> int:
        """Physics steps between servo reference updates."""
        return round(self.servo_update / self.time_step)


def build_model(config: SimConfig, scene: Scene, settings: MujocoSettings) -> mujoco.MjModel:
    """The MJCF model of ``scene``'s robots on the plate (body ``robot{k}``, hinges ``robot{k}_arm{j}``)."""
    import mujoco   # here, so that the settings can be imported (e.g. to check a spec) without the engine

    spec, ph = config.robot, config.physics
    if ph.mass_model != 'uniform':
        raise SimError(f'PhysicsConfig.mass_model: the MuJoCo engine builds the uniform robot only, '
                       f'got {ph.mass_model!r}')
    w, d, h = spec.body_width, spec.body_depth, spec.body_height
    half_l, half_t, half_h = spec.arm_length / 2.0, spec.arm_thickness / 2.0, spec.arm_height / 2.0
    arm_z = spec.arm_clearance + spec.arm_height / 2.0 - h / 2.0
    bodies, excludes, actuators = [], [], []
    for k, robot in enumerate(scene.robots):
        yaw = robot.heading - math.pi / 2.0          # the body's x axis from its normal (as in Physics)
        arms = []
        for j, (sign, axis) in enumerate(((-1.0, -1.0), (1.0, 1.0))):   # Physics: link axes -z and +z
            arms.append(
                f'<body name="robot{k}_link{j}" pos="{sign * w / 2.0!r} 0 {arm_z!r}">'
                f'<joint name="robot{k}_arm{j}" type="hinge" axis="0 0 {axis!r}"/>'
                f'<geom type="box" pos="{sign * half_l!r} 0 0" size="{half_l!r} {half_t!r} {half_h!r}" '
                f'mass="{spec.arm_mass!r}" friction="{ph.friction_robot_robot!r} 0 0"/></body>')
            actuators.append(f'<velocity joint="robot{k}_arm{j}" kv="{settings.servo_kv!r}" '
                             f'forcelimited="true" forcerange="{-spec.servo_torque!r} {spec.servo_torque!r}"/>')
        bodies.append(
            f'<body name="robot{k}" pos="{robot.x!r} {robot.y!r} {h / 2.0!r}" euler="0 0 {yaw!r}"><freejoint/>'
            f'<geom type="box" size="{w / 2.0!r} {d / 2.0!r} {h / 2.0!r}" mass="{spec.body_mass!r}" '
            f'friction="{ph.friction_robot_robot!r} 0 0"/>{"".join(arms)}</body>')
        excludes.append(f'<exclude body1="robot{k}_link0" body2="robot{k}_link1"/>')
    half_plate = ph.plate_size / 2.0
    xml = (f'<mujoco><compiler angle="radian"/>'
           f'<option timestep="{settings.time_step!r}" gravity="0 0 {-ph.gravity!r}" cone="{settings.friction_cone}" '
           f'integrator="implicitfast" noslip_iterations="{settings.noslip_iterations}"/>'
           f'<default><geom condim="3" solref="{settings.contact_timeconst!r} {settings.contact_dampratio!r}"/>'
           f'</default><worldbody>'
           f'<geom name="plate" type="plane" size="{half_plate!r} {half_plate!r} 0.1" '
           f'friction="{ph.friction_body_plate!r} 0 0"/>'
           f'{"".join(bodies)}</worldbody><contact>{"".join(excludes)}</contact>'
           f'<actuator>{"".join(actuators)}</actuator></mujoco>')
    return mujoco.MjModel.from_xml_string(xml)


def run_mujoco(config: SimConfig, scene: Scene, periods: float, sample_every: int,
               settings: MujocoSettings | None = None) -> Recording:
    """Run ``scene`` for ``periods`` gait periods in MuJoCo from a synchronised start at t = 0.

    Samples every ``sample_every`` control ticks (``PhysicsConfig.control_tick``), like ``run_trial``;
    ``contacts[s]`` is True for a pair of robots that touched at any servo update (1/960 s) since the sample before.
    """
    import mujoco

    settings = settings or MujocoSettings()
    sample_every = check_run_request(periods, sample_every)
    gaits = [SquareGait(r.gait) if r.gait is not None else None for r in scene.robots]
    period = scene_period(scene)
    model = build_model(config, scene, settings)
    data = mujoco.MjData(model)
    n = len(scene.robots)
    qpos = [model.jnt_qposadr[model.joint(f'robot{k}_arm{j}').id] for k in range(n) for j in (0, 1)]
    free = np.array([model.jnt_qposadr[model.body_jntadr[model.body(f'robot{k}').id]] for k in range(n)])
    owner = np.full(model.ngeom, -1)
    for g in range(model.ngeom):
        name = model.body(model.geom_bodyid[g]).name
        if name.startswith('robot'):
            owner[g] = int(name[5:].split('_')[0])
    for k, robot in enumerate(scene.robots):
        data.qpos[qpos[2 * k]], data.qpos[qpos[2 * k + 1]] = robot.alpha1, robot.alpha2
    mujoco.mj_forward(model, data)
    bandwidth = config.physics.servo_gain() / config.physics.time_step   # Bullet's speed goal per radian
    targets = np.array([[r.alpha1, r.alpha2] for r in scene.robots])
    speeds = np.zeros(n)
    for gait in gaits:
        if gait is not None:
            gait.start(0.0)
    sample_dt = sample_every * config.physics.control_tick
    samples = int(math.floor(periods * period / sample_dt + 1e-9)) + 1
    updates_per_sample = round(sample_dt / settings.servo_update)
    if abs(sample_dt / settings.servo_update - updates_per_sample) > 1e-6:
        raise SimError(f'the sample interval {sample_dt:g} s is not a whole number of servo updates '
                       f'({settings.servo_update:g} s)')
    times = np.zeros(samples)
    poses = np.zeros((samples, n, 3))
    arms = np.zeros((samples, n, 2))
    touching = np.zeros((samples, n, n), dtype=bool)
    meta: dict[str, Any] = {
        'engine': 'mujoco', 'mujoco_version': mujoco.__version__, 'mujoco': asdict(settings),
        'robot': asdict(config.robot), 'physics': asdict(config.physics), 'scene': scene.name, 'seed': scene.seed,
        'periods': periods, 'period': period, 'start_time': 0.0, 'sample_every': sample_every,
        'sample_rate': 1.0 / sample_dt, 'fsr_recorded': False, 'contacts_recorded': True,
        'fsr_faces': list(FSR_FACES), 'trouble': '', 'peak_tilt_deg': 0.0, 'peak_overlap_mm': 0.0}
    peak_tilt, peak_overlap = 0.0, 0.0
    seen = np.zeros((n, n), dtype=bool)
    taken = 0
    for s in range(samples):
        if s > 0:
            for _ in range(updates_per_sample):
                t = data.time
                for k, gait in enumerate(gaits):
                    if gait is not None:
                        command = gait.command(t + TIME_EPS)
                        targets[k], speeds[k] = command.targets, command.speed
                angles = data.qpos[qpos].reshape(n, 2)
                goal = np.clip(bandwidth * (targets - angles), -speeds[:, None], speeds[:, None])
                data.ctrl[:] = goal.ravel()
                mujoco.mj_step(model, data, nstep=settings.steps_per_update)
                a, b = owner[data.contact.geom1], owner[data.contact.geom2]
                robots = (a >= 0) & (b >= 0) & (a != b)
                if robots.any():
                    seen[a[robots], b[robots]] = seen[b[robots], a[robots]] = True
                    peak_overlap = max(peak_overlap, -float(data.contact.dist[robots].min()))
        quats = data.qpos[free[:, None] + [4, 5, 6, 3]]      # MuJoCo keeps w, x, y, z; Bullet's order is x, y, z, w
        heading, tilt = body_headings_and_tilts(quats)
        times[s] = data.time
        poses[s, :, :2] = data.qpos[free[:, None] + [0, 1]]
        poses[s, :, 2] = heading
        arms[s] = data.qpos[qpos].reshape(n, 2)
        touching[s], seen[:] = seen, False
        taken = s + 1
        peak_tilt = max(peak_tilt, float(tilt.max()))
        if not np.all(np.isfinite(poses[s])):
            meta['trouble'] = f'non-finite state at t = {data.time:.3f} s (MuJoCo)'
            break
        if peak_tilt > config.physics.max_tilt:
            k = int(np.argmax(tilt))
            meta['trouble'] = (f'robot {k} tipped {math.degrees(float(tilt[k])):.1f} deg at t = {data.time:.3f} s '
                               f'(MuJoCo)')
            break
    meta['peak_tilt_deg'] = math.degrees(peak_tilt)
    meta['peak_overlap_mm'] = peak_overlap * 1000.0
    return Recording(times[:taken], poses[:taken], arms[:taken], np.zeros((taken, n, len(FSR_FACES))),
                     touching[:taken], config.robot.body_length, meta)
