"""The hardware path over DDS and a real pty: an FSR impact on the emulated board halts the servos until the
next gait period (servo_bridge, gait and feedback as separate processes; behaviour, not wall-clock time)."""

from __future__ import annotations

import os
import re
import signal
import time
from pathlib import Path
from typing import Any

from smarticle_feedback.parameters import DEFAULT_WINDOWS
from tests.helpers.ros import spin_until
from tests.helpers.fake_board import running_emulator

from tests.helpers.hardware_rig import HardwareRig

PERIOD = 0.8
#: A C2 start whose batch run halts robot 0 in several periods (1-4 of 5) at the shipped windows.
SEED = 2


def test_an_fsr_impact_holds_the_emulated_servos_until_the_next_period(nodes: Any, ros_node: Any,
                                                                        tmp_path: Path) -> None:
    with running_emulator(tmp_path / 'maestro') as emulator:
        probe = ros_node('feedback_hw_probe')
        rig = HardwareRig(nodes, emulator, probe, period=PERIOD, alpha_max_deg=45.0)
        logs = rig.logs
        assert spin_until(probe, rig.ready, 20.0), logs()
        t0 = rig.start(1.0)
        # during period 2's first quarter arm 1 strokes from +45 to -45 degrees (0.15 s of a 0.2 s quarter)
        spin_until(probe, lambda: time.time() >= rig.period_start(2) + 0.04, 10.0)
        # inside the shipped window [7.37, 15.07] N; held 80 ms (8 of the bridge's 10 ms reads), not 30: with the
        # whole suite running, the bridge process can stall past a 30 ms press and never read it. One halt per
        # period, so the longer press still halts once, mid-stroke (period 2 + 0.04-0.12 s)
        rig.pulse('arm1_front', 11.0, duration=0.08)
        assert spin_until(probe, lambda: len(rig.observed.halts) >= 1, 5.0), logs()
        spin_until(probe, lambda: time.time() >= rig.period_start(3) + PERIOD / 2, 10.0)

        stamp, _, face = rig.observed.halts[0]
        assert face == 'arm1_front'
        assert rig.period_start(2) <= stamp < rig.period_start(2) + 0.2, (stamp - t0)
        hold = rig.targets_between(stamp, rig.period_start(3) - 0.05)
        assert [r.channel for r in hold] == [0], f'one hold Set Target on arm 1, got {hold}'
        corners = {1500.0 + 600.0 * a for a in (-0.7853981, 0.7853981)}
        assert all(abs(hold[0].pulse_us - c) > 5.0 for c in corners), 'the hold target lies between the corners'
        # arm 1 resumes in the next period: its first target after the hold reaches the board (the emulator's own
        # record) no earlier than the period's start and within its first half; the gait sends it at the start, and
        # on a loaded machine the bridge's forwarding can take well over 100 ms
        after = [r for r in rig.targets_between(stamp, rig.period_start(3) + PERIOD / 2) if r.channel == 0][1:]
        assert after, f'arm 1 resumes in the next period; after the hold: {rig.targets_between(stamp, time.time())}'
        assert rig.period_start(3) - 0.05 <= rig.wall(after[0]) < rig.period_start(3) + PERIOD / 2, (
            rig.wall(after[0]) - rig.period_start(3))
        assert len(rig.observed.halts) == 1, 'one impact, one halt'


def test_the_feedback_node_refuses_an_inverted_window(nodes: Any) -> None:
    proc = nodes.start('feedback', '--ros-args', '-p', 'arm2_back_min:=5.0', '-p', 'arm2_back_max:=1.0')
    assert proc.wait(timeout=20) == 2
    assert 'f_min (5 N) is above f_max (1 N)' in nodes.output(proc)


def test_impact_windows_change_at_once_and_bad_changes_are_refused(nodes: Any, ros_node: Any) -> None:
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Header
    from smarticle_common import topics

    from tests.helpers.params import get_parameter, set_parameter

    feedback = nodes.start('feedback', '--ros-args', '-r', '__ns:=/smarticle_5', '-p', 'start_at:=0.0',
                           '-p', 'period:=1.0')
    probe = ros_node('feedback_params_probe')
    halts: list[Any] = []
    probe.create_subscription(Header, topics.topic('halt', 5), halts.append, topics.qos_profile(topics.Qos.COMMAND))
    fsr = probe.create_publisher(JointState, topics.topic('fsr', 5), topics.qos_profile(topics.Qos.SENSOR))
    assert spin_until(probe, lambda: fsr.get_subscription_count() >= 1, 20.0)
    spin_until(probe, lambda: False, 0.5)                # the subscriber's side of the match

    def press(t: float, newtons: float) -> int:
        """One sample at time t (its own gait period) with arm1_front at ``newtons``; the halts so far."""
        msg = JointState(name=list(topics.FSR_FACES), effort=[newtons, 0.0, 0.0, 0.0])
        msg.header.stamp.sec = int(t)
        fsr.publish(msg)
        spin_until(probe, lambda: False, 0.4)
        return len(halts)

    target = '/smarticle_5/feedback'
    assert press(10.0, 11.0) == 1                          # inside the default window [7.37, 15.07] N
    for name, value, reason in (('arm1_front_min', 25.0, 'above f_max'), ('arm1_front_max', -1.0, 'out of range'),
                                ('period', 2.0, 'read-only'), ('robot_id', 3, 'read-only')):
        ok, why = set_parameter(probe, target, name, value)
        assert not ok and reason in why, (name, why)
    assert get_parameter(probe, target, 'arm1_front_min') == DEFAULT_WINDOWS['arm1_front'][0]   # unchanged
    assert press(11.0, 11.0) == 2
    assert set_parameter(probe, target, 'arm1_front_max', 10.0) == (True, '')
    assert press(12.0, 11.0) == 2                          # 11 N is outside [7.37, 10] N now: no halt
    assert press(13.0, 9.0) == 3
    assert set_parameter(probe, target, 'arm1_front_enabled', False) == (True, '')
    assert press(14.0, 9.0) == 3
    os.killpg(feedback.pid, signal.SIGINT)                 # its exit summary, for the launcher's line per robot
    assert feedback.wait(timeout=10) == 0
    assert re.search(r'summary: robot 5: halts 3, impact samples \d+', nodes.output(feedback)), nodes.output(feedback)


def test_a_recorded_c2_force_trace_halts_the_hardware_path_at_the_batch_periods(nodes: Any, ros_node: Any,
                                                                                 tmp_path: Path) -> None:
    """Robot 0's FSR samples of a batch feedback run, played as voltages into the emulator in real time."""
    import math
    import threading

    from smarticle_common.topics import FSR_FACES
    from smarticle_experiments.p6 import COLLIDING_START, Condition, run_pair_trial

    from tests.helpers.hardware_rig import FSR_CHANNEL, volts_for

    period, periods = 1.6, 5
    batch = run_pair_trial(Condition(90.0, True), SEED, periods, record_samples=True, base=COLLIDING_START)
    expected = sorted({math.floor(t / period) for t, robot, _ in batch.halts if robot == 0})
    assert len(expected) >= 2, batch.halts
    tick = batch.samples[1][0] - batch.samples[0][0]
    trace = [(t, [volts_for(face, f) if f > 0.05 else 0.0 for face, f in zip(FSR_FACES, forces[0], strict=True)])
             for t, forces in batch.samples if forces[0].max() > 0.05]

    with running_emulator(tmp_path / 'maestro') as emulator:
        probe = ros_node('feedback_trace_probe')
        rig = HardwareRig(nodes, emulator, probe, period=period, alpha_max_deg=90.0)
        logs = rig.logs
        assert spin_until(probe, rig.ready, 20.0), logs()
        t0 = rig.start(1.0)

        def play() -> None:
            # each tick's sample held until the next one when contact goes on, else for one control tick plus one
            # of the bridge's 10 ms reads (so a late read on a loaded machine still sees it); never later than
            # the next sample, so the trace keeps its own times
            for i, (t, volts) in enumerate(trace):
                time.sleep(max(0.0, t0 + t - time.time()))
                for face, v in zip(FSR_FACES, volts, strict=True):
                    emulator.set_voltage(FSR_CHANNEL[face], v)
                following = trace[i + 1][0] if i + 1 < len(trace) else math.inf
                if following - t <= tick * 1.5:
                    continue
                time.sleep(max(0.0, t0 + t + tick + 0.010 - time.time()))
                for face in FSR_FACES:
                    emulator.set_voltage(FSR_CHANNEL[face], 0.0)

        player = threading.Thread(target=play, daemon=True)
        player.start()
        spin_until(probe, lambda: time.time() >= t0 + periods * period + 0.2, periods * period + 10.0)
        player.join(timeout=5.0)
        got = sorted(math.floor((stamp - t0) / period) for stamp, _, _ in rig.observed.halts)
        assert got == expected, (got, expected, batch.halts, logs())
        for stamp, _, _ in rig.observed.halts:       # the gait answered each halt with a hold command
            assert any(stamp - 0.001 <= c <= stamp + 0.2 for c, _, _ in rig.observed.commands), stamp
