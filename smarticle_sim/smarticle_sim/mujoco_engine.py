"""The same scene in a second physics engine (MuJoCo): a cross-check of what Bullet's contact model does.

PyBullet is the simulation of this project. This module steps a ``Scene`` in MuJoCo instead, to tell
what the robots, their gait and their start do from what Bullet's rigid contacts do (in Bullet
two robots in phase never glide; is that Bullet's?). ``MujocoPhysics`` implements the engine interface
(``engine.Engine``), so the one ``Runner`` steps it with the same controllers (gait cores, their noise, the
FSR feedback, contact watchers) and trouble checks as Bullet's ``Physics``, and ``batch.run_trial`` records
it as the same ``Recording``: the glider analysis and the experiment reports read it unchanged.

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

FSR forces, noise and trouble checks are Bullet's where the engine allows (``MujocoPhysics``); the gait's
commands go out at control ticks, as in Bullet. ``Diagnostics.mass_model`` 'authors' gives the links Bullet's
masses and inertias of the authors' model. Not modelled here: a held robot.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from smarticle_common.poses import body_headings_and_tilts
from smarticle_common.runs import Recording
from smarticle_common.topics import FSR_FACES

from .engine import EngineFactory, PhysicsState, robot_index
from .errors import SimError
from .noise import FrictionField
from .diagnostics import arm_masses, authors_inertias
from .scenes import Scene
from .settings import SimConfig
from .trouble import check_penetration, check_state

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


def build_model(config: SimConfig, scene: Scene, settings: MujocoSettings,
                plate_pairs: bool = False) -> mujoco.MjModel:
    """The MJCF model of ``scene``'s robots on the plate (body ``robot{k}``, hinges ``robot{k}_arm{j}``).

    With ``plate_pairs`` (and always with 'hertz' contact) the plate's contacts are explicit pairs, one per
    robot geom (``robot{k}_body_plate``, ...), whose friction can be set per robot (the friction field).
    """
    import mujoco   # here, so that the settings can be imported (e.g. to check a spec) without the engine

    spec, ph = config.robot, config.physics
    diag = config.diagnostics
    diag.check_engine('mujoco')
    masses = arm_masses(spec, diag.mass_model)
    # the authors' model (``Diagnostics.mass_model``): Bullet's arm masses and every link's inertia, given
    # explicitly (an <inertial> element overrides the inertia MuJoCo takes from the geoms)
    inertias = authors_inertias(spec) if diag.mass_model == 'authors' else None
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
    plate_pairs = plate_pairs or hertz
    plate_class = ' contype="2" conaffinity="2"' if plate_pairs else ''
    for k, robot in enumerate(scene.robots):
        yaw = robot.heading - math.pi / 2.0          # the body's x axis from its normal (as in Physics)
        arms = []
        for j, (sign, axis) in enumerate(((-1.0, -1.0), (1.0, 1.0))):   # Physics: link axes -z and +z
            inertial = '' if inertias is None else \
                f'<inertial pos="{sign * half_l!r} 0 0" mass="{masses[j]!r}" diaginertia="{_triple(inertias[j + 1])}"/>'
            arms.append(
                f'<body name="robot{k}_link{j}" pos="{sign * w / 2.0!r} 0 {arm_z!r}">{inertial}'
                f'<joint name="robot{k}_arm{j}" type="hinge" axis="0 0 {axis!r}"/>'
                f'<geom name="robot{k}_arm{j}_geom" type="box" pos="{sign * half_l!r} 0 0" '
                f'size="{half_l!r} {half_t!r} {half_h!r}" mass="{masses[j]!r}" '
                f'friction="{ph.friction_robot_robot!r} 0 0"{robot_geom}/></body>')
            actuators.append(f'<velocity joint="robot{k}_arm{j}" kv="{settings.servo_kv!r}" '
                             f'forcelimited="true" forcerange="{-spec.servo_torque!r} {spec.servo_torque!r}"/>')
        body_inertial = '' if inertias is None else \
            f'<inertial pos="0 0 0" mass="{spec.body_mass!r}" diaginertia="{_triple(inertias[0])}"/>'
        bodies.append(
            f'<body name="robot{k}" pos="{robot.x!r} {robot.y!r} {h / 2.0!r}" euler="0 0 {yaw!r}">{body_inertial}'
            f'<freejoint/>'
            f'<geom name="robot{k}_body" type="box" size="{w / 2.0!r} {d / 2.0!r} {h / 2.0!r}" '
            f'mass="{spec.body_mass!r}" friction="{ph.friction_robot_robot!r} 0 0"{robot_geom}/>'
            f'{"".join(arms)}</body>')
        contact_items.append(f'<exclude body1="robot{k}_link0" body2="robot{k}_link1"/>')
        if plate_pairs:   # the plate's contacts, MuJoCo's own: explicit pairs (the plate is out of the robots' filter)
            plate_friction = max(ph.friction_body_plate, ph.friction_robot_robot)   # MuJoCo's rule, as without
            for geom in (f'robot{k}_body', f'robot{k}_arm0_geom', f'robot{k}_arm1_geom'):
                contact_items.append(f'<pair name="{geom}_plate" geom1="plate" geom2="{geom}" condim="3" '
                                     f'margin="0" gap="0" friction="{plate_friction!r} {plate_friction!r} 0 0 0" '
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


def _triple(values: tuple[float, float, float]) -> str:
    """Three numbers for an MJCF attribute, exactly (repr)."""
    return ' '.join(repr(float(v)) for v in values)


def hertz_contact_forces(model: mujoco.MjModel, data: mujoco.MjData, law: HertzLaw, owner: np.ndarray,
                         normals: np.ndarray | None = None) -> int:
    """Set ``data.qfrc_applied`` to ``law``'s forces at every contact point between two robots now.

    Call between ``mj_step1`` and ``mj_step2``: the contacts are the present state's (each robot-robot point
    with its overlap, left out of MuJoCo's solver by the gap), the velocities too. A point's normal runs from
    geom 1 to geom 2; geom 2's body gets the force, geom 1's the opposite, both at the point. The effective
    mass is the two links' (as Chrono takes its two bodies'). Returns the number of points that pushed;
    ``normals`` (at least ``data.ncon`` long), if given, gets each point's normal force (0 where none).
    """
    import mujoco

    data.qfrc_applied[:] = 0.0
    if normals is not None:
        normals[:data.ncon] = 0.0
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
        if normals is not None:
            normals[i] = f_normal
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


class MujocoPhysics:
    """N smarticles on a plate in MuJoCo: the MuJoCo implementation of ``engine.Engine``.

    A step is one servo update (``MujocoSettings.servo_update``, ``steps_per_update`` MuJoCo steps): before
    it, each arm's velocity actuator gets its speed goal from the last command (``send``) and the arm's angle
    now (the servo of the module docstring). The control tick (``PhysicsConfig.control_tick``) must be a
    whole number of servo updates; the FSR reading averages ``fsr_window`` over servo updates.

    FSR forces follow ``physics.Physics.fsr``: every contact on an arm geom counts its normal force (MuJoCo's
    solver force of the last step, ``mj_contactForce``, or the Hertz law's with 'hertz' contact) toward the
    arm's front face when it pushes the arm toward -front (the link's -y), else toward its back face, times
    the cosine between the push and the face normal. Noise: the gait's clock rates and servo delays are the
    runner's (``GaitController``); the friction field sets the friction of each body's plate contact
    (an explicit pair) once per tick. Trouble checks are Bullet's (``trouble.check_state`` and
    ``check_penetration`` on the deepest overlap of any contact).
    """

    def __init__(self, config: SimConfig, scene: Scene, settings: MujocoSettings | None = None) -> None:
        import mujoco

        scene.validate(config.robot, config.physics.plate_size)
        self.config = config
        self.scene = scene
        self.settings = settings = settings or MujocoSettings()
        ph = config.physics
        self._physics = ph
        ratio = ph.control_tick / settings.servo_update
        if abs(ratio - round(ratio)) > 1e-6 or round(ratio) < 1:
            raise SimError(f'the control tick {ph.control_tick:g} s is not a whole number of servo updates '
                           f'({settings.servo_update:g} s)')
        self._steps_per_tick = round(ratio)
        self._fsr_steps = max(1, round(ph.fsr_window / settings.servo_update))
        noise = config.noise
        #: The plate's friction field (``NoiseConfig.friction_sd`` > 0), or None: uniform friction.
        self.friction_field: FrictionField | None = None
        if noise.friction_sd > 0.0:
            self.friction_field = FrictionField(noise.friction_sd, noise.friction_length, ph.plate_size,
                                                noise.trial_seed(scene.seed))
        self._mujoco = mujoco
        self._model = model = build_model(config, scene, settings, plate_pairs=self.friction_field is not None)
        self._data = data = mujoco.MjData(model)
        n = len(scene.robots)
        self._n = n
        arm_joints = [model.joint(f'robot{k}_arm{j}').id for k in range(n) for j in (0, 1)]
        self._arm_qpos = np.array([model.jnt_qposadr[i] for i in arm_joints])
        self._arm_qvel = np.array([model.jnt_dofadr[i] for i in arm_joints])
        free = [model.body_jntadr[model.body(f'robot{k}').id] for k in range(n)]
        self._free_qpos = np.array([model.jnt_qposadr[i] for i in free])
        self._free_qvel = np.array([model.jnt_dofadr[i] for i in free])
        self._link_body = np.array([[model.body(f'robot{k}_link{j}').id for j in (0, 1)] for k in range(n)])
        self._owner = np.full(model.ngeom, -1)      # robot of each geom (-1: the plate)
        self._arm_of = np.full(model.ngeom, -1)     # arm (0, 1) of each geom (-1: a body or the plate)
        for k in range(n):
            for j in (0, 1):
                self._arm_of[model.geom(f'robot{k}_arm{j}_geom').id] = j
                self._owner[model.geom(f'robot{k}_arm{j}_geom').id] = k
            self._owner[model.geom(f'robot{k}_body').id] = k
        for k, robot in enumerate(scene.robots):
            data.qpos[self._arm_qpos[2 * k]], data.qpos[self._arm_qpos[2 * k + 1]] = robot.alpha1, robot.alpha2
        mujoco.mj_forward(model, data)
        self._law = HertzLaw.of(settings, ph.friction_robot_robot) if settings.robot_contact == 'hertz' else None
        self._normals = np.zeros(0)   # the Hertz law's normal force of each contact point of the last step
        self._bandwidth = ph.servo_gain() / ph.time_step   # Bullet's speed goal per radian
        self._targets = np.array([[r.alpha1, r.alpha2] for r in scene.robots], dtype=float).reshape(n, 2)
        self._speeds = np.full(n, config.robot.servo_speed)   # as Bullet: hold the start at the servo's speed
        self._step_count = 0
        self._state: PhysicsState | None = None
        self._deep_checks = 0
        self.peak_tilt = 0.0
        self.peak_overlap = 0.0
        self._friction_factor = np.full(n, np.nan)
        if self.friction_field is not None:
            self._plate_pair = np.array([model.pair(f'robot{k}_body_plate').id for k in range(n)])
            self._plate_friction = float(model.pair_friction[self._plate_pair[0], 0]) if n else 0.0
            self.update_plate_friction()

    # ----------------------------------------------------------------- properties
    @property
    def model(self) -> mujoco.MjModel:
        """The MuJoCo model (for inspection; do not step it directly)."""
        return self._model

    @property
    def data(self) -> mujoco.MjData:
        """The MuJoCo data (for inspection; do not step it directly)."""
        return self._data

    @property
    def n_robots(self) -> int:
        """Number of robots."""
        return self._n

    @property
    def time(self) -> float:
        """Simulated time since the world was built (s): servo updates taken times their interval."""
        return self._step_count * self.settings.servo_update

    @property
    def step_count(self) -> int:
        """Servo updates taken."""
        return self._step_count

    @property
    def steps_per_tick(self) -> int:
        """Servo updates per control tick."""
        return self._steps_per_tick

    @property
    def fsr_steps(self) -> int:
        """Servo updates the FSR reading averages over (``PhysicsConfig.fsr_window``, at least 1)."""
        return self._fsr_steps

    def ticks_for(self, seconds: float) -> int:
        """Number of control ticks in ``seconds`` of sim time (rounded)."""
        return round(seconds / self._physics.control_tick)

    def run_meta(self) -> dict[str, Any]:
        """The engine, its version and settings, for a recording's meta."""
        return {'engine': 'mujoco', 'mujoco_version': self._mujoco.__version__, 'mujoco': asdict(self.settings)}

    # ----------------------------------------------------------------- commands and stepping
    def command(self, robot: int, targets: tuple[float, float], speed: float | None = None) -> None:
        """Command ``robot``'s servos: arm targets (rad) and speed limit (rad/s, capped at the servo's)."""
        k = self.check_robot(robot)
        t1, t2 = float(targets[0]), float(targets[1])
        spd = self.config.robot.servo_speed if speed is None else float(speed)
        if not (math.isfinite(t1) and math.isfinite(t2)):
            raise SimError(f'robot {k}: joint targets must be finite, got {targets!r}')
        if not (math.isfinite(spd) and spd > 0.0):
            raise SimError(f'robot {k}: speed limit must be > 0 rad/s, got {speed!r}')
        self.send(k, (t1, t2), spd)

    def send(self, k: int, targets: tuple[float, float], speed: float) -> None:
        """Set robot ``k``'s servo targets and speed limit (unchecked: for controllers)."""
        self._targets[k] = targets
        self._speeds[k] = min(speed, self.config.robot.servo_speed)

    def step(self, n: int = 1) -> None:
        """Advance ``n`` servo updates."""
        mujoco, model, data = self._mujoco, self._model, self._data
        law, substeps = self._law, self.settings.steps_per_update
        qpos, bandwidth, speeds = self._arm_qpos, self._bandwidth, self._speeds[:, None]
        for _ in range(n):
            angles = data.qpos[qpos].reshape(self._n, 2)
            data.ctrl[:] = np.clip(bandwidth * (self._targets - angles), -speeds, speeds).ravel()
            if law is None:
                mujoco.mj_step(model, data, nstep=substeps)
            else:
                for _ in range(substeps):
                    mujoco.mj_step1(model, data)     # contacts and velocities of the state now
                    if len(self._normals) < data.ncon:
                        self._normals = np.zeros(max(data.ncon, 2 * len(self._normals)))
                    hertz_contact_forces(model, data, law, self._owner, self._normals)
                    mujoco.mj_step2(model, data)
        self._step_count += n
        self._state = None

    # ----------------------------------------------------------------- ground truth
    def state(self) -> PhysicsState:
        """Ground truth of all robots now (cached until the next step)."""
        if self._state is None:
            data, free, dof = self._data, self._free_qpos, self._free_qvel
            positions = data.qpos[free[:, None] + [0, 1, 2]].reshape(self._n, 3)
            quats = data.qpos[free[:, None] + [4, 5, 6, 3]].reshape(self._n, 4)   # w, x, y, z -> Bullet's x, y, z, w
            heading, tilt = body_headings_and_tilts(quats)
            poses = np.column_stack([positions[:, 0], positions[:, 1], heading])
            speed = np.linalg.norm(data.qvel[dof[:, None] + [0, 1, 2]].reshape(self._n, 3), axis=1)
            self._state = PhysicsState(self.time, poses, positions, tilt, speed,
                                       data.qpos[self._arm_qpos].reshape(self._n, 2).copy(),
                                       data.qvel[self._arm_qvel].reshape(self._n, 2).copy())
        return self._state

    def poses(self) -> np.ndarray:
        """(N, 3) x, y (m) and heading of the body normal (rad) of every robot."""
        return self.state().poses

    def arm_angles(self) -> np.ndarray:
        """(N, 2) arm angles alpha1, alpha2 (rad)."""
        return self.state().arm_angles

    def arm_velocities(self) -> np.ndarray:
        """(N, 2) arm angular velocities (rad/s)."""
        return self.state().arm_velocities

    def body_xy(self) -> np.ndarray:
        """(N, 2) body centre x, y (m)."""
        return self.state().positions[:, :2]

    # ----------------------------------------------------------------- plate friction
    def update_plate_friction(self) -> int:
        """Set each body's plate-contact friction from the friction field at its position (when it differs
        from the applied factor by more than ``NoiseConfig.friction_tolerance``); return the bodies changed."""
        field = self.friction_field
        if field is None:
            return 0
        factor = field.factor(self.body_xy())
        changed = np.flatnonzero(~(np.abs(factor - self._friction_factor)
                                   <= self.config.noise.friction_tolerance))
        for k in changed:
            self._model.pair_friction[self._plate_pair[k], :2] = self._plate_friction * factor[k]
            self._friction_factor[k] = factor[k]
        return int(changed.size)

    # ----------------------------------------------------------------- contacts and FSR
    def _robot_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Indices of the contact points between two robots now, and the robots of their geoms 1 and 2."""
        contact = self._data.contact
        a, b = self._owner[contact.geom1], self._owner[contact.geom2]
        robots = (a >= 0) & (b >= 0) & (a != b)
        if self._law is not None:   # the gap keeps robot-robot points that do not touch in the list
            robots &= contact.dist < 0.0
        points = np.flatnonzero(robots)
        return points, a[points], b[points]

    def fsr(self, robots: Sequence[int] | None = None) -> np.ndarray:
        """(len(robots), 4) normal force (N) on each FSR face, in the order of ``FSR_FACES`` (as Bullet's)."""
        return self.fsr_of(self.robot_list(robots))

    def fsr_of(self, ks: list[int]) -> np.ndarray:
        """``fsr`` of robots ``ks`` already checked (``FsrReading`` calls it every servo update)."""
        out = np.zeros((len(ks), len(FSR_FACES)))
        data, model = self._data, self._model
        if data.ncon == 0:
            return out
        row_of = {k: row for row, k in enumerate(ks)}
        contact = data.contact
        arm1, arm2 = self._arm_of[contact.geom1], self._arm_of[contact.geom2]
        wrench = np.zeros(6)
        for i in np.flatnonzero((arm1 >= 0) | (arm2 >= 0)):
            g1, g2 = int(contact.geom1[i]), int(contact.geom2[i])
            sides = [(g, sign) for g, sign in ((g1, -1.0), (g2, 1.0))
                     if self._arm_of[g] >= 0 and int(self._owner[g]) in row_of]
            if not sides:
                continue
            force = 0.0
            if contact.efc_address[i] >= 0:
                self._mujoco.mj_contactForce(model, data, i, wrench)
                force = float(wrench[0])
            elif self._law is not None and i < len(self._normals):
                force = float(self._normals[i])
            if force <= 0.0:
                continue
            normal = contact.frame[i, :3]    # from geom 1 to geom 2: geom 2 is pushed along it, geom 1 against it
            for g, sign in sides:
                k, j = int(self._owner[g]), int(self._arm_of[g])
                front = data.xmat[self._link_body[k, j]].reshape(3, 3)[:, 1]
                along = force * sign * float(normal @ front)
                if along < 0.0:
                    out[row_of[k], 2 * j] -= along      # pushed toward -front: contact on the front face
                else:
                    out[row_of[k], 2 * j + 1] += along
        return out

    def robot_contacts(self) -> np.ndarray:
        """(N, N) symmetric bool matrix: True where two robots touch now (any links)."""
        out = np.zeros((self._n, self._n), dtype=bool)
        _, a, b = self._robot_points()
        out[a, b] = out[b, a] = True
        return out

    def touching(self, max_distance: float = 0.0) -> set[tuple[int, int]]:
        """Pairs (i, j), i < j, of robots with a contact point at distance <= ``max_distance`` (m) now."""
        points, a, b = self._robot_points()
        near = self._data.contact.dist[points] <= max_distance
        return {(int(min(i, j)), int(max(i, j))) for i, j in zip(a[near], b[near], strict=True)}

    def max_penetration(self) -> tuple[int, float]:
        """(robot, depth in m) of the deepest contact overlap now; (-1, 0.0) without contacts."""
        contact = self._data.contact
        if self._data.ncon == 0:
            return -1, 0.0
        depth = -contact.dist
        if not np.all(np.isfinite(depth)):
            i = int(np.flatnonzero(~np.isfinite(depth))[0])
        else:
            i = int(np.argmax(depth))
            if depth[i] <= 0.0:
                return -1, 0.0
        a, b = int(self._owner[contact.geom1[i]]), int(self._owner[contact.geom2[i]])
        return (a if a >= 0 else b), float(depth[i])

    def check_trouble(self) -> None:
        """Raise SimTrouble if a robot is not finite, off the plate, flipped, too fast or tunnelling (Bullet's
        checks and limits, ``PhysicsConfig``)."""
        s = self.state()
        if s.tilt.size and np.isfinite(s.tilt).all():
            self.peak_tilt = max(self.peak_tilt, float(s.tilt.max()))
        check_state(s.time, s.positions, s.tilt, s.speed, s.arm_angles, self._physics, self.config.robot.body_height)
        robot, depth = self.max_penetration()
        if depth == depth:
            self.peak_overlap = max(self.peak_overlap, depth)
        self._deep_checks = check_penetration(s.time, robot, depth, self._physics, self._deep_checks)

    # ----------------------------------------------------------------- housekeeping
    def check_robot(self, robot: int) -> int:
        """Return ``robot`` as an index or raise SceneError."""
        return robot_index(robot, self._n)

    def robot_list(self, robots: Sequence[int] | None) -> list[int]:
        """All robots, or the given ones checked."""
        return list(range(self._n)) if robots is None else [robot_index(k, self._n) for k in robots]

    def close(self) -> None:
        """Nothing to release (the model and data go with the object); idempotent, as ``Physics.close``."""
        self._state = None

    def __enter__(self) -> MujocoPhysics:
        """Context manager, as ``Physics``'s."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Close."""
        self.close()


def mujoco_engine(settings: MujocoSettings | None = None) -> EngineFactory:
    """An engine factory (``Runner.with_gaits``, ``batch.run_trial``) of MuJoCo worlds with ``settings``."""
    def build(config: SimConfig, scene: Scene) -> MujocoPhysics:
        return MujocoPhysics(config, scene, settings)
    return build


def run_mujoco(config: SimConfig, scene: Scene, periods: float, sample_every: int,
               settings: MujocoSettings | None = None) -> Recording:
    """Run ``scene`` for ``periods`` gait periods in MuJoCo from a synchronised start at t = 0: ``batch.run_trial``
    through the one ``Runner`` with a ``MujocoPhysics``.

    Samples every ``sample_every`` control ticks; ``contacts[s]`` is True for a pair of robots that touched at
    any servo update since the sample before (``run_trial``'s ``contacts_between_samples``).
    """
    from .batch import run_trial

    return run_trial(config, scene, periods, sample_every, record_contacts=True, engine=mujoco_engine(settings),
                     contacts_between_samples=True)
