"""The one stepping loop: a ``Runner`` owns the tick, its controllers, trouble checks and observer hooks.

Modelled on dm_control's ``rl/control.py``: the physics, any ``engine.Engine`` (dm_control's abstract
``Physics``: Bullet's ``physics.Physics`` or MuJoCo's ``mujoco_engine.MujocoPhysics``), knows bodies, joints,
contacts and sensors; what acts on the robots is a *controller* plugged into the runner; the runner's
``tick`` is the only place that steps the physics:

1. the plate's friction field, if the physics has one (``Engine.update_plate_friction``);
2. every controller's ``before_tick(runner)``, in the order given (e.g. the feedback controller, whose
   halts the gait controller then respects, before the gait controller);
3. ``physics.step(steps_per_tick)``;
4. a trouble check every ``trouble_every`` ticks (``SimTrouble`` propagates to the caller).

``Runner.run`` adds observer hooks (sampling, progress) called every k ticks, and an early stop.
The batch trial (``batch.run_trial``), the sim bridge (``bridge.SimBridgeCore``), the experiments and
the benchmarks all step through it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from smarticle_common.gait import GaitConfig, SquareGait, TIME_EPS, board_time

from .errors import ConfigError
from .engine import Engine, EngineFactory, FsrReading
from .noise import ServoDelays, clock_rates
from .physics import Physics
from .scenes import Scene
from .settings import SimConfig


class Controller(Protocol):
    """Anything that acts on the robots once per control tick, before the physics steps."""

    def before_tick(self, runner: Runner) -> None:
        """Read sensors from ``runner.physics`` and send commands (the time is ``runner.time``)."""


@dataclass(frozen=True)
class Hook:
    """An observer called every ``every`` ticks of ``Runner.run`` (and before the first tick if ``at_start``)."""

    every: int
    call: Callable[[Runner], None]
    at_start: bool = True


class Runner:
    """Steps an engine (``engine.Engine``) one control tick at a time with its controllers and trouble checks."""

    def __init__(self, physics: Engine, controllers: Sequence[Controller] = ()) -> None:
        self.physics = physics
        self.controllers: list[Controller] = list(controllers)
        #: The gait controller among ``controllers``, when built by ``with_gaits``.
        self.gaits: GaitController | None = None
        #: Observers of every physics step (instruments that need each step, e.g. collision impulses); with
        #: any, a tick steps the physics one step at a time, which gives the same trajectory.
        self.step_hooks: list[Callable[[Runner], None]] = []
        self.tick_count = 0
        self._steps_per_tick = physics.steps_per_tick
        self._trouble_every = physics.config.physics.trouble_every
        self._friction = physics.update_plate_friction if physics.friction_field is not None else None

    @classmethod
    def with_gaits(cls, config: SimConfig, scene: Scene, before: Sequence[Controller] = (),
                   engine: EngineFactory | None = None) -> Runner:
        """A new world of ``scene`` (``engine``'s; default Bullet's ``Physics``) stepped with each robot's gait
        (``runner.gaits``), after ``before``."""
        physics = (engine or Physics)(config, scene)
        gaits = GaitController.for_scene(physics)
        runner = cls(physics, [*before, gaits])
        runner.gaits = gaits
        return runner

    @property
    def time(self) -> float:
        """Sim time (s)."""
        return self.physics.time

    def tick(self) -> None:
        """One control tick: controllers act, the physics steps, every few ticks a trouble check."""
        if self._friction is not None:
            self._friction()
        for controller in self.controllers:
            controller.before_tick(self)
        if self.step_hooks:
            for _ in range(self._steps_per_tick):
                self.physics.step(1)
                for hook in self.step_hooks:
                    hook(self)
        else:
            self.physics.step(self._steps_per_tick)
        self.tick_count += 1
        if self.tick_count % self._trouble_every == 0:
            self.physics.check_trouble()

    def run(self, ticks: int, hooks: Sequence[Hook] = (), stop: Callable[[Runner], bool] | None = None) -> int:
        """Run up to ``ticks`` ticks with observer ``hooks``; return the ticks run (fewer if ``stop`` said so).

        A hook with ``at_start`` is called once before the first tick; then each hook is called after
        every ``hook.every``-th tick of this run. ``stop`` is asked after every tick (and its hooks).
        ``SimTrouble`` propagates: what the hooks have seen so far is the caller's to keep.
        """
        for hook in hooks:
            if hook.every < 1:
                raise ValueError(f'Hook.every must be >= 1 tick, got {hook.every!r}')
            if hook.at_start:
                hook.call(self)
        tick = self.tick
        for i in range(1, ticks + 1):
            tick()
            for hook in hooks:
                if i % hook.every == 0:
                    hook.call(self)
            if stop is not None and stop(self):
                return i
        return ticks

    def ticks_for(self, seconds: float) -> int:
        """Number of control ticks in ``seconds`` of sim time (rounded)."""
        return self.physics.ticks_for(seconds)

    def close(self) -> None:
        """Close the physics (idempotent)."""
        self.physics.close()

    def __enter__(self) -> Runner:
        """Context manager: the physics closes on exit."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Close the physics."""
        self.close()


class GaitController:
    """Runs each robot's square gait core: new servo targets at quarter boundaries, after a start or halt.

    A gait core is asked for a command only when its quarter has ended (or it was started or halted),
    so most ticks cost one comparison. Robots without a gait config take no commands from here.

    Noise (``settings.NoiseConfig``, drawn by ``for_scene``): with ``clock_rates`` robot k's gait core
    reads its own clock, t0 + (t - t0) * (1 + eps_k) from the shared start t0, so its quarters end every
    T / 4 / (1 + eps_k) of sim time; with ``servo_jitter`` each quarter's command goes to the servos at
    the quarter boundary plus a seeded delay in [0, servo_jitter] (at the first control tick from then on).
    A command that went out is never re-timed; a halt drops a command still waiting and holds at once.
    """

    def __init__(self, physics: Engine, gaits: Sequence[GaitConfig | None],
                 clock_rates: Sequence[float] | np.ndarray | None = None, servo_jitter: float = 0.0,
                 seed: int = 0) -> None:
        n = len(gaits)
        if n != physics.n_robots:
            raise ValueError(f'GaitController: {n} gait configs for {physics.n_robots} robots')
        self.physics = physics
        self._gaits: list[SquareGait | None] = [SquareGait(g) if g is not None else None for g in gaits]
        self._next_update = np.full(n, math.inf)
        self._next_due = math.inf   # min of _next_update (or earlier): most ticks need no gait work
        eps = np.zeros(n) if clock_rates is None else np.asarray(clock_rates, dtype=float)
        if eps.shape != (n,) or not np.all(np.isfinite(eps)) or np.any(eps <= -0.5) or np.any(eps >= 0.5):
            raise ConfigError(f'GaitController: clock_rates must be {n} finite offsets in (-0.5, 0.5), got {eps!r}')
        #: Each robot's gait clock rate 1 + eps_k (1.0: the sim clock).
        self.clock_rates: tuple[float, ...] = tuple(float(1.0 + e) for e in eps)
        quarters = [g.period / 4.0 for g in gaits if g is not None]
        if not (math.isfinite(servo_jitter) and 0.0 <= servo_jitter < min(quarters, default=math.inf)):
            raise ConfigError(f'NoiseConfig.servo_jitter must be >= 0 s and shorter than a quarter period '
                              f'({min(quarters, default=math.inf):g} s), got {servo_jitter!r}')
        self._delays = ServoDelays(servo_jitter, n, seed) if servo_jitter > 0.0 else None
        self._pending: list[tuple[tuple[float, float], float] | None] = [None] * n
        self._pending_at = np.full(n, math.inf)   # sim time a delayed command goes out

    @classmethod
    def for_scene(cls, physics: Engine) -> GaitController:
        """A controller running the gait each robot of the physics' scene was placed with (and its noise)."""
        noise = physics.config.noise
        seed = noise.trial_seed(physics.scene.seed)
        return cls(physics, [r.gait for r in physics.scene.robots],
                   clock_rates(noise, physics.n_robots, seed), noise.servo_jitter, seed)

    def local_time(self, robot: int, t: float) -> float:
        """Robot ``robot``'s gait clock at sim time ``t`` (the sim time itself before a start)."""
        gait = self._gaits[robot]
        return t if gait is None else board_time(t, gait.start_time, self.clock_rates[robot])

    def pending(self, robot: int) -> float | None:
        """Sim time at which ``robot``'s delayed command goes out, or None if none is waiting."""
        at = float(self._pending_at[self.physics.check_robot(robot)])
        return None if math.isinf(at) else at

    def _sim_time(self, robot: int, local: float) -> float:
        """Sim time at which robot ``robot``'s gait clock reads ``local`` (after a start)."""
        start, rate = self._gaits[robot].start_time, self.clock_rates[robot]  # type: ignore[union-attr]
        return local if rate == 1.0 else start + (local - start) / rate  # type: ignore[operator]

    def gait(self, robot: int) -> SquareGait | None:
        """The gait core driving ``robot``, or None if it takes no gait commands."""
        return self._gaits[self.physics.check_robot(robot)]

    def start(self, t0: float | None = None, robots: Sequence[int] | None = None) -> None:
        """Start the gait cores (all, or ``robots``) at sim time ``t0`` (default: now)."""
        start = self.physics.time if t0 is None else float(t0)
        for k in self.physics.robot_list(robots):
            gait = self._gaits[k]
            if gait is not None:
                gait.start(start)
                self._next_update[k] = start
                self._next_due = min(self._next_due, start)
                self._pending[k] = None
                self._pending_at[k] = math.inf

    def halt(self, robot: int) -> bool:
        """Halt ``robot``'s gait now (arms hold; resume at its next period); False if not running.

        The arms hold at the gait's own hold command (its reference angles at the halt, from which it
        resumes), sent at once: the command the gait node sends a board or the sim bridge after a halt,
        so the batch and ROS paths hold at the same angles.
        """
        k = self.physics.check_robot(robot)
        gait = self._gaits[k]
        now = self.physics.time
        # the halt's time to the nanosecond, as a message stamp carries it: a halt in mid-stroke holds at the
        # angle of that time, so the ROS path (whose gait node sees stamps) holds at the same angle bit for bit
        local = self.local_time(k, round(now * 1e9) * 1e-9)
        if gait is None or not gait.halt(local):
            return False
        self._pending[k] = None   # a command still waiting for its servo frame never goes out
        self._pending_at[k] = math.inf
        hold = gait.command(self.local_time(k, now) + TIME_EPS)   # now + 1 ns is after the halt's rounded time
        self.physics.send(k, hold.targets, hold.speed)
        self._next_update[k] = now
        self._next_due = min(self._next_due, now)
        return True

    def before_tick(self, runner: Runner) -> None:
        """Ask the gait cores whose quarter has ended (or that were started or halted) for new targets."""
        physics = self.physics
        now = physics.time
        if now + TIME_EPS < self._next_due:
            return
        delays = self._delays
        if delays is not None:
            for k in np.flatnonzero(self._pending_at <= now + TIME_EPS):
                targets, speed = self._pending[k]  # type: ignore[misc]
                physics.send(int(k), targets, speed)
                self._pending[k] = None
                self._pending_at[k] = math.inf
        due = np.flatnonzero(self._next_update <= now + TIME_EPS)
        for k in due:
            gait = self._gaits[k]
            if gait is None:
                self._next_update[k] = math.inf
                continue
            t = max(now, gait.start_time if gait.start_time is not None else now)
            t = self.local_time(int(k), t)
            command = gait.command(t + TIME_EPS)
            if not command.halted:  # a halted robot keeps holding the angles it had when it stopped
                if delays is None:
                    physics.send(int(k), command.targets, command.speed)
                else:
                    at = float(self._next_update[k]) + delays.draw(int(k))   # the quarter boundary + delay
                    if at <= now + TIME_EPS:
                        physics.send(int(k), command.targets, command.speed)
                    else:
                        self._pending[k] = (command.targets, command.speed)
                        self._pending_at[k] = at
            tau = gait.gait_time(t + TIME_EPS)
            next_tau = (math.floor(4.0 * tau) + 1) / 4.0
            cfg = gait.config
            boundary = gait.start_time + (next_tau - cfg.phase) * cfg.period  # type: ignore[operator]
            self._next_update[k] = self._sim_time(int(k), boundary)
        self._next_due = float(self._next_update.min())
        if delays is not None:
            self._next_due = min(self._next_due, float(self._pending_at.min()))


class Decision(Protocol):
    """What a feedback policy answers for one FSR sample."""

    @property
    def halt(self) -> bool:
        """True to stop the arms now."""

    @property
    def face(self) -> str | None:
        """The FSR face that triggered the halt, if any."""


class FeedbackPolicy(Protocol):
    """A per-robot tactile policy (e.g. ``smarticle_feedback.controller.ImpactController``)."""

    def update(self, time: float, forces: Sequence[float], /) -> Decision:
        """Take one FSR sample (forces in N, faces in ``FSR_FACES`` order) at sim ``time``."""


class FeedbackController:
    """Feeds every tick's FSR forces to per-robot policies; a halt decision halts that robot's gait.

    Put it before the ``GaitController`` in the runner's controllers, so that a halt is part of the tick
    it was decided in. Halts that took effect are listed in ``halts`` as (time, robot, face). Each policy
    is given its robot's gait clock (``GaitController.local_time``), the sim time unless clock-rate noise
    is on, so its gait periods are the gait's.

    With ``peak_hold`` (the default) a tick's FSR sample is the largest force of each face over the physics
    steps since the previous sample (a step hook on the runner; each step's reading is the force averaged
    over ``PhysicsConfig.fsr_window``, ``physics.FsrReading``), not the force at the tick's instant:
    robot-robot collisions are kicks of a few milliseconds, shorter than a 1/60 s control tick, and an
    instantaneous read would see most of them as zero. A real FSR read through a divider and the servo
    board's ADC sees a kick stretched by the sensor's elastomer and the analogue input's filter; the peak
    of the interval is the sim's stand-in for it (docs/feedback.md). Without ``peak_hold``: the instant.
    """

    def __init__(self, gaits: GaitController, policies: Mapping[int, FeedbackPolicy], peak_hold: bool = True,
                 record: bool = False) -> None:
        self.gaits = gaits
        self.policies = dict(policies)
        self._robots = sorted(self.policies)
        self.halts: list[tuple[float, int, str]] = []
        self.peak_hold = peak_hold
        self._reading: FsrReading | None = None   # with peak_hold: built at the first tick
        #: With ``record``: every sample given to the policies, as (time, forces (robots, 4)).
        self.samples: list[tuple[float, np.ndarray]] | None = [] if record else None

    def _on_step(self, runner: Runner) -> None:
        self._reading.step()  # type: ignore[union-attr]   # attached only once the reading exists

    def before_tick(self, runner: Runner) -> None:
        """Read the FSR forces of the policies' robots and halt where a policy says so."""
        physics = self.gaits.physics
        now = physics.time
        if self.peak_hold and self._reading is None:
            self._reading = FsrReading(physics, self._robots)
            runner.step_hooks.append(self._on_step)
        peak = self._reading.take_peak() if self._reading is not None else None
        forces = physics.fsr(self._robots) if peak is None else peak
        if self.samples is not None:
            self.samples.append((now, np.array(forces)))
        for row, k in enumerate(self._robots):
            # the policy keeps the robot's own time, as its gait does (the same board clock; with clock-rate
            # noise the two would otherwise disagree on where a gait period begins)
            decision = self.policies[k].update(self.gaits.local_time(k, now), forces[row])
            if decision.halt and self.gaits.halt(k):
                self.halts.append((now, k, decision.face or ''))


class ContactPeriods:
    """A controller that only watches: for every pair of robots, the gait periods in which they touched at
    any physics step (``periods[(i, j)]``, i < j; periods counted from ``start_time``).

    Touching is ``Physics.touching(max_distance)``: by default contact points at zero or negative distance,
    not the points Bullet keeps within its contact margin (``math.inf`` counts those too).
    """

    def __init__(self, period: float, start_time: float = 0.0, max_distance: float = 0.0) -> None:
        self.period, self.start_time, self.max_distance = period, start_time, max_distance
        self.periods: dict[tuple[int, int], set[int]] = {}
        self._attached = False

    def _on_step(self, runner: Runner) -> None:
        pairs = runner.physics.touching(self.max_distance)
        if pairs:
            q = math.floor((runner.time - self.start_time) / self.period)
            for key in pairs:
                self.periods.setdefault(key, set()).add(q)

    def before_tick(self, runner: Runner) -> None:
        """Attach the step hook at the first tick."""
        if not self._attached:
            runner.step_hooks.append(self._on_step)
            self._attached = True
