"""The physics of a run: a PyBullet world of smarticles on a plate (bodies, joints, contacts, sensors).

``Physics`` knows nothing of gaits or feedback: it takes servo commands, steps and reports ground truth,
FSR forces, contacts and trouble. What acts on the robots (gait cores, the feedback controller, a
bridge's external commands) and the loop that steps it live in ``runner.py``.

Each Physics owns its PyBullet client (``BulletClient(DIRECT)``), never the implicit global one, so
several worlds can live in one process. A robot is one multibody: the body box as the base, resting on
the plate, and two arm boxes on revolute joints at the body's ends. Joint 0 is arm 1 (at body -x, axis
-z) and joint 1 is arm 2 (at +x, axis +z), so each joint position *is* the gait's alpha_i. Arms hang
``arm_clearance`` above the plate and their collisions with the plate are filtered out.

With ``NoiseConfig.friction_sd`` > 0 the physics owns the plate's friction field (``noise.FrictionField``)
and sets each body's friction from it on ``update_plate_friction`` (the runner calls it once per tick).

Per-tick Python work is kept small: motor commands are sent only when a target or speed changes, state
is read with one pass of batched calls and cached until the next step, and FSR forces and contacts are
computed only when asked for.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from smarticle_common.poses import body_headings_and_tilts
from smarticle_common.topics import FSR_FACES

from smarticle_sim.quiet import BulletClient, pybullet, silenced_output

from . import diagnostics
from .diagnostics import arm_masses, body_inertia_scales
from .settings import PhysicsConfig, SimConfig
from .engine import FsrReading as FsrReading   # its home was here: ``physics.FsrReading`` still names it
from .engine import PhysicsState, robot_index
from .errors import SimError
from .noise import FrictionField
from .scenes import RobotPlacement, RobotState, Scene
from .trouble import check_penetration, check_state

#: Joint index of arm 1 and arm 2 (also their link indices); the body is link -1.
ARM_JOINTS: tuple[int, int] = (0, 1)
#: With soft contacts (``PhysicsConfig.contact_stiffness``) the plate's stiffness is this many times a robot
#: link's: in series with the link's, the body-plate spring is the link's to 1 part in a million.
SOFT_PLATE_STIFFNESS_FACTOR = 1.0e6


class Physics:
    """N smarticles on a plate in their own PyBullet client; step it, command its servos, read ground truth.

    The Bullet implementation of ``engine.Engine``: a step is one ``PhysicsConfig.time_step``.
    """

    def __init__(self, config: SimConfig, scene: Scene) -> None:
        scene.validate(config.robot, config.physics.plate_size)
        self.config = config
        self.scene = scene
        self._physics = config.physics
        self._steps_per_tick = config.physics.steps_per_tick
        self._client = quiet_client()
        self._step_count = 0
        self._state: PhysicsState | None = None
        self._last_check: tuple[float, np.ndarray | None] = (0.0, None)
        self._deep_checks = 0          # trouble checks in a row with a contact deeper than max_penetration
        #: The largest body tilt (rad) and the deepest contact overlap (m) seen at the trouble checks so
        #: far: how close the run came to the trouble limits (``max_tilt``, ``max_penetration``).
        self.peak_tilt = 0.0
        self.peak_overlap = 0.0
        n = len(scene.robots)
        self._commands: list[list[tuple[float, float] | None]] = [[None, None] for _ in range(n)]
        self._build()
        noise = config.noise
        #: The plate's friction field (``NoiseConfig.friction_sd`` > 0), or None: uniform friction.
        self.friction_field: FrictionField | None = None
        self._friction_factor = np.full(n, np.nan)   # factor applied to each body now
        if noise.friction_sd > 0.0:
            self.friction_field = FrictionField(noise.friction_sd, noise.friction_length,
                                                self._physics.plate_size, noise.trial_seed(scene.seed))
            self.update_plate_friction()

    # ----------------------------------------------------------------- construction
    def _build(self) -> None:
        """Create the plate and the robots and set the engine parameters once."""
        c, ph, spec, diag = self._client, self._physics, self.config.robot, self.config.diagnostics
        configure_engine(c, ph, len(self.scene.robots))
        c.setGravity(0.0, 0.0, -ph.gravity)
        arm_friction, body_friction, plate_friction = ph.link_frictions()   # Bullet multiplies the pair's values
        link_contact = robot_link_contact(ph, spec.total_mass)
        restitution = link_contact['restitution']
        half = ph.plate_size / 2.0
        plate_shape = c.createCollisionShape(pybullet.GEOM_BOX,
                                             halfExtents=[half, half, ph.plate_thickness / 2.0])
        plate_visual = c.createVisualShape(pybullet.GEOM_BOX,
                                           halfExtents=[half, half, ph.plate_thickness / 2.0],
                                           rgbaColor=[0.75, 0.75, 0.78, 1.0])
        self.plate_id = c.createMultiBody(0.0, plate_shape, plate_visual,
                                          basePosition=[0.0, 0.0, -ph.plate_thickness / 2.0])
        plate_restitution = restitution   # Bullet multiplies the pair's values, like friction
        if ph.restitution_body_plate is not None:
            plate_restitution = ph.restitution_body_plate / restitution if restitution > 0.0 else 0.0
        c.changeDynamics(self.plate_id, -1, lateralFriction=plate_friction,
                         restitution=plate_restitution, rollingFriction=0.0, spinningFriction=0.0)
        soft = ph.soft_contact(spec.total_mass)
        if soft is not None:
            link_stiffness, _, plate_damping = soft
            c.changeDynamics(self.plate_id, -1, contactStiffness=link_stiffness * SOFT_PLATE_STIFFNESS_FACTOR,
                             contactDamping=plate_damping)

        w, d, h = spec.body_width, spec.body_depth, spec.body_height
        half_l = spec.arm_length / 2.0
        arm_half = [half_l, spec.arm_thickness / 2.0, spec.arm_height / 2.0]
        body_shape = c.createCollisionShape(pybullet.GEOM_BOX, halfExtents=[w / 2, d / 2, h / 2])
        body_visual = c.createVisualShape(pybullet.GEOM_BOX, halfExtents=[w / 2, d / 2, h / 2],
                                          rgbaColor=[0.2, 0.3, 0.8, 1.0])
        arm_shapes, arm_visuals = [], []
        for sign in (-1.0, 1.0):
            offset = [sign * half_l, 0.0, 0.0]
            arm_shapes.append(self._arm_shape(sign, arm_half))
            arm_visuals.append(c.createVisualShape(pybullet.GEOM_BOX, halfExtents=arm_half,
                                                   visualFramePosition=offset,
                                                   rgbaColor=[0.9, 0.5, 0.1, 1.0]))
        arm_z = spec.arm_clearance + spec.arm_height / 2.0 - h / 2.0   # arm centre relative to body centre
        ident = [0.0, 0.0, 0.0, 1.0]
        ids = []
        for placement in self.scene.robots:
            state = placement.state
            z = h / 2.0 if state is None else state.z
            yaw = placement.heading - math.pi / 2.0
            # A held body has no mass: Bullet makes it the fixed base of its multibody, so it neither moves
            # nor tips, other robots collide with it as with a wall, and its arms still turn on their joints.
            body = c.createMultiBody(
                0.0 if placement.held else spec.body_mass, body_shape, body_visual, [placement.x, placement.y, z],
                c.getQuaternionFromEuler([0.0, 0.0, yaw]) if state is None else state.orientation,
                linkMasses=list(arm_masses(spec, diag.mass_model)), linkCollisionShapeIndices=arm_shapes,
                linkVisualShapeIndices=arm_visuals,
                linkPositions=[[-w / 2, 0.0, arm_z], [w / 2, 0.0, arm_z]], linkOrientations=[ident, ident],
                linkInertialFramePositions=[[-half_l, 0.0, 0.0], [half_l, 0.0, 0.0]],
                linkInertialFrameOrientations=[ident, ident], linkParentIndices=[0, 0],
                linkJointTypes=[pybullet.JOINT_REVOLUTE] * 2, linkJointAxis=[[0, 0, -1], [0, 0, 1]])
            # Damping and activation state are whole-body properties: passed with a link index, PyBullet
            # applies the call's friction to the base instead of the link. So they go with the base only.
            c.changeDynamics(body, -1, lateralFriction=body_friction,
                             rollingFriction=0.0, spinningFriction=0.0, linearDamping=0.0, angularDamping=0.0,
                             activationState=pybullet.ACTIVATION_STATE_DISABLE_SLEEPING, **link_contact)
            for link in ARM_JOINTS:
                c.changeDynamics(body, link, lateralFriction=arm_friction,
                                 rollingFriction=0.0, spinningFriction=0.0, jointDamping=0.0, **link_contact)
            diagnostics.bullet_robot(c, body, placement.held, spec, diag)
            scales = body_inertia_scales(ph.tilt_inertia_scale, diag)
            if scales != (1.0, 1.0, 1.0) and not placement.held:
                inertia = c.getDynamicsInfo(body, -1)[2]
                c.changeDynamics(body, -1, localInertiaDiagonal=[i * k for i, k in zip(inertia, scales, strict=True)])
            if ph.ccd_swept_sphere_radius > 0.0:
                for link in (-1, *ARM_JOINTS):
                    c.changeDynamics(body, link, ccdSweptSphereRadius=ph.ccd_swept_sphere_radius)
            if not ph.arm_plate_collision:
                for j in ARM_JOINTS:
                    c.setCollisionFilterPair(body, self.plate_id, j, -1, 0)
            if state is None:
                c.resetJointState(body, ARM_JOINTS[0], placement.alpha1)
                c.resetJointState(body, ARM_JOINTS[1], placement.alpha2)
            else:   # a start taken from a running trial: its velocities too
                c.resetJointState(body, ARM_JOINTS[0], placement.alpha1, targetVelocity=state.arm_velocities[0])
                c.resetJointState(body, ARM_JOINTS[1], placement.alpha2, targetVelocity=state.arm_velocities[1])
                if not placement.held:
                    c.resetBaseVelocity(body, linearVelocity=state.velocity, angularVelocity=state.angular_velocity)
            ids.append(body)
        self.body_ids: tuple[int, ...] = tuple(ids)
        self._robot_of_body = {b: k for k, b in enumerate(ids)}
        for k, placement in enumerate(self.scene.robots):
            self.send(k, (placement.alpha1, placement.alpha2), spec.servo_speed)
        #: What the diagnostics run before each step (``Diagnostics.plate_friction_slip``), or None.
        self._before_step = diagnostics.bullet_world(c, self.plate_id, self.body_ids, ARM_JOINTS,
                                                     ph.friction_body_plate, diag)

    def _arm_shape(self, sign: float, arm_half: list[float]) -> int:
        """The collision shape of the arm of half extents ``arm_half`` along ``sign`` * x: the authors' box arm,
        unless the diagnostics give it other ends."""
        shape = diagnostics.bullet_arm_shape(self._client, sign, arm_half, self.config.diagnostics)
        if shape is not None:
            return shape
        return self._client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=arm_half,
                                                  collisionFramePosition=[sign * arm_half[0], 0.0, 0.0])

    # ----------------------------------------------------------------- properties
    @property
    def client(self) -> BulletClient:
        """The world's own PyBullet client (for rendering or debugging; do not step it directly)."""
        return self._client

    @property
    def n_robots(self) -> int:
        """Number of robots."""
        return len(self.body_ids)

    @property
    def time(self) -> float:
        """Simulated time since the world was built (s)."""
        return self._step_count * self._physics.time_step

    @property
    def step_count(self) -> int:
        """Physics steps taken."""
        return self._step_count

    @property
    def steps_per_tick(self) -> int:
        """Physics steps per control tick."""
        return self._steps_per_tick

    @property
    def control_tick(self) -> float:
        """Seconds of sim time in one control tick."""
        return self._physics.control_tick

    @property
    def fsr_steps(self) -> int:
        """Physics steps the FSR reading averages over (``PhysicsConfig.fsr_steps``)."""
        return self._physics.fsr_steps

    def run_meta(self) -> dict[str, Any]:
        """Nothing: a recording without an ``engine`` entry is Bullet's."""
        return {}

    # ----------------------------------------------------------------- commands
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
        """Send servo commands of robot ``k`` (unchecked: for controllers), only for joints that changed."""
        speed = min(speed, self.config.robot.servo_speed)
        last = self._commands[k]
        for j in ARM_JOINTS:
            command = (targets[j], speed)
            if last[j] == command:
                continue
            self._client.setJointMotorControl2(
                self.body_ids[k], j, pybullet.POSITION_CONTROL, targetPosition=targets[j],
                targetVelocity=0.0, force=self.config.robot.servo_torque, maxVelocity=speed,
                positionGain=self._physics.servo_gain(), velocityGain=1.0)
            last[j] = command

    # ----------------------------------------------------------------- plate friction
    def update_plate_friction(self) -> int:
        """Set each body's friction from the friction field at its position; return the bodies changed.

        A body is changed only when the field there differs from its applied factor by more than
        ``NoiseConfig.friction_tolerance`` (of the mean), so most calls cost one pose read per robot. Bullet
        multiplies the two links' values, so the body link takes ``factor * link_frictions()[1]``: body-plate
        friction follows the field, and this robot's contacts with other robots' arms and bodies (arm-body,
        body-body) are scaled by the same factor. No field: nothing to do (0).
        """
        field = self.friction_field
        if field is None:
            return 0
        factor = field.factor(self.body_xy())
        changed = np.flatnonzero(~(np.abs(factor - self._friction_factor)
                                   <= self.config.noise.friction_tolerance))
        if changed.size:
            body_friction = self._physics.link_frictions()[1]
            for k in changed:
                self._client.changeDynamics(self.body_ids[k], -1, lateralFriction=body_friction * factor[k])
                self._friction_factor[k] = factor[k]
        return int(changed.size)

    def plate_friction(self, robot: int) -> float:
        """Body-plate friction coefficient of ``robot`` now, from Bullet's dynamics info (body x plate)."""
        k = self.check_robot(robot)
        body = self._client.getDynamicsInfo(self.body_ids[k], -1)[1]
        plate = self._client.getDynamicsInfo(self.plate_id, -1)[1]
        return float(body * plate)

    # ----------------------------------------------------------------- stepping
    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps (the runner adds controllers and trouble checks around them)."""
        step = self._client.stepSimulation
        before = self._before_step
        if before is None:
            for _ in range(n):
                step()
        else:
            for _ in range(n):
                before()
                step()
        self._step_count += n
        self._state = None

    def ticks_for(self, seconds: float) -> int:
        """Number of control ticks in ``seconds`` of sim time (rounded)."""
        return round(seconds / self._physics.control_tick)

    # ----------------------------------------------------------------- ground truth
    def state(self) -> PhysicsState:
        """Ground truth of all robots now (read once per step, then cached)."""
        if self._state is None:
            self._state = self._read_state()
        return self._state

    def poses(self) -> np.ndarray:
        """(N, 3) x, y (m) and heading of the body normal (rad) of every robot: from the cached state if there
        is one, else from the bases alone (a third of ``state``'s reads; the same values)."""
        if self._state is not None:
            return self._state.poses
        pos, quat = self._read_bases()
        heading, _ = body_headings_and_tilts(quat)
        return np.column_stack([pos[:, 0], pos[:, 1], heading])

    def arm_angles(self) -> np.ndarray:
        """(N, 2) arm angles alpha1, alpha2 (rad)."""
        return self.state().arm_angles

    def arm_velocities(self) -> np.ndarray:
        """(N, 2) arm angular velocities (rad/s)."""
        return self.state().arm_velocities

    def placements(self) -> tuple[RobotPlacement, ...]:
        """Every robot's full state now as a placement (pose, arm angles, ``RobotState``; the scene's gait):
        a scene of them (``scenes.state_scene``) starts a new world where this one is."""
        c = self._client
        pos, quat = self._read_bases()
        heading, _ = body_headings_and_tilts(quat)
        out = []
        for k, body in enumerate(self.body_ids):
            lin, ang = c.getBaseVelocity(body)
            (a1, v1, _, _), (a2, v2, _, _) = c.getJointStates(body, ARM_JOINTS)
            state = RobotState(float(pos[k, 2]), tuple(float(q) for q in quat[k]),  # type: ignore[arg-type]
                               tuple(float(v) for v in lin), tuple(float(w) for w in ang),  # type: ignore[arg-type]
                               (float(v1), float(v2)))
            out.append(RobotPlacement(float(pos[k, 0]), float(pos[k, 1]), float(heading[k]), float(a1), float(a2),
                                      self.scene.robots[k].gait, state, self.scene.robots[k].held))
        return tuple(out)

    def body_xy(self) -> np.ndarray:
        """(N, 2) body centre x, y (m): from the cached state if there is one, else one read per robot."""
        if self._state is not None:
            return self._state.positions[:, :2]
        base_pose = self._client.getBasePositionAndOrientation
        return np.array([base_pose(body)[0][:2] for body in self.body_ids])

    def _read_bases(self) -> tuple[np.ndarray, np.ndarray]:
        """Body centre positions (N, 3) and orientation quaternions (N, 4, xyzw) of every robot."""
        base_pose = self._client.getBasePositionAndOrientation
        pos = np.empty((self.n_robots, 3))
        quat = np.empty((self.n_robots, 4))
        for k, body in enumerate(self.body_ids):
            pos[k], quat[k] = base_pose(body)
        return pos, quat

    def _read_state(self) -> PhysicsState:
        """Read every robot's base pose, velocity and joint states."""
        c = self._client
        n = self.n_robots
        pos, quat = self._read_bases()
        vel = np.empty((n, 3))
        arms = np.empty((n, 2))
        arm_vel = np.empty((n, 2))
        base_vel, joints = c.getBaseVelocity, c.getJointStates
        for k, body in enumerate(self.body_ids):
            vel[k] = base_vel(body)[0]
            (a1, v1, _, _), (a2, v2, _, _) = joints(body, ARM_JOINTS)
            arms[k] = a1, a2
            arm_vel[k] = v1, v2
        heading, tilt = body_headings_and_tilts(quat)
        poses = np.column_stack([pos[:, 0], pos[:, 1], heading])
        return PhysicsState(self.time, poses, pos, tilt, np.linalg.norm(vel, axis=1), arms, arm_vel)

    # ----------------------------------------------------------------- contacts and FSR
    def fsr(self, robots: Sequence[int] | None = None) -> np.ndarray:
        """(len(robots), 4) normal force (N) on each FSR face, in the order of ``FSR_FACES``.

        A contact on arm i counts toward face ``front`` (the face on the body-normal side at alpha = 0,
        i.e. the arm link's +y side) when its force pushes the arm toward -y, else toward ``back``; only
        the component of the contact force along the face normal counts.
        """
        return self.fsr_of(self.robot_list(robots))

    def fsr_of(self, ks: list[int]) -> np.ndarray:
        """``fsr`` of robots ``ks`` already checked (``FsrReading`` calls it every physics step)."""
        out = np.zeros((len(ks), len(FSR_FACES)))
        # bound once (the client wraps every attribute access); link states only for arms in contact
        contact_points, link_states = self._client.getContactPoints, self._client.getLinkStates
        for row, k in enumerate(ks):
            body = self.body_ids[k]
            links = None
            for j in ARM_JOINTS:
                contacts = contact_points(bodyA=body, linkIndexA=j)
                if not contacts:
                    continue
                if links is None:
                    links = link_states(body, ARM_JOINTS)
                qx, qy, qz, qw = links[j][1]
                front = (2.0 * (qx * qy - qw * qz), 1.0 - 2.0 * (qx * qx + qz * qz),
                         2.0 * (qy * qz + qw * qx))
                for point in contacts:
                    force = point[9]
                    normal = point[7]   # on B, pointing from B toward this arm: the push direction
                    along = force * (normal[0] * front[0] + normal[1] * front[1] + normal[2] * front[2])
                    if along < 0.0:
                        out[row, 2 * j] -= along        # pushed toward -front: contact on the front face
                    else:
                        out[row, 2 * j + 1] += along
        return out

    def robot_contacts(self) -> np.ndarray:
        """(N, N) symmetric bool matrix: True where two robots touch now (any links)."""
        n = self.n_robots
        out = np.zeros((n, n), dtype=bool)
        index = self._robot_of_body
        for point in self._client.getContactPoints():
            a, b = index.get(point[1]), index.get(point[2])
            if a is not None and b is not None and a != b:
                out[a, b] = out[b, a] = True
        return out

    def touching(self, max_distance: float = 0.0) -> set[tuple[int, int]]:
        """Pairs (i, j), i < j, of robots with a contact point at distance <= ``max_distance`` (m) now."""
        out: set[tuple[int, int]] = set()
        index = self._robot_of_body
        for point in self._client.getContactPoints():
            if point[8] <= max_distance:
                a, b = index.get(point[1]), index.get(point[2])
                if a is not None and b is not None and a != b:
                    out.add((a, b) if a < b else (b, a))
        return out

    def link_contacts(self, a: int, b: int) -> np.ndarray:
        """(3, 3) bool: [i, j] True where link i of robot ``a`` touches link j of robot ``b`` (body, arm 1, arm 2)."""
        out = np.zeros((3, 3), dtype=bool)
        ka, kb = self.check_robot(a), self.check_robot(b)
        for point in self._client.getContactPoints(bodyA=self.body_ids[ka], bodyB=self.body_ids[kb]):
            out[point[3] + 1, point[4] + 1] = True
        return out

    def max_penetration(self) -> tuple[int, float]:
        """(robot, depth in m) of the deepest contact overlap now; (-1, 0.0) without contacts."""
        worst, robot = 0.0, -1
        index = self._robot_of_body
        for point in self._client.getContactPoints():
            depth = -point[8]
            if depth > worst or depth != depth:
                worst = depth
                robot = index.get(point[1], index.get(point[2], -1))
                if depth != depth:
                    break
        return robot, worst

    def check_trouble(self) -> None:
        """Raise SimTrouble if a robot is not finite, off the plate, flipped, too fast or tunnelling.

        Uses the cached state if there is one; otherwise reads only the body poses and takes the speed
        as the mean over the interval since the previous check (cheap enough to run every few ticks).
        """
        now = self.time
        if self._state is not None:
            s = self._state
            positions, tilt, speed, arms = s.positions, s.tilt, s.speed, s.arm_angles
        else:
            positions, quat = self._read_bases()
            tilt = body_headings_and_tilts(quat)[1]
            last_time, last_positions = self._last_check
            if last_positions is not None and now > last_time:
                speed = np.linalg.norm(positions - last_positions, axis=1) / (now - last_time)
            else:
                speed = np.zeros(self.n_robots)
            arms = np.zeros((self.n_robots, 2))
        self._last_check = (now, positions)
        if tilt.size and np.isfinite(tilt).all():
            self.peak_tilt = max(self.peak_tilt, float(tilt.max()))
        check_state(now, positions, tilt, speed, arms, self._physics, self.config.robot.body_height)
        robot, depth = self.max_penetration()
        if depth == depth:
            self.peak_overlap = max(self.peak_overlap, depth)
        self._deep_checks = check_penetration(now, robot, depth, self._physics, self._deep_checks)

    # ----------------------------------------------------------------- housekeeping
    def check_robot(self, robot: int) -> int:
        """Return ``robot`` as an index or raise SceneError."""
        return robot_index(robot, self.n_robots)

    def robot_list(self, robots: Sequence[int] | None) -> list[int]:
        """All robots, or the given ones checked."""
        if robots is None:
            return list(range(self.n_robots))
        return [self.check_robot(k) for k in robots]

    def close(self) -> None:
        """Disconnect the PyBullet client (idempotent)."""
        client = getattr(self, '_client', None)
        if client is not None:
            try:
                client.disconnect()
            except pybullet.error:
                pass
            self._client = None

    def __enter__(self) -> Physics:
        """Context manager: the physics client closes on exit."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Disconnect the client."""
        self.close()


def robot_link_contact(physics: PhysicsConfig, robot_mass: float) -> dict[str, float]:
    """The ``changeDynamics`` contact values of every robot link: the restitution (Bullet multiplies the two
    links' values, so each gets the square root), or, with soft contacts (``PhysicsConfig.soft_contact``),
    no restitution impulse and the link's stiffness and damping."""
    soft = physics.soft_contact(robot_mass)
    if soft is None:
        return {'restitution': math.sqrt(physics.restitution)}
    return {'restitution': 0.0, 'contactStiffness': soft[0], 'contactDamping': soft[1]}


def configure_engine(client: BulletClient, physics: PhysicsConfig, n_robots: int) -> None:
    """Give the engine the ``physics`` settings for a scene of ``n_robots`` robots: step, solver iterations
    (``PhysicsConfig.iterations_for``) and their residual threshold, deterministic pair order, contact breaking
    threshold, contact ERP and restitution velocity threshold."""
    client.setPhysicsEngineParameter(fixedTimeStep=physics.time_step,
                                     numSolverIterations=physics.iterations_for(n_robots),
                                     numSubSteps=0, deterministicOverlappingPairs=1,
                                     contactBreakingThreshold=physics.contact_breaking_threshold,
                                     contactERP=physics.contact_erp)
    if physics.restitution_velocity_threshold is not None:
        client.setPhysicsEngineParameter(restitutionVelocityThreshold=physics.restitution_velocity_threshold)
    if physics.solver_residual_threshold is not None:
        client.setPhysicsEngineParameter(solverResidualThreshold=physics.solver_residual_threshold)


def quiet_client() -> BulletClient:
    """A DIRECT BulletClient, with the engine's start-up chatter on stdout ('argv[0]=') silenced."""
    with silenced_output():
        return BulletClient(connection_mode=pybullet.DIRECT)
