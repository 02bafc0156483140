"""The demo's two scenes as plain data: what each runs, why, its parameters, its batch run and its analysis.

Pure (no rclpy). ``smarticle_bringup.demo`` runs a scene through the lock-step ROS stack with the node
parameters ``node_params`` gives; ``tests/benchmarks/demo_seeds.py`` runs the same scene through the batch
core (``run_batch``: the same ``Runner``, gait cores and impact controller) on many seeds; both analyse the
poses with ``analyse`` and call a bound pair a glider by ``travelling`` (the glider analysis's definitions).

* ``GLIDERS``: two small robots at P5's start (r 1.3 BL, theta 330 deg, phi 180 deg, P5's seeded jitter),
  robot 1's gait a tenth of a period ahead of robot 0's, open loop. In this model two robots exactly in
  phase settle into a still, symmetric pair, while a pair 0.075-0.1 period apart glides 3-4 W per 100
  periods (docs/sim_calibration.md); the real robots' gaits drift apart in phase (the paper: "the phase
  drift in the gaits of glider-forming smarticle pairs during experiments"; resonator clocks of 0.29 % sd
  move two robots a tenth of a period apart in about 25 periods, docs/sim_core.md "Noise with a cause").
* ``FEEDBACK``: two robots of the paper's larger feedback robot (``smarticle_common.facts.FEEDBACK``, the
  robot the paper ran its tactile feedback on) at the colliding start of the P6 tests (side by side, robot 1
  a quarter period ahead), with the impact controller: the small robot's contacts stay below the shipped
  impact window, the feedback robot's enter it within the first period.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from smarticle_common.facts import GAIT_PERIOD, R_BIND_BL, RobotSpec
from smarticle_common.gait import GaitConfig
from smarticle_tracking.gliders import MIN_PERIODS, TRAVEL_MIN_W_PER_100

#: Sim time (s) at which the gaits start (the shared ``start_at`` of config/stack.yaml): period 0 begins here.
START_AT = 0.5
# The demo's words are the glider analysis's (``smarticle_tracking.gliders``, docs/gliders.md): a bound pair is
# bound (centre distance under ``R_BIND_BL`` in some frame of each period) for at least ``MIN_PERIODS`` periods in
# a row, a glider is a bound pair whose centre of mass travels at least ``TRAVEL_MIN_W_PER_100`` W per 100 periods.
#: Draws of the jittered start before giving up when the two robots overlap.
START_ATTEMPTS = 20


@dataclass(frozen=True)
class PairStart:
    """Pair coordinates of a start: r (BL), theta and phi (deg), and the two gaits' phases (periods)."""

    r_bl: float
    theta_deg: float
    phi_deg: float
    phases: tuple[float, float]


@dataclass(frozen=True)
class DemoScene:
    """One part of the demo: a pair of robots of one preset, its start, how long, with or without feedback."""

    key: str                          # 'gliders' or 'feedback': the output folder and the label
    title: str                        # one line: what the part shows
    preset: str                       # robot preset (``smarticle_common.facts.PRESETS``) or a preset file
    start: PairStart                  # the start before the seeded jitter
    jitter: tuple[float, float, float]   # uniform jitter of r (BL), theta, phi (deg): +- these
    periods: float                    # gait periods to run (the default)
    feedback: bool                    # run each robot's impact controller
    publish_period: float             # s: the sim bridge's publish period (poses, FSR sample, lock-step barrier)
    alpha_max_deg: float = 90.0

    @property
    def spec(self) -> RobotSpec:
        """The robot of this scene (of its preset file's overrides when ``preset`` is a preset file)."""
        from smarticle_sim.config_builder import build_config

        return build_config(self.preset).robot

    def gait(self) -> GaitConfig:
        """The gait of both robots (phase 0; each robot's phase is in ``start.phases``)."""
        return GaitConfig.from_degrees(self.alpha_max_deg, GAIT_PERIOD, self.spec.servo_speed)

    def start_for(self, seed: int) -> PairStart:
        """The seed's start: ``start`` plus seeded uniform jitter, the first draw whose robots do not overlap.

        Draw 0 is ``numpy.random.default_rng(seed).uniform(-1, 1, 3)``, the jitter of the experiments'
        pair starts (``smarticle-experiments run p5`` starts seed s where this starts it); a draw whose
        robots overlap is drawn again from ``default_rng([seed, attempt])``. SceneError if none fits.
        """
        from smarticle_sim.errors import SceneError

        for attempt in range(START_ATTEMPTS):
            u = np.random.default_rng([seed, attempt] if attempt else seed).uniform(-1.0, 1.0, size=3)
            start = replace(self.start, r_bl=self.start.r_bl + self.jitter[0] * float(u[0]),
                            theta_deg=self.start.theta_deg + self.jitter[1] * float(u[1]),
                            phi_deg=self.start.phi_deg + self.jitter[2] * float(u[2]))
            try:
                self._scene(start, seed)
            except SceneError:
                continue
            return start
        raise SceneError(f'demo scene {self.key}: no admissible start near {self.start} in {START_ATTEMPTS} '
                         f'draws for seed {seed}')

    def _scene(self, start: PairStart, seed: int) -> Any:
        from smarticle_sim.scenes import pair_scene

        return pair_scene(self.spec, self.gait(), start.r_bl, math.radians(start.theta_deg),
                          math.radians(start.phi_deg), phases=start.phases, seed=seed)

    def scene(self, seed: int) -> Any:
        """The ``smarticle_sim.scenes.Scene`` of the seed (what the sim bridge builds from ``bridge_params``)."""
        return self._scene(self.start_for(seed), seed)

    def bridge_params(self, seed: int) -> dict[str, Any]:
        """The sim bridge's parameters for this scene and seed (besides the launch file's)."""
        start = self.start_for(seed)
        return {'preset': self.preset, 'pair_r': start.r_bl, 'pair_theta_deg': start.theta_deg,
                'pair_phi_deg': start.phi_deg, 'pair_phase_0': start.phases[0], 'pair_phase_1': start.phases[1],
                'publish_period': self.publish_period, 'phase_jitter': 0.0}

    def robot_params(self, seed: int, clock_offsets: Sequence[float] | np.ndarray | None = None,
                     ) -> list[dict[str, Any]]:
        """Each robot's own gait and feedback parameters: its phase and, with ``clock_offsets``, its clock rate
        offset (``demo.write_params`` adds the preset's servo speed for the gait node)."""
        start = self.start_for(seed)
        own: list[dict[str, Any]] = []
        for k, phase in enumerate(start.phases):
            values: dict[str, Any] = {'phase': float(phase)}
            if clock_offsets is not None:
                values['clock_rate_offset'] = float(clock_offsets[k])
            own.append(values)
        return own

    def monitor_params(self) -> dict[str, Any]:
        """The live glider monitor's parameters: the analysis rule in this robot's body length."""
        bl = self.spec.body_length
        return {'min_periods': MIN_PERIODS, 'travel_min_w_per_100': TRAVEL_MIN_W_PER_100, 'body_length': bl,
                'r_bind': R_BIND_BL * bl}

    def glider_config(self) -> Any:
        """The glider analysis of the demo (``MIN_PERIODS``, ``R_BIND_BL``) in this robot's body length (= W)."""
        from smarticle_tracking.gliders import GliderConfig

        bl = self.spec.body_length
        return GliderConfig(period=GAIT_PERIOD, r_bind=R_BIND_BL * bl, min_periods=MIN_PERIODS,
                            body_length=bl, width=bl, travel_min_w_per_100=TRAVEL_MIN_W_PER_100)


GLIDERS = DemoScene(
    key='gliders',
    title='the phenomenon: two small robots glide (open loop, robot 1 a tenth of a period ahead)',
    preset='small', start=PairStart(1.3, 330.0, 180.0, (0.0, 0.1)), jitter=(0.04, 4.0, 4.0),
    periods=40.0, feedback=False, publish_period=0.05)

FEEDBACK = DemoScene(
    key='feedback',
    title='the controller: two feedback robots collide and the tactile feedback halts their arms',
    preset='feedback', start=PairStart(1.3, 0.0, 350.0, (0.0, 0.25)), jitter=(0.04, 4.0, 4.0),
    # one control tick: an FSR sample every tick, as the batch loop reads it, so the ROS run is the batch run
    periods=12.0, feedback=True, publish_period=1.0 / 60.0)

SCENES: dict[str, DemoScene] = {GLIDERS.key: GLIDERS, FEEDBACK.key: FEEDBACK}


@dataclass(frozen=True)
class BatchRun:
    """A scene run through the batch core: sample times (s after the gait start), poses (T, N, 3), arm
    angles (T, N, 2), halts (sim time after the gait start, robot, face) and the trouble text ('' if none)."""

    times: np.ndarray
    poses: np.ndarray
    arms: np.ndarray
    halts: list[tuple[float, int, str]]
    trouble: str


def feedback_config(phase: float, windows: dict[str, Any] | None = None) -> Any:
    """The impact controller's config for a robot of gait ``phase``: the feedback node's defaults with the
    shared windows of ``windows`` (face min/max/enabled and debounce, e.g. config/stack.yaml's ``/**``)."""
    from smarticle_feedback.parameters import PARAMS, config_from_values, default_values

    names = {spec.name for spec in PARAMS}
    shared = {k: v for k, v in (windows or {}).items() if k in names and k not in ('phase', 'robot_id')}
    return config_from_values(default_values(**shared, phase=phase))


def run_batch(scene: DemoScene, seed: int, periods: float | None = None, feedback: bool | None = None,
              windows: dict[str, Any] | None = None, clock_noise: bool = False) -> BatchRun:
    """Run ``scene`` for ``periods`` (default: the scene's) through the batch core, sampled at the sim
    bridge's publish period, with the impact controller when ``feedback`` (default: the scene's) and, with
    ``clock_noise``, each robot's gait clock off by the seed's draw of the cited spread (``./demo.sh
    --clock-noise`` gives the gait nodes the same draws)."""
    from smarticle_feedback.controller import ImpactController
    from smarticle_sim.batch import run_trial
    from smarticle_sim.config_builder import build_config
    from smarticle_sim.runner import FeedbackController
    from smarticle_sim.settings import CLOCK_RATE_SD

    config = build_config(scene.preset, noise={'clock_rate_sd': CLOCK_RATE_SD} if clock_noise else None)
    sim_scene = scene.scene(seed)
    use_feedback = scene.feedback if feedback is None else feedback
    controllers: list[FeedbackController] = []

    def add_feedback(_: Any, gaits: Any) -> list[FeedbackController]:
        if not use_feedback:
            return []
        policies = {}
        for k, robot in enumerate(sim_scene.robots):
            policy = ImpactController(feedback_config(robot.gait.phase, windows))
            policy.start(START_AT)
            policies[k] = policy
        controllers.append(FeedbackController(gaits, policies))
        return controllers

    every = max(1, round(scene.publish_period / config.physics.control_tick))
    recording = run_trial(config, sim_scene, scene.periods if periods is None else periods, sample_every=every,
                          controllers=add_feedback, start_time=START_AT)
    keep = recording.time >= START_AT - 1e-9
    halts = [(t - START_AT, k, face) for t, k, face in controllers[0].halts] if controllers else []
    return BatchRun(recording.time[keep] - START_AT, recording.poses[keep], recording.arm_angles[keep], halts,
                    recording.trouble)


def analyse(scene: DemoScene, times: np.ndarray, poses: np.ndarray) -> Any:
    """The glider analysis of a run of ``scene`` (times in s after the gait start, poses (T, N, 3))."""
    from smarticle_tracking.gliders import analyse_gliders

    return analyse_gliders(times, poses, scene.glider_config(), t0=0.0)


def travelling(glider: Any) -> bool:
    """Whether a bound pair of the analysis is a glider: it travels >= ``TRAVEL_MIN_W_PER_100`` W per 100 periods."""
    return bool(glider.is_glider)
