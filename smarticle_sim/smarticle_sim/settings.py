"""Frozen, validated settings of the smarticle simulation: physics knobs and the robot they simulate.

Lengths in metres, masses in kilograms, angles in radians, times in seconds (SI inside). The robots
themselves (``RobotSpec``, the presets ``SMALL`` and ``FEEDBACK``) are facts of ``smarticle_common.facts``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import Any

from smarticle_common.facts import SMALL, RobotSpec, require_non_negative, require_positive

from .diagnostics import Diagnostics
from .errors import ConfigError, NotConvergedWarning

#: Soft contacts (``PhysicsConfig.contact_stiffness``): the largest contact-spring angle per step (rad; omega
#: x time_step, omega = sqrt(k / (m / 2)) of one contact point) before Bullet's implicit integration takes
#: about 10 % of the rebound (the measured rebound against the angle: docs/calibration/paper_figures.md,
#: "Soft contacts").
SOFT_CONTACT_MAX_OMEGA_DT = 0.03
#: Bullet's own solver residual threshold (PyBullet's physics server sets it), what
#: ``PhysicsConfig.solver_residual_threshold`` None leaves in place.
BULLET_SOLVER_RESIDUAL_THRESHOLD = 1e-7


@dataclass(frozen=True)
class PhysicsConfig:
    """PyBullet settings: stepping, solver, contact and servo-loop knobs, trouble bounds.

    The defaults are the converged, stable model of docs/sim_calibration.md: the paper authors' contact
    values (friction 0.3 on every pair, impacts between robots rebounding with 0.85 and none on the plate), a servo
    of fixed bandwidth, the robots' own masses and inertias, at the coarsest step and the fewest solver
    iterations at which the observables converge (1/960 s, 10 iterations; where each is against its
    time-step limit, and what misses: docs/sim_calibration.md, the claims table). Each value that departs
    from a measured or published one says why below; the figures behind it are in the docs.
    """

    #: Physics step (s). 1/960 s: the coarsest step at which the dense statistics (the C1 / C2 mix of P1's
    #: gliders) converge; the single-robot drift is within 10 % of its limit
    #: (docs/calibration/numerics.md, Convergence).
    time_step: float = 1.0 / 960.0
    control_tick: float = 1.0 / 60.0            # must be a whole number of time steps
    #: Contact solver sweeps per step. 10 at 1/960 s: the fewest with which a bound pair's travel and the
    #: drift at every heading converge; fewer let the pair glide too fast (docs/calibration/numerics.md,
    #: "The default's solver" and Speed). Stopping the solver early by its residual
    #: (``solver_residual_threshold``) was measured and not taken: it leaves the drift off its limit.
    solver_iterations: int = 10
    #: Large packs: a scene of more than ``large_pack_robots`` robots is stepped with at least
    #: ``large_pack_iterations`` solver iterations. Bullet's sequential-impulse solver converges more slowly
    #: on larger contact islands, and more slowly still at contact ERP 0.1, which pushes a jam's overlaps
    #: out slowly: 50 densely packed robots need 20 to run clean (docs/calibration/numerics.md, Stability).
    #: 7 is the largest pack measured clean at the small-scene iterations, so the rule starts above it.
    large_pack_robots: int = 7
    large_pack_iterations: int = 20
    #: Bullet's solver residual threshold (``solverResidualThreshold``): the solver stops iterating early
    #: once the largest squared velocity change (m^2/s^2) any constraint row got in an iteration is at or
    #: below it, so ``solver_iterations`` becomes a cap. None: Bullet's own 1e-7 (a velocity change of 0.3
    #: mm/s, ``BULLET_SOLVER_RESIDUAL_THRESHOLD``), which in contact rarely stops the solver before the cap.
    solver_residual_threshold: float | None = None
    contact_breaking_threshold: float = 0.002   # m; Bullet's default 0.02 is far larger than the robots' gaps
    gravity: float = 9.81
    friction_body_plate: float = 0.30           # the authors' Chrono model (0.3-0.37)
    friction_robot_robot: float = 0.30          # the authors' Chrono model: every robot-robot pair
    #: Arm-arm friction. None: every robot-robot pair uses friction_robot_robot (the default, as in the
    #: authors' model). A number: arm-arm uses it, arm-body keeps friction_robot_robot, and body-body
    #: becomes friction_robot_robot**2 / friction_arm_arm (Bullet multiplies the two links' values). The
    #: old 1.5 "hook" took back part of every push and kept every pair bound (docs/history/physics_study.md, A).
    friction_arm_arm: float | None = None
    #: Robot-robot restitution set in Bullet: 0.80, which with ``contact_erp`` 0.1 gives two robots meeting
    #: head on the authors' 0.85; Bullet adds the ERP's push-out of the impact step's overlap to the bounce
    #: (docs/calibration/paper_figures.md, "What restitution Bullet gives"). Restitution is what makes
    #: collisions repel: kicks that leave the pair separating instead of pushes that end at rest
    #: (docs/history/physics_study.md, A).
    restitution: float = 0.80
    position_gain: float = 0.3                  # servo loop gain per step, used only if servo_bandwidth is None
    plate_size: float = 0.60                    # square plate side (m), centred on the origin
    plate_thickness: float = 0.01
    arm_plate_collision: bool = False           # arms have clearance; the pair is filtered out
    max_tilt: float = math.radians(25.0)        # trouble: body z axis tilted beyond this
    max_speed: float = 2.0                      # trouble: body speed (m/s)
    #: Bullet's contact error reduction: the fraction of an overlap pushed out per step. 0.1: the push-out
    #: of the overlap found at an impact adds to the bounce, which at 0.6 (an earlier default) made impacts
    #: super-elastic on average (docs/calibration/paper_figures.md, "What restitution Bullet gives").
    contact_erp: float = 0.1
    max_penetration: float = 0.004              # trouble: contact overlap (m) ...
    penetration_checks: int = 3                 # ... at this many trouble checks in a row (a spike is not a tunnel)
    trouble_every: int = 6                      # check for trouble every n control ticks
    #: Servo loop bandwidth (1/s): the gain per step is min(1, servo_bandwidth * time_step), so the servo's
    #: final approach (time constant 1 / bandwidth, 5 ms) is the same at every step and the drift converges.
    #: P7's drift is what pins it (the paper gives no bandwidth; docs/sim_calibration.md, "The default
    #: model"; docs/physics_study.md). None: the old per-step ``position_gain``, whose approach shrinks with
    #: the step, so the drift has no limit.
    servo_bandwidth: float | None = 200.0
    #: Bullet's restitutionVelocityThreshold (m/s): contacts approaching slower get no restitution. 0.01:
    #: the authors' model bounces every impact (Bullet's 0.2 binds pairs the same: docs/sim_calibration.md,
    #: "The default model").
    restitution_velocity_threshold: float | None = 0.01
    #: Body-plate restitution. 0: the bodies rest on the plate; 0.85 there makes robots hop and tip.
    #: None: the same as ``restitution``.
    restitution_body_plate: float | None = 0.0
    #: Bullet's continuous collision detection: swept-sphere radius (m) on every robot link; 0 = off (no
    #: tunnelling at 1/480 s or finer, so it is not needed: docs/sim_calibration.md, "The default model").
    ccd_swept_sphere_radius: float = 0.0
    #: Factor on the body's roll and pitch inertia (mass, yaw inertia and contacts unchanged). 1: the body's
    #: own. x100 kept robots flat while impacts were super-elastic (contact ERP 0.6: jammed robots bounced
    #: between two contacts and rolled over; docs/history/physics_study.md, C); at the default contact the robots'
    #: own inertia runs clean (docs/calibration/paper_figures.md, "The robots' own roll and pitch inertia"),
    #: so nothing departs from the robot here any more.
    tilt_inertia_scale: float = 1.0
    #: Compliant robot-robot contacts, as in the authors' smooth-contact (penalty) Chrono model: the
    #: stiffness (N/m) of a robot-robot contact point. None: Bullet's rigid contacts (the restitution as a
    #: velocity jump, overlaps pushed out by ``contact_erp``). If set, each robot-robot contact point is a
    #: spring of this stiffness with the damping that would give two whole robots meeting on one point the
    #: ``restitution`` (reduced mass m / 2; a face-to-face contact has up to four points, so it is stiffer and
    #: more damped), Bullet's restitution impulse is off, and the body-plate contact is a critically damped
    #: spring whatever ``restitution_body_plate`` says (Bullet cannot make one contact of a link soft and
    #: another rigid). Measured against the rigid default in docs/calibration/paper_figures.md, "Soft
    #: contacts".
    contact_stiffness: float | None = None

    #: The sim's FSR reading is each face's contact force averaged over this time (s; a whole number of
    #: steps, at least one), so a collision kick reads its impulse / fsr_window at every time step instead
    #: of impulse / time_step. 1/480 s: a kick is one physics step there, and the feedback windows were
    #: first calibrated at that step (docs/feedback.md, "FSR sample in the sim").
    fsr_window: float = 1.0 / 480.0

    def __post_init__(self) -> None:
        require_positive(self, 'time_step', 'control_tick', 'fsr_window', 'plate_size', 'plate_thickness', 'max_tilt',
                  'max_speed', 'max_penetration', 'position_gain', 'contact_breaking_threshold', 'contact_erp',
                         error=ConfigError)
        require_non_negative(self, 'gravity', 'friction_body_plate', 'friction_robot_robot', 'restitution',
                             error=ConfigError)
        if self.contact_erp > 1.0:
            raise ConfigError(f'PhysicsConfig.contact_erp must be in (0, 1], got {self.contact_erp}')
        for name in ('solver_iterations', 'trouble_every', 'penetration_checks', 'large_pack_robots',
                     'large_pack_iterations'):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f'PhysicsConfig.{name} must be an integer >= 1, got {value!r}')
        if self.friction_arm_arm is not None:
            require_positive(self, 'friction_arm_arm', error=ConfigError)
        for name in ('servo_bandwidth', 'contact_stiffness', 'solver_residual_threshold'):
            if getattr(self, name) is not None:
                require_positive(self, name, error=ConfigError)
        for name in ('restitution_velocity_threshold', 'restitution_body_plate'):
            if getattr(self, name) is not None:
                require_non_negative(self, name, error=ConfigError)
        require_non_negative(self, 'ccd_swept_sphere_radius', error=ConfigError)
        require_positive(self, 'tilt_inertia_scale', error=ConfigError)
        if self.restitution_body_plate is not None and self.restitution_body_plate > 1.0:
            raise ConfigError(f'PhysicsConfig.restitution_body_plate must be in [0, 1], '
                              f'got {self.restitution_body_plate}')
        if self.link_frictions()[2] > 10.0:
            raise ConfigError(f'PhysicsConfig.friction_arm_arm: {self.friction_arm_arm} with friction_robot_robot '
                              f'{self.friction_robot_robot} leaves too little body friction to reach '
                              f'friction_body_plate {self.friction_body_plate} (plate value above 10)')
        if self.restitution > 1.0:
            raise ConfigError(f'PhysicsConfig.restitution must be in [0, 1], got {self.restitution}')
        if self.position_gain > 1.0:
            raise ConfigError(f'PhysicsConfig.position_gain must be in (0, 1], got {self.position_gain}')
        steps_per_tick(self.control_tick, self.time_step)

    @property
    def steps_per_tick(self) -> int:
        """Physics steps in one control tick."""
        return steps_per_tick(self.control_tick, self.time_step)

    @property
    def fsr_steps(self) -> int:
        """Physics steps the FSR reading averages over (``fsr_window`` / ``time_step``, rounded, at least 1)."""
        return max(1, round(self.fsr_window / self.time_step))

    def iterations_for(self, n_robots: int) -> int:
        """The solver iterations a scene of ``n_robots`` robots is stepped with (see ``large_pack_robots``)."""
        if n_robots > self.large_pack_robots:
            return max(self.solver_iterations, self.large_pack_iterations)
        return self.solver_iterations

    def servo_gain(self) -> float:
        """The servo loop's position gain per step given to Bullet (see ``servo_bandwidth``)."""
        if self.servo_bandwidth is None:
            return self.position_gain
        return min(1.0, self.servo_bandwidth * self.time_step)

    def soft_contact(self, robot_mass: float) -> tuple[float, float, float] | None:
        """The Bullet contact values of ``contact_stiffness``: (stiffness, damping) of each robot link and the
        plate's damping, or None for rigid contacts.

        Bullet puts the two links' stiffnesses in series and adds their dampings, so each link gets twice
        the pair's stiffness and half its damping. The pair's damping c = 2 zeta sqrt(k m / 2) with zeta =
        -ln e / sqrt(pi^2 + ln^2 e) is that of a linear spring-dashpot whose rebound is the restitution e.
        The body-plate contact is then a spring of the link's stiffness (in series with a far stiffer plate)
        and the plate's damping makes it critically damped for one robot, so the robots rest on the plate
        instead of bouncing on it.
        """
        if self.contact_stiffness is None:
            return None
        k = self.contact_stiffness
        log_e = math.log(max(self.restitution, 1e-9))
        zeta = -log_e / math.hypot(math.pi, log_e)
        damping = 2.0 * zeta * math.sqrt(k * robot_mass / 2.0)
        link_stiffness, link_damping = 2.0 * k, damping / 2.0
        plate_damping = max(0.0, 2.0 * math.sqrt(link_stiffness * robot_mass) - link_damping)
        return link_stiffness, link_damping, plate_damping

    def link_frictions(self) -> tuple[float, float, float]:
        """Return the (arm link, body link, plate) lateral friction values given to Bullet.

        Bullet's contact friction is the product of the two colliding links' values, so these give
        arm-arm = friction_arm_arm (or friction_robot_robot), arm-body = friction_robot_robot and
        body-plate = friction_body_plate. Arms never touch the plate (arm_plate_collision False).
        """
        arm_arm = self.friction_robot_robot if self.friction_arm_arm is None else self.friction_arm_arm
        arm = math.sqrt(arm_arm)
        body = self.friction_robot_robot / arm if arm > 0.0 else 0.0
        plate = self.friction_body_plate / body if body > 0.0 else 0.0
        return arm, body, plate


def steps_per_tick(control_tick: float, time_step: float) -> int:
    """Return control_tick / time_step, or raise ConfigError (a ValueError) if not a whole number >= 1."""
    ratio = control_tick / time_step
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-6 * max(1.0, ratio):
        raise ConfigError(f'PhysicsConfig.control_tick: {control_tick!r} s is not a whole number of '
                          f'time steps of {time_step!r} s ({ratio:.6g} steps)')
    return n


#: Relative standard deviation of a robot's gait clock rate. The paper does not name the robots' board; an
#: Arduino-class board (ATmega328P) clocked by a ceramic resonator is assumed, as on the Arduino Pro Mini.
#: Ceramic resonators are specified to +-0.5 % initial tolerance (e.g. Murata CSTNE: +-0.5 %, plus up to
#: +-0.3 % over -40..85 C); read as a uniform spread over +-0.5 %, the sd is 0.5 % / sqrt(3) = 0.29 %. A
#: measured Arduino Uno's resonator-clocked ATmega ran at 15,959,622 Hz for 16 MHz (-0.25 %). A quartz
#: crystal (+-20-50 ppm) would give 100 times less.
CLOCK_RATE_SD = 0.005 / math.sqrt(3.0)
#: Servo timing jitter (s): a hobby servo takes a new target only with the next pulse of its 50 Hz PWM
#: frame (20 ms; the Arduino Servo library's REFRESH_INTERVAL is 20000 us, the Pololu Maestro's default
#: period 20 ms), so a command waits a uniform 0-20 ms before the servo acts on it.
SERVO_FRAME = 0.020
#: Relative standard deviation of the body-plate friction across the plate. No measurement of the plate
#: exists; the figure is the repeatability of a friction-coefficient test on one material pair (ASTM D2534:
#: two results differ by more than 0.06 in 1 case of 20, i.e. a single-result sd of 0.06 / 2.8 = 0.021,
#: 6 % of mu = 0.35).
FRICTION_SD = 0.06
#: Correlation length (m) of the friction field: an assumption (about one body width, 5.4 cm); nothing
#: about the plate's finish is measured.
FRICTION_LENGTH = 0.05
#: The friction field is clipped at this many standard deviations, so friction stays positive.
FRICTION_CLIP = 4.0
#: Upper bounds of the noise settings (beyond them the model does not mean what it says).
_NOISE_LIMITS = {'clock_rate_sd': 0.05, 'servo_jitter': 0.1, 'friction_sd': 1.0 / (FRICTION_CLIP + 1.0),
                 'friction_tolerance': 0.1}


@dataclass(frozen=True)
class NoiseConfig:
    """Noise with a cause: robot clocks, servo timing and plate friction, each seeded and zero on request.

    The dataclass defaults are the cited figures above (``NoiseConfig.paper()``); ``NoiseConfig.none()``
    switches every source off and gives exactly the noise-free trajectories. Draws come from the trial
    seed (``seed``, or the scene's seed when None) through their own random streams, so a seed places the
    robots the same with or without noise. docs/sim_core.md, "Noise with a cause".
    """

    #: Relative sd of each robot's gait clock rate: robot k's gait sees t0 + (t - t0) * (1 + eps_k),
    #: eps_k ~ Normal(0, clock_rate_sd) (clipped at 4 sd).
    clock_rate_sd: float = CLOCK_RATE_SD
    #: Each quarter's servo command goes out after a seeded delay, uniform in [0, servo_jitter] (s).
    servo_jitter: float = SERVO_FRAME
    #: Relative sd of the body-plate friction across the plate (a smooth seeded Gaussian random field).
    friction_sd: float = FRICTION_SD
    #: Correlation length (m) of the friction field: correlation exp(-d^2 / (2 friction_length^2)).
    friction_length: float = FRICTION_LENGTH
    #: A robot's friction is updated (once per control tick at most) when the field at its position differs
    #: from the applied value by more than this fraction of the mean friction.
    friction_tolerance: float = 0.002
    #: Seed of the noise draws; None: the scene's seed (0 if the scene has none).
    seed: int | None = None

    def __post_init__(self) -> None:
        require_non_negative(self, 'clock_rate_sd', 'servo_jitter', 'friction_sd', 'friction_tolerance',
                             error=ConfigError)
        require_positive(self, 'friction_length', error=ConfigError)
        for name, limit in _NOISE_LIMITS.items():
            if getattr(self, name) > limit:
                raise ConfigError(f'NoiseConfig.{name} must be at most {limit:g}, got {getattr(self, name)!r}'
                                  + (f' (the field is clipped at {FRICTION_CLIP:g} sd and friction must stay '
                                     'positive)' if name == 'friction_sd' else ''))
        if self.seed is not None and (isinstance(self.seed, bool) or not isinstance(self.seed, int)
                                      or self.seed < 0):
            raise ConfigError(f'NoiseConfig.seed must be None or an integer >= 0, got {self.seed!r}')

    @classmethod
    def none(cls) -> NoiseConfig:
        """Every source off: the noise-free model, bit for bit."""
        return cls(clock_rate_sd=0.0, servo_jitter=0.0, friction_sd=0.0)

    @classmethod
    def paper(cls) -> NoiseConfig:
        """The cited figures: resonator clocks, 50 Hz servo frames, friction test repeatability."""
        return cls()

    @property
    def enabled(self) -> bool:
        """True if any source is on."""
        return self.clock_rate_sd > 0.0 or self.servo_jitter > 0.0 or self.friction_sd > 0.0

    def trial_seed(self, scene_seed: int | None) -> int:
        """The seed of a trial's noise draws: ``seed``, else the scene's seed, else 0."""
        if self.seed is not None:
            return self.seed
        return 0 if scene_seed is None else int(scene_seed)


@dataclass(frozen=True)
class SimConfig:
    """Everything a Physics needs besides the scene: the robot spec, the physics settings, the noise and the
    diagnostics. Made by ``config_builder.build_config`` (a preset, overrides, noise, engine)."""

    robot: RobotSpec = SMALL
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    #: Noise with a cause; off by default (``NoiseConfig.none()``), see ``with_noise``.
    noise: NoiseConfig = field(default_factory=NoiseConfig.none)
    #: Knobs measured and not taken (``diagnostics.Diagnostics``); the default is the shipped model.
    diagnostics: Diagnostics = field(default_factory=Diagnostics)

    def __post_init__(self) -> None:
        """Refuse settings that cannot converge for this robot; warn about ones that converge poorly."""
        ph, spec = self.physics, self.robot
        self.diagnostics.check(spec, ph, self.noise.friction_sd)
        tip_travel = spec.servo_speed * spec.arm_length * ph.time_step     # arm tip per step at top speed
        if tip_travel >= spec.arm_thickness:
            raise ConfigError(f'PhysicsConfig.time_step: {ph.time_step:.6g} s lets an arm tip travel '
                              f'{1e3 * tip_travel:.2f} mm per step, more than the arm is thick '
                              f'({1e3 * spec.arm_thickness:.1f} mm): arms pass through each other; use at most '
                              f'{spec.arm_thickness / (spec.servo_speed * spec.arm_length):.3g} s')
        if 2.0 * tip_travel >= spec.arm_thickness:
            warnings.warn(f'PhysicsConfig.time_step: {ph.time_step:.6g} s lets two approaching arm tips close '
                          f'{2e3 * tip_travel:.2f} mm per step against a {1e3 * spec.arm_thickness:.1f} mm arm: '
                          'arms wedge and the results are not converged (docs/sim_calibration.md)',
                          NotConvergedWarning, stacklevel=3)
        if ph.ccd_swept_sphere_radius > spec.arm_thickness / 2.0:
            raise ConfigError(f'PhysicsConfig.ccd_swept_sphere_radius: {ph.ccd_swept_sphere_radius!r} m is larger '
                              f'than half the arm thickness ({spec.arm_thickness / 2.0:.4g} m); the swept sphere '
                              'must fit inside the arm')
        if ph.contact_stiffness is not None:
            omega_dt = math.sqrt(ph.contact_stiffness / (spec.total_mass / 2.0)) * ph.time_step
            if omega_dt > SOFT_CONTACT_MAX_OMEGA_DT:
                warnings.warn(f'PhysicsConfig.contact_stiffness: {ph.contact_stiffness:g} N/m at a '
                              f'{ph.time_step:.6g} s step is {omega_dt:.3f} rad of the contact spring per step; '
                              'Bullet integrates it implicitly and loses part of the rebound (about 10 % at 0.035, '
                              f'57 % at 0.35; keep it under {SOFT_CONTACT_MAX_OMEGA_DT}): the restitution set is not '
                              'the one given '
                              '(docs/sim_calibration.md, "Soft contacts")', NotConvergedWarning, stacklevel=3)
        if ph.servo_bandwidth is not None and ph.servo_bandwidth * ph.time_step > 0.5:
            warnings.warn(f'PhysicsConfig.servo_bandwidth: {ph.servo_bandwidth:g} /s at a {ph.time_step:.6g} s step '
                          f'is {ph.servo_bandwidth * ph.time_step:.2f} of the step; the servo converges only for '
                          'bandwidth x time_step <= 0.5 (docs/sim_calibration.md)', NotConvergedWarning,
                          stacklevel=3)

    def with_physics(self, **changes: Any) -> SimConfig:
        """Return a copy with some PhysicsConfig fields changed (validated)."""
        return replace(self, physics=replace(self.physics, **changes))

    def with_diagnostics(self, **changes: Any) -> SimConfig:
        """Return a copy with some Diagnostics fields changed (validated)."""
        return replace(self, diagnostics=replace(self.diagnostics, **changes))

    def with_noise(self, noise: NoiseConfig | None = None, **changes: Any) -> SimConfig:
        """Return a copy with ``noise`` (default: ``NoiseConfig.paper()``), some of its fields changed."""
        return replace(self, noise=replace(NoiseConfig.paper() if noise is None else noise, **changes))
