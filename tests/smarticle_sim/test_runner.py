"""The one stepping loop: controller order, observer hooks, early stop, and the feedback controller."""

from __future__ import annotations

import math

import numpy as np
import pytest
from smarticle_common.gait import GaitConfig

from smarticle_sim.batch import run_trial
from smarticle_sim.physics import Physics
from smarticle_sim.runner import FeedbackController, GaitController, Hook, Runner
from smarticle_sim.scenes import RobotPlacement, Scene, dense_scene
from smarticle_sim.settings import SimConfig


def lone(gait: GaitConfig) -> Scene:
    """One robot at the corner c0 of ``gait``."""
    a = gait.alpha_max
    return Scene((RobotPlacement(0.0, 0.0, math.pi / 2, a, a, gait),), name='lone')


class Recorder:
    """A controller that writes down the time of every call."""

    def __init__(self, log: list[tuple[str, float]], name: str) -> None:
        self.log, self.name = log, name

    def before_tick(self, runner: Runner) -> None:
        self.log.append((self.name, runner.time))


def test_controllers_act_in_order_before_each_step(config: SimConfig, gait90: GaitConfig) -> None:
    log: list[tuple[str, float]] = []
    with Runner.with_gaits(config, lone(gait90), before=[Recorder(log, 'a'), Recorder(log, 'b')]) as run:
        run.run(3)
        dt = run.physics.control_tick
        assert log == [('a', 0.0), ('b', 0.0), ('a', dt), ('b', dt), ('a', 2 * dt), ('b', 2 * dt)]
        assert run.tick_count == 3
        assert run.physics.step_count == 3 * run.physics.steps_per_tick


def test_hooks_run_at_start_and_every_k_ticks_and_stop_ends_early(config: SimConfig, gait90: GaitConfig) -> None:
    with Runner.with_gaits(config, lone(gait90)) as run:
        seen: list[int] = []
        later: list[int] = []
        done = run.run(10, [Hook(3, lambda r: seen.append(r.tick_count)),
                            Hook(4, lambda r: later.append(r.tick_count), at_start=False)],
                       stop=lambda r: r.tick_count >= 7)
        assert done == 7
        assert seen == [0, 3, 6]
        assert later == [4]
        with pytest.raises(ValueError, match='every'):
            run.run(1, [Hook(0, lambda r: None)])


class HaltOnce:
    """A feedback policy that asks for a halt at its first sample at or after ``at``."""

    def __init__(self, at: float) -> None:
        self.at, self.done = at, False

    class _Decision:
        def __init__(self, halt: bool) -> None:
            self.halt, self.face = halt, 'arm1_front' if halt else None

    def update(self, time: float, forces: np.ndarray) -> HaltOnce._Decision:
        assert forces.shape == (4,)
        fire = time >= self.at and not self.done
        self.done = self.done or fire
        return self._Decision(fire)


def test_a_halt_is_part_of_the_tick_it_was_decided_in(config: SimConfig, gait90: GaitConfig) -> None:
    """The arms hold from the tick of the halt: the gait controller (after it) sends no new target."""
    with Physics(config, lone(gait90)) as physics:
        gaits = GaitController.for_scene(physics)
        feedback = FeedbackController(gaits, {0: HaltOnce(0.2)})
        run = Runner(physics, [feedback, gaits])
        gaits.start(0.0)
        run.run(run.ticks_for(0.25))
        assert len(feedback.halts) == 1
        t_halt, robot, face = feedback.halts[0]
        assert robot == 0 and face == 'arm1_front'
        assert t_halt == pytest.approx(0.2, abs=physics.control_tick)
        held = physics.arm_angles()[0].copy()
        run.run(run.ticks_for(0.5))                 # the rest of the period: nothing moves
        assert physics.arm_angles()[0] == pytest.approx(held, abs=0.03)


def test_a_policy_reads_its_robots_own_clock(config: SimConfig, gait90: GaitConfig) -> None:
    """With clock-rate noise the feedback policy gets the robot's gait clock, the time its gait runs on."""
    seen: list[float] = []

    class Watch(HaltOnce):
        def update(self, time: float, forces: np.ndarray) -> HaltOnce._Decision:
            seen.append(time)
            return super().update(time, forces)

    with Physics(config, lone(gait90)) as physics:
        gaits = GaitController(physics, [gait90], clock_rates=[0.25])
        run = Runner(physics, [FeedbackController(gaits, {0: Watch(99.0)}), gaits])
        gaits.start(0.2)
        run.run(run.ticks_for(1.0))
        ticks = np.arange(len(seen)) * physics.control_tick   # sim time of each tick
        assert np.allclose(seen, 0.2 + (ticks - 0.2) * 1.25)   # the board clock from the start at 0.2 s


def test_batch_trial_with_extra_controllers_is_deterministic(config: SimConfig, gait90: GaitConfig) -> None:
    scene = dense_scene(config.robot, gait90, 3, seed=4)
    halts: list[list[tuple[float, int, str]]] = []

    def feedback(physics: Physics, gaits: GaitController) -> list[FeedbackController]:
        controller = FeedbackController(gaits, {1: HaltOnce(0.5)})
        halts.append(controller.halts)
        return [controller]

    first = run_trial(config, scene, 1.0, controllers=feedback)
    second = run_trial(config, scene, 1.0, controllers=feedback)
    plain = run_trial(config, scene, 1.0)
    assert np.array_equal(first.poses, second.poses) and np.array_equal(first.arm_angles, second.arm_angles)
    assert halts[0] == halts[1] and len(halts[0]) == 1
    assert not np.array_equal(first.arm_angles, plain.arm_angles)   # the halt changed the run


def test_step_hooks_see_every_physics_step_of_the_same_trajectory(config: SimConfig, gait90: GaitConfig) -> None:
    scene = dense_scene(config.robot, gait90, 2, seed=1)
    with Runner.with_gaits(config, scene) as plain, Runner.with_gaits(config, scene) as watched:
        steps: list[float] = []
        watched.step_hooks.append(lambda r: steps.append(r.time))
        for run in (plain, watched):
            assert run.gaits is not None
            run.gaits.start(0.0)
            run.run(run.ticks_for(1.0))
        assert np.array_equal(plain.physics.poses(), watched.physics.poses())
        assert len(steps) == watched.physics.step_count
        assert steps[0] == pytest.approx(config.physics.time_step)
