"""Speed benchmark: the Runner loop (gait cores, trouble checks, recording) against a bare PyBullet loop.

The bare loop is the reference of the speed figures, and the one loop over ``stepSimulation`` outside
``Runner``: it steps the same scene with corner targets at quarter boundaries and nothing else.

Every timing function takes a ``clock`` (default ``time.perf_counter``, wall time); on a machine shared
with other work, ``time.process_time`` (this process's CPU time; PyBullet DIRECT steps in-process on
one thread) gives steadier ratios.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

from .batch import run_trial, scene_period
from .quiet import pybullet
from .scenes import Scene
from .settings import SimConfig
from .physics import ARM_JOINTS, Physics
from .runner import GaitController, Runner

Clock = Callable[[], float]


@dataclass(frozen=True)
class BenchRow:
    """One benchmark measurement: best wall time over repeats for a mode."""

    mode: str
    steps: int
    seconds: float
    sim_seconds: float

    @property
    def steps_per_second(self) -> float:
        """Physics steps per wall-clock second."""
        return self.steps / self.seconds

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.sim_seconds / self.seconds


def bare_loop(config: SimConfig, scene: Scene, periods: float,
              clock: Clock = time.perf_counter) -> tuple[int, float]:
    """Step the same scene with raw stepSimulation calls and corner targets sent at quarter boundaries."""
    with Physics(config, scene) as physics:
        c = physics.client
        period = scene_period(scene)
        steps = round(periods * period / config.physics.time_step)
        quarter_steps = round(period / 4.0 / config.physics.time_step)
        speed, torque = config.robot.servo_speed, config.robot.servo_torque
        gain = config.physics.position_gain
        schedule = []
        for placement in scene.robots:
            assert placement.gait is not None
            q0 = math.floor(4.0 * placement.gait.phase)
            schedule.append([placement.gait.corner(q0 + q + 1) for q in range(4)])
        step = c.stepSimulation
        start = clock()
        for i in range(steps):
            if i % quarter_steps == 0:
                q = (i // quarter_steps) % 4
                for body, corners in zip(physics.body_ids, schedule, strict=True):
                    for j in ARM_JOINTS:
                        c.setJointMotorControl2(body, j, pybullet.POSITION_CONTROL,
                                                targetPosition=corners[q][j], force=torque,
                                                maxVelocity=speed, positionGain=gain)
            step()
        return steps, clock() - start


def runner_loop(config: SimConfig, scene: Scene, periods: float,
               clock: Clock = time.perf_counter) -> tuple[int, float]:
    """Run the Runner's tick loop (gait cores, command on change, trouble checks), no recording."""
    with Physics(config, scene) as physics:
        gaits = GaitController.for_scene(physics)
        runner = Runner(physics, [gaits])
        ticks = runner.ticks_for(periods * scene_period(scene))
        gaits.start(0.0)
        start = clock()
        runner.run(ticks)
        return physics.step_count, clock() - start


def batch_loop(config: SimConfig, scene: Scene, periods: float, sample_every: int | None = None,
               record_fsr: bool = False, clock: Clock = time.perf_counter) -> tuple[int, float]:
    """Run a recorded batch trial and time it (world construction included).

    ``sample_every`` None is the batch default (about 20 Hz); ``record_fsr`` records FSR and contacts.
    """
    start = clock()
    rec = run_trial(config, scene, periods, sample_every=sample_every, record_fsr=record_fsr,
                    record_contacts=record_fsr)
    seconds = clock() - start
    return round(rec.time[-1] / config.physics.time_step), seconds


def benchmark(config: SimConfig, scene: Scene, periods: float = 10.0, repeats: int = 3,
              clock: Clock = time.perf_counter) -> list[BenchRow]:
    """Time every mode ``repeats`` times, interleaved, and keep each mode's best run."""
    modes = {
        'bare pybullet loop': lambda: bare_loop(config, scene, periods, clock),
        'Runner.run (gaits, trouble checks)': lambda: runner_loop(config, scene, periods, clock),
        'batch default (poses at 20 Hz, no FSR)': lambda: batch_loop(config, scene, periods, clock=clock),
        'batch, poses every tick, no FSR': lambda: batch_loop(config, scene, periods, 1, False, clock),
        'batch, poses+FSR+contacts at 20 Hz': lambda: batch_loop(config, scene, periods, None, True, clock),
        'batch, poses+FSR+contacts every tick': lambda: batch_loop(config, scene, periods, 1, True, clock),
    }
    best: dict[str, tuple[int, float]] = {}
    for _ in range(repeats):
        for name, fn in modes.items():
            steps, seconds = fn()
            if name not in best or seconds < best[name][1]:
                best[name] = (steps, seconds)
    dt = config.physics.time_step
    return [BenchRow(name, steps, seconds, steps * dt) for name, (steps, seconds) in best.items()]


def format_table(rows: list[BenchRow]) -> str:
    """Render benchmark rows as a Markdown table with the overhead against the first row."""
    base = rows[0].steps_per_second
    lines = ['| mode | steps/s | x real time | vs bare loop |', '| --- | ---: | ---: | ---: |']
    for row in rows:
        lines.append(f'| {row.mode} | {row.steps_per_second:,.0f} | {row.real_time_factor:.1f} | '
                     f'{100.0 * (row.steps_per_second / base - 1.0):+.1f} % |')
    return '\n'.join(lines)
