"""The guide's test (docs/own_controller.md): the example controller in the simulation, over real DDS."""

import numpy as np

from smarticle_sim.testing import SimWorld

CONTROLLER = 'smarticle_example_controller/square_stop'
STOP_FORCE = 0.5   # N: the controller's default stop_force, which the test leaves as it is


def test_the_robots_walk_and_a_robot_stops_after_a_hard_contact(sim_world: SimWorld) -> None:
    sim_world.start(scene='pair', seed=1, controller=CONTROLLER, fsr=True, joint_states=True,
                    controller_params={'amplitude_deg': 60.0})
    sim_world.step_to(4.0)

    # the pair moved
    assert np.linalg.norm(sim_world.poses(4.0)[:, :2] - sim_world.poses(0.0)[:, :2]) > 0.0
    stopped = 0
    for robot in (0, 1):
        forces = sim_world.fsr(robot)
        arms = sim_world.joint_states(robot)
        hard = [stamp for stamp, sample in sorted(forces.items()) if sample.max() > STOP_FORCE]
        if not hard:
            continue
        stopped += 1
        # from half a second after the first hard contact on, the arms stay where the gait stopped
        later = np.array([angles for stamp, angles in arms.items() if stamp > hard[0] + 500_000_000])
        assert len(later) > 0 and np.ptp(later, axis=0).max() < 0.05, robot
        assert 'stopped at' in sim_world.output(f'/smarticle_{robot}/square_stop')
    assert stopped >= 1, 'no robot touched the other hard enough: the test would show nothing'
    # the bridge saw no bad command from the controller
    assert sim_world.counters().get('nonfinite_targets', 0) == 0
