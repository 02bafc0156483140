"""The same scene in a second physics engine (MuJoCo): a cross-check of what Bullet's contact model does.

PyBullet is the simulation of this project. This module steps a ``Scene`` in MuJoCo instead, to tell
what the robots, their gait and their start do from what Bullet's rigid contacts do (in Bullet
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

``robot_contact`` 'hertz' replaces MuJoCo's own contact between robots (the plate's stays MuJoCo's) with the
authors' Chrono smooth contact (``ChSystemSMC``'s Hertz model, computed here before every step,
``hertz_contact_forces``): MuJoCo still finds every robot-robot contact point and its overlap, but leaves it
out of its solver, and each point gets a normal force k_n delta - g_n v_n and a tangential force
k_t v_t dt + g_t v_t capped at mu times the normal one, with Chrono's Hertz stiffness and damping from the
Young's modulus, Poisson ratio, restitution and effective curvature radius set here (the authors' values and
Chrono's default radius) and the two links' masses.

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


#: ``MujocoSettings.robot_contact`` values.
ROBOT_CONTACTS = ('soft', 'hertz')

#: Chrono's slip velocity threshold (m/s): a contact sliding slower gets no tangential force.
HERTZ_SLIP_THRESHOLD = 1e-4


@dataclass(frozen=True)
class HertzLaw:
    """Chrono's Hertz smooth-contact law for one material pair (``ChSystemSMC``, Hertz model, the tangential
    displacement of one step): the effective moduli and damping factor of two bodies of the same material."""

    youngs: float          # E_eff = 1 / (2 (1 - nu^2) / E), Pa
    shear: float           # G_eff = 1 / (4 (2 - nu) (1 + nu) / E), Pa
    beta: float            # ln(cr) / sqrt(ln(cr)^2 + pi^2), <= 0
    radius: float          # m
    friction: float
    time_step: float

    @classmethod
    def of(cls, settings: MujocoSettings, friction: float) -> HertzLaw:
        """The law of ``settings``' material with Coulomb ``friction``."""
        e, nu = settings.hertz_youngs_modulus, settings.hertz_poisson
        log_cr = math.log(max(settings.hertz_restitution, 1e-6))
        return cls(youngs=e / (2.0 * (1.0 - nu * nu)), shear=e / (4.0 * (2.0 - nu) * (1.0 + nu)),
                   beta=log_cr / math.sqrt(log_cr * log_cr + math.pi * math.pi), radius=settings.hertz_radius,
                   friction=friction, time_step=settings.time_step)

    def forces(self, overlap: float, v_normal: float, v_tangent: float, mass: float) -> tuple[float, float]:
        """(normal, tangential) force magnitudes (N) of a contact point with ``overlap`` (m) > 0, separating at
        ``v_normal`` (m/s, negative while approaching), sliding at ``v_tangent`` >= 0 (m/s), between bodies
        of effective mass ``mass`` (kg). The tangential force opposes the sliding; 0 below Chrono's slip
        threshold and when the normal force would pull."""
        root = math.sqrt(self.radius * overlap)
        sn, st = 2.0 * self.youngs * root, 8.0 * self.shear * root
        damping = -2.0 * math.sqrt(5.0 / 6.0) * self.beta
        normal = (2.0 / 3.0) * sn * overlap - damping * math.sqrt(sn * mass) * v_normal
        if normal <= 0.0:
            return 0.0, 0.0
        if v_tangent < HERTZ_SLIP_THRESHOLD:
            return normal, 0.0
        tangential = st * v_tangent * self.time_step + damping * math.sqrt(st * mass) * v_tangent
        return normal, min(tangential, self.friction * normal)


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
    #: Robot-robot contact: 'soft' (MuJoCo's spring-damper above) or 'hertz' (the authors' Chrono smooth
    #: contact, ``hertz_contact_forces``, with the four values below and ``friction_robot_robot``).
    robot_contact: str = 'soft'
    hertz_youngs_modulus: float = 2.0e7  # Pa, the authors' material (E)
    hertz_poisson: float = 0.3           # the authors' material (nu)
    hertz_restitution: float = 0.85      # the authors' value (0.85-0.9)
    hertz_radius: float = 0.1            # m, Chrono's default effective curvature radius of a contact

    def __post_init__(self) -> None:
        for name in ('time_step', 'contact_timeconst', 'contact_dampratio', 'servo_kv', 'servo_update',
                     'hertz_youngs_modulus', 'hertz_restitution', 'hertz_radius'):
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

        if self.robot_contact not in ROBOT_CONTACTS:
            raise SimError(f'MujocoSettings.robot_contact must be one of {", ".join(ROBOT_CONTACTS)}, '
                           f'got {self.robot_contact!r}')
        if not (isinstance(self.hertz_poisson, (int, float)) and 0.0 <= self.hertz_poisson < 0.5):
            raise SimError(f'MujocoSettings.hertz_poisson must be in [0, 0.5), got {self.hertz_poisson!r}')
        if self.hertz_restitution > 1.0:
            raise SimError(f'MujocoSettings.hertz_restitution must be in (0, 1], got {self.hertz_restitution!r}')
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
    if any(robot.held for robot in scene.robots):
        raise SimError('the MuJoCo engine holds no robot in place (RobotPlacement.held); run a held robot in '
                       'Bullet or Chrono')
    w, d, h = spec.body_width, spec.body_depth, spec.body_height
    half_l, half_t, half_h = spec.arm_length / 2.0, spec.arm_thickness / 2.0, spec.arm_height / 2.0
    arm_z = spec.arm_clearance + spec.arm_height / 2.0 - h / 2.0
    bodies, contact_items, actuators = [], [], []
    hertz = settings.robot_contact == 'hertz'
    # 'hertz': robot-robot contacts are found (overlap < 0 margin) but all inside the gap, so MuJoCo's solver
    # leaves them to ``hertz_contact_forces``; the plate is in another collision class (explicit pairs)
    robot_geom = ' contype="1" conaffinity="1" margin="0" gap="1"' if hertz else ''
    plate_class = ' contype="2" conaffinity="2"' if hertz else ''
    for k, robot in enumerate(scene.robots):
        yaw = robot.heading - math.pi / 2.0          # the body's x axis from its normal (as in Physics)
        arms = []
        for j, (sign, axis) in enumerate(((-1.0, -1.0), (1.0, 1.0))):   # Physics: link axes -z and +z
            arms.append(
                f'<body name="robot{k}_link{j}" pos="{sign * w / 2.0!r} 0 {arm_z!r}">'
                f'<joint name="robot{k}_arm{j}" type="hinge" axis="0 0 {axis!r}"/>'
                f'<geom name="robot{k}_arm{j}_geom" type="box" pos="{sign * half_l!r} 0 0" '
                f'size="{half_l!r} {half_t!r} {half_h!r}" mass="{spec.arm_mass!r}" '
                f'friction="{ph.friction_robot_robot!r} 0 0"{robot_geom}/></body>')
            actuators.append(f'<velocity joint="robot{k}_arm{j}" kv="{settings.servo_kv!r}" '
                             f'forcelimited="true" forcerange="{-spec.servo_torque!r} {spec.servo_torque!r}"/>')
        bodies.append(
            f'<body name="robot{k}" pos="{robot.x!r} {robot.y!r} {h / 2.0!r}" euler="0 0 {yaw!r}"><freejoint/>'
            f'<geom name="robot{k}_body" type="box" size="{w / 2.0!r} {d / 2.0!r} {h / 2.0!r}" '
            f'mass="{spec.body_mass!r}" friction="{ph.friction_robot_robot!r} 0 0"{robot_geom}/>'
            f'{"".join(arms)}</body>')
        contact_items.append(f'<exclude body1="robot{k}_link0" body2="robot{k}_link1"/>')
        if hertz:   # the plate's contacts, MuJoCo's own: explicit pairs (the plate is out of the robots' filter)
            plate_friction = max(ph.friction_body_plate, ph.friction_robot_robot)   # MuJoCo's rule, as without
            for geom in (f'robot{k}_body', f'robot{k}_arm0_geom', f'robot{k}_arm1_geom'):
                contact_items.append(f'<pair geom1="plate" geom2="{geom}" condim="3" margin="0" gap="0" '
                                f'friction="{plate_friction!r} {plate_friction!r} 0 0 0" '
                                f'solref="{settings.contact_timeconst!r} {settings.contact_dampratio!r}"/>')
    half_plate = ph.plate_size / 2.0
    xml = (f'<mujoco><compiler angle="radian"/>'
           f'<option timestep="{settings.time_step!r}" gravity="0 0 {-ph.gravity!r}" cone="{settings.friction_cone}" '
           f'integrator="implicitfast" noslip_iterations="{settings.noslip_iterations}"/>'
           f'<default><geom condim="3" solref="{settings.contact_timeconst!r} {settings.contact_dampratio!r}"/>'
           f'</default><worldbody>'
           f'<geom name="plate" type="plane" size="{half_plate!r} {half_plate!r} 0.1" '
           f'friction="{ph.friction_body_plate!r} 0 0"{plate_class}/>'
           f'{"".join(bodies)}</worldbody><contact>{"".join(contact_items)}</contact>'
           f'<actuator>{"".join(actuators)}</actuator></mujoco>')
    return mujoco.MjModel.from_xml_string(xml)


def hertz_contact_forces(model: mujoco.MjModel, data: mujoco.MjData, law: HertzLaw, owner: np.ndarray) -> int:
    """Set ``data.qfrc_applied`` to ``law``'s forces at every contact point between two robots now.

    Call between ``mj_step1`` and ``mj_step2``: the contacts are the present state's (each robot-robot point
    with its overlap, left out of MuJoCo's solver by the gap), the velocities too. A point's normal runs from
    geom 1 to geom 2; geom 2's body gets the force, geom 1's the opposite, both at the point. The effective
    mass is the two links' (as Chrono takes its two bodies'). Returns the number of points that pushed.
    """
    import mujoco

    data.qfrc_applied[:] = 0.0
    pushed = 0
    contact = data.contact
    a, b = owner[contact.geom1], owner[contact.geom2]
    for i in np.flatnonzero((contact.dist < 0.0) & (a >= 0) & (b >= 0) & (a != b)):
        g1, g2 = contact.geom1[i], contact.geom2[i]
        b1, b2 = model.geom_bodyid[g1], model.geom_bodyid[g2]
        point = contact.pos[i]
        normal = contact.frame[i, :3]
        v1 = _point_velocity(model, data, b1, point)
        v2 = _point_velocity(model, data, b2, point)
        relative = v2 - v1
        v_normal = float(relative @ normal)
        tangent = relative - v_normal * normal
        v_tangent = float(np.linalg.norm(tangent))
        m1, m2 = model.body_mass[b1], model.body_mass[b2]
        f_normal, f_tangent = law.forces(-float(contact.dist[i]), v_normal, v_tangent, m1 * m2 / (m1 + m2))
        if f_normal <= 0.0:
            continue
        force = f_normal * normal
        if f_tangent > 0.0:
            force = force - (f_tangent / v_tangent) * tangent
        mujoco.mj_applyFT(model, data, force, np.zeros(3), point, b2, data.qfrc_applied)
        mujoco.mj_applyFT(model, data, -force, np.zeros(3), point, b1, data.qfrc_applied)
        pushed += 1
    return pushed


def _point_velocity(model: mujoco.MjModel, data: mujoco.MjData, body: int, point: np.ndarray) -> np.ndarray:
    """World velocity of the point of ``body`` at ``point`` (``cvel`` is [angular, linear] at the subtree's
    centre of mass of the body's root)."""
    spatial = data.cvel[body]
    return spatial[3:] + np.cross(spatial[:3], point - data.subtree_com[model.body_rootid[body]])


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
    law = HertzLaw.of(settings, config.physics.friction_robot_robot) if settings.robot_contact == 'hertz' else None
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
                if law is None:
                    mujoco.mj_step(model, data, nstep=settings.steps_per_update)
                else:
                    for _ in range(settings.steps_per_update):
                        mujoco.mj_step1(model, data)     # contacts and velocities of the state now
                        hertz_contact_forces(model, data, law, owner)
                        mujoco.mj_step2(model, data)
                a, b = owner[data.contact.geom1], owner[data.contact.geom2]
                robots = (a >= 0) & (b >= 0) & (a != b)
                if law is not None:   # the gap keeps robot-robot points that do not touch in the list
                    robots &= data.contact.dist < 0.0
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
