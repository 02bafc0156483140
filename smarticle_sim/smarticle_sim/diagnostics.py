"""Diagnostics: knobs measured and not taken, set on top of the shipped model (``SimConfig.diagnostics``).

``PhysicsConfig`` is the model the project ships. What was measured beside it to find out what a result rests
on lives here, outside the production path: the authors' uneven masses (``mass_model``, also built by MuJoCo and
the Chrono reference, so their masses can be checked in three engines), their light body in yaw
(``yaw_inertia_scale``), a plate without static friction (``plate_friction_slip``), round arm ends
(``arm_ends``) and raw Bullet solver and contact knobs the physics study tried (``split_impulse`` ... the
study's settings of the same names; docs/physics_study.md). ``Diagnostics()`` is the shipped model: every
function here then leaves the world as ``Physics`` builds it, bit for bit.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import Any

from smarticle_common.facts import SMALL, RobotSpec, require_positive

from .errors import ConfigError, NotConvergedWarning

#: The arm end shapes ``Diagnostics.arm_ends`` accepts.
ARM_ENDS = ('square', 'round')
#: ``Diagnostics.mass_model``: how a robot's mass and inertia are spread over its three links.
MASS_MODELS = ('uniform', 'authors')
#: The authors' published Chrono model of the small robot builds every link as a box of this density and then
#: sets the mass of the body and of one arm only (``mass_model`` 'authors').
AUTHORS_LINK_DENSITY = 100.0          # kg/m^3
#: The mass (kg) their code gives the one arm whose mass it sets (the other keeps its 100 kg/m^3 box: 0.345 g).
AUTHORS_ARM_MASS = 0.00319
#: The diagnostics each engine builds (the others it refuses: ``Diagnostics.check_engine``).
ENGINE_SUPPORT: dict[str, frozenset[str]] = {
    'mujoco': frozenset({'mass_model'}),
    'chrono': frozenset({'mass_model', 'yaw_inertia_scale'}),
}
#: Raw Bullet knobs: field -> ``setPhysicsEngineParameter`` name.
_ENGINE_PARAMETERS = {'split_impulse': 'useSplitImpulse', 'split_threshold': 'splitImpulsePenetrationThreshold',
                      'cfm': 'globalCFM', 'cone_friction': 'enableConeFriction', 'friction_erp': 'frictionERP'}


@dataclass(frozen=True)
class Diagnostics:
    """Knobs measured as diagnostics and not taken; the defaults are the shipped model (nothing changed)."""

    #: Factor on the body's yaw inertia (about the plate normal; mass and contacts unchanged). 1: a uniform box
    #: of the body's mass. The authors' published Chrono code keeps the inertia of a box of density 100 kg/m^3
    #: after setting the body's mass to 24.8 g, a yaw inertia 0.129 of the uniform body's; measured on P1 as a
    #: diagnostic of whether their P1 rests on it (docs/calibration/paper_figures.md, "The authors' light
    #: body"), not taken: a real body with a servo at each end is no lighter in yaw than uniform.
    yaw_inertia_scale: float = 1.0
    #: How the robot's mass is spread over its links. 'uniform': the body and two equal arms of the robot's
    #: spec, each link with the inertia of a uniform box of its mass. 'authors': as the authors' published
    #: Chrono code builds the small robot, every link's inertia that of a box of density 100 kg/m^3 (the
    #: body's that of a 3.2 g box), the body's mass the spec's (24.8 g), arm 1 (the left arm, joint 0) 3.19 g
    #: and arm 2 its 100 kg/m^3 box's 0.345 g (28.3 g in all). Measured as a diagnostic of what lets the
    #: authors' in-phase pairs glide (docs/calibration/paper_figures.md, "The authors' uneven arms"), not
    #: taken: a robot with one arm nine times heavier than the other is not the paper's robot. The roll /
    #: pitch and yaw factors multiply the body's inertia of either model.
    mass_model: str = 'uniform'
    #: Body-plate friction without static friction, as in the authors' smooth (SMC) Chrono contact. None:
    #: Bullet's Coulomb friction, which holds a body still under any sideways force below mu N. A speed (m/s):
    #: Bullet's body-plate friction is off and every body-plate contact point gets a friction force applied
    #: before each step, mu N_i v_i / max(|v_i|, plate_friction_slip) against its sliding velocity v_i (N_i:
    #: its normal force of the step before), so below that speed friction is a viscous drag. Chrono's
    #: Hertzian contact with the authors' values (E 2e7 Pa, nu 0.3, restitution 0.85, a 1e-4 s step, its
    #: default 0.1 m curvature radius, four corner points under a 28-35 g robot) makes its tangential force
    #: k_t v dt + g_t v below mu N, i.e. viscous up to about 7 mm/s. A diagnostic of whether the authors'
    #: in-phase pairs glide because their plate has no static friction (docs/calibration/paper_figures.md,
    #: "A plate without static friction"); not taken.
    plate_friction_slip: float | None = None
    #: The arms' ends in plan view. 'square': the authors' box arms (5.0 x 0.3 x 2.3 cm). 'round': the same
    #: box with both vertical end edges rounded to the arm's half thickness (a stadium in plan view: a box of
    #: length L - t between two vertical cylinders of diameter t, same length, height, mass and inertia), so
    #: an arm tip slides round another arm instead of catching on a box corner. Measured as a candidate for
    #: the hook that binds the paper's isolated pairs and rejected: no more isolated gliders than square ends
    #: on P1's seeds (docs/calibration/paper_figures.md, "Round arm ends").
    arm_ends: str = 'square'
    #: Raw Bullet knobs the physics study tried (docs/history/physics_study.md); None: Bullet's own.
    split_impulse: bool | None = None          # useSplitImpulse
    split_threshold: float | None = None       # splitImpulsePenetrationThreshold (m)
    cfm: float | None = None                   # globalCFM
    cone_friction: bool | None = None          # enableConeFriction
    friction_erp: float | None = None          # frictionERP
    plate_restitution: float | None = None     # the plate's own restitution value, set after the build
    #: Every robot link's raw contact stiffness (N/m) and damping, set after the build (``PhysicsConfig.
    #: contact_stiffness`` is the calibrated soft contact; this is Bullet's value as given).
    link_contact_stiffness: float | None = None
    link_contact_damping: float = 0.0

    def __post_init__(self) -> None:
        require_positive(self, 'yaw_inertia_scale', error=ConfigError)
        if self.mass_model not in MASS_MODELS:
            raise ConfigError(f'Diagnostics.mass_model must be one of {", ".join(MASS_MODELS)}, '
                              f'got {self.mass_model!r}')
        if self.arm_ends not in ARM_ENDS:
            raise ConfigError(f'Diagnostics.arm_ends must be one of {", ".join(ARM_ENDS)}, got {self.arm_ends!r}')
        for name in ('plate_friction_slip', 'split_threshold', 'link_contact_stiffness'):
            if getattr(self, name) is not None:
                require_positive(self, name, error=ConfigError)
        for name in ('cfm', 'friction_erp', 'plate_restitution', 'link_contact_damping'):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float)) or value < 0):
                raise ConfigError(f'Diagnostics.{name} must be a number >= 0, got {value!r}')

    @property
    def changed(self) -> tuple[str, ...]:
        """The fields that differ from the shipped model."""
        return tuple(f.name for f in fields(self) if getattr(self, f.name) != f.default)

    @property
    def active(self) -> bool:
        """True if anything differs from the shipped model."""
        return bool(self.changed)

    def check(self, robot: RobotSpec, physics: Any, friction_sd: float) -> None:
        """Refuse what cannot hold for ``robot`` and ``physics`` (a PhysicsConfig) and a friction field of
        ``friction_sd``; warn about what converges poorly."""
        if self.plate_friction_slip is not None:
            if friction_sd > 0.0:
                raise ConfigError('Diagnostics.plate_friction_slip: the applied plate friction has no friction '
                                  'field; set NoiseConfig.friction_sd to 0')
            drag_per_step = physics.friction_body_plate * physics.gravity * physics.time_step / self.plate_friction_slip
            if drag_per_step > 1.0:
                warnings.warn(f'Diagnostics.plate_friction_slip: {self.plate_friction_slip:g} m/s at a '
                              f'{physics.time_step:.6g} s step takes {drag_per_step:.2f} of a sliding speed in one '
                              'step (explicit drag; above 1 it overshoots): use a larger slip speed or a finer step',
                              NotConvergedWarning, stacklevel=4)
        if self.mass_model == 'authors' and ((robot.body_width, robot.body_depth, robot.arm_length)
                                             != (SMALL.body_width, SMALL.body_depth, SMALL.arm_length)):
            raise ConfigError("Diagnostics.mass_model 'authors' is the authors' Chrono model of the paper's small "
                              'robot; use it with the small preset')

    def check_engine(self, engine: str) -> None:
        """Refuse the diagnostics ``engine`` does not build (Bullet builds every one)."""
        if engine == 'bullet':
            return
        missing = [name for name in self.changed if name not in ENGINE_SUPPORT.get(engine, frozenset())]
        if missing:
            raise ConfigError(f'diagnostics.{missing[0]} is built by Bullet only, not by {engine}')


def arm_masses(spec: RobotSpec, mass_model: str) -> tuple[float, float]:
    """The masses (kg) of arm 1 and arm 2 (joints 0 and 1) under ``Diagnostics.mass_model``."""
    if mass_model == 'authors':
        return AUTHORS_ARM_MASS, AUTHORS_LINK_DENSITY * spec.arm_length * spec.arm_thickness * spec.arm_height
    return spec.arm_mass, spec.arm_mass


def box_inertia(mass: float, size_x: float, size_y: float, size_z: float) -> tuple[float, float, float]:
    """The principal moments of inertia (kg m^2) of a uniform box of ``mass`` and edge lengths ``size_*`` (m)."""
    return (mass * (size_y ** 2 + size_z ** 2) / 12.0, mass * (size_x ** 2 + size_z ** 2) / 12.0,
            mass * (size_x ** 2 + size_y ** 2) / 12.0)


def authors_inertias(spec: RobotSpec) -> tuple[tuple[float, float, float], ...]:
    """Body, arm 1 and arm 2 inertias (kg m^2, link frames) of the authors' model: boxes of 100 kg/m^3.

    Their code sets the body's and arm 1's masses after building the boxes, which leaves every link the
    inertia of its 100 kg/m^3 box (``Diagnostics.mass_model``).
    """
    body = (spec.body_width, spec.body_depth, spec.body_height)
    arm = (spec.arm_length, spec.arm_thickness, spec.arm_height)
    arm_inertia = box_inertia(AUTHORS_LINK_DENSITY * math.prod(arm), *arm)
    return box_inertia(AUTHORS_LINK_DENSITY * math.prod(body), *body), arm_inertia, arm_inertia


def body_inertia_scales(tilt_inertia_scale: float, diagnostics: Diagnostics) -> tuple[float, float, float]:
    """The factors on the body's roll, pitch and yaw inertia."""
    return tilt_inertia_scale, tilt_inertia_scale, diagnostics.yaw_inertia_scale


# ------------------------------------------------------------------ Bullet


def bullet_arm_shape(client: Any, sign: float, arm_half: Sequence[float], diagnostics: Diagnostics) -> int | None:
    """The collision shape of a diagnostic arm end (``arm_ends`` 'round'), or None for the shipped box arm."""
    if diagnostics.arm_ends == 'square':
        return None
    # 'round': a box between two vertical cylinders of the arm's thickness, the same overall extent. The
    # compound's AABB is the box arm's, so Bullet gives the link the same inertia.
    import pybullet   # here: the settings import this module without the engine

    half_l, half_t, half_h = arm_half
    return int(client.createCollisionShapeArray(
        shapeTypes=[pybullet.GEOM_BOX, pybullet.GEOM_CYLINDER, pybullet.GEOM_CYLINDER],
        halfExtents=[[half_l - half_t, half_t, half_h], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
        radii=[0.0, half_t, half_t], lengths=[0.0, 2.0 * half_h, 2.0 * half_h],
        collisionFramePositions=[[sign * half_l, 0.0, 0.0], [sign * half_t, 0.0, 0.0],
                                 [sign * (2.0 * half_l - half_t), 0.0, 0.0]]))


def bullet_robot(client: Any, body: int, held: bool, spec: RobotSpec, diagnostics: Diagnostics) -> None:
    """A robot's diagnostic inertias (``mass_model`` 'authors'), set as it is built."""
    if diagnostics.mass_model == 'authors':
        for link, inertia in enumerate(authors_inertias(spec)):
            if link > 0 or not held:
                client.changeDynamics(body, link - 1, localInertiaDiagonal=inertia)


def bullet_world(client: Any, plate_id: int, body_ids: Sequence[int], arm_links: Sequence[int],
                 friction_body_plate: float, diagnostics: Diagnostics) -> Callable[[], None] | None:
    """Set the diagnostics on a built Bullet world; return what runs before each step (or None)."""
    params = {_ENGINE_PARAMETERS[name]: (int(bool(value)) if isinstance(value, bool) else float(value))
              for name in _ENGINE_PARAMETERS if (value := getattr(diagnostics, name)) is not None}
    if params:
        client.setPhysicsEngineParameter(**params)
    if diagnostics.plate_restitution is not None:
        client.changeDynamics(plate_id, -1, restitution=float(diagnostics.plate_restitution))
    if diagnostics.link_contact_stiffness is not None:
        for body in body_ids:
            for link in (-1, *arm_links):
                client.changeDynamics(body, link, contactStiffness=float(diagnostics.link_contact_stiffness),
                                      contactDamping=float(diagnostics.link_contact_damping))
    if diagnostics.plate_friction_slip is None:
        return None
    client.changeDynamics(plate_id, -1, lateralFriction=0.0)   # friction is applied per contact point
    return PlateSlip(client, plate_id, friction_body_plate, float(diagnostics.plate_friction_slip))


class PlateSlip:
    """``plate_friction_slip``'s friction, applied to every body-plate contact point of the last step."""

    def __init__(self, client: Any, plate_id: int, mu: float, slip: float) -> None:
        self.client, self.plate_id, self.mu, self.slip = client, plate_id, mu, slip

    def __call__(self) -> None:
        """Apply the friction forces (plain floats, not numpy: a few points per robot and step, where numpy's
        call overhead would dominate)."""
        import pybullet

        c, mu, slip = self.client, self.mu, self.slip
        moving: dict[int, tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]] = {}
        for point in c.getContactPoints(bodyA=self.plate_id):
            body, normal_force = point[2], point[9]
            if point[4] != -1 or normal_force <= 0.0:
                continue
            if body not in moving:
                linear, angular = c.getBaseVelocity(body)
                moving[body] = (linear, angular, c.getBasePositionAndOrientation(body)[0])
            (vx, vy, vz), (wx, wy, wz), (cx, cy, cz) = moving[body]
            at = point[6]
            nx, ny, nz = point[7]
            rx, ry, rz = at[0] - cx, at[1] - cy, at[2] - cz
            ux, uy, uz = vx + wy * rz - wz * ry, vy + wz * rx - wx * rz, vz + wx * ry - wy * rx
            along = ux * nx + uy * ny + uz * nz
            sx, sy, sz = ux - along * nx, uy - along * ny, uz - along * nz
            scale = -mu * normal_force / max(math.sqrt(sx * sx + sy * sy + sz * sz), slip)
            c.applyExternalForce(body, -1, (scale * sx, scale * sy, scale * sz), at, pybullet.WORLD_FRAME)
