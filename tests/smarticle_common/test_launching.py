"""What a launcher reads back from its processes: the one-line reason of a failure, the exit summaries."""

from __future__ import annotations

from smarticle_common.launching import failure_reason, gather_summaries, report_line, summary_line

TRACEBACK = '''[INFO] [1.5] [gait]: robot 0: alpha_max 90 deg
Traceback (most recent call last):
  File "/x/bin/gait", line 6, in <module>
    sys.exit(main())
  File "/x/smarticle_driver/gait_node.py", line 50, in __init__
    super().__init__(NODE_NAME, **node_options)
rclpy._rclpy_pybind11.RCLInvalidROSArgsError: Failed to parse ROS arguments: Error parsing near line 3, \
at /project/src/parse.c:782, at /project/src/rcl/arguments.c:415[ERROR] [1795779194.4] [rcl]: Failed to parse global \
arguments
'''


def test_a_traceback_gives_its_message_and_last_frame_on_one_line() -> None:
    reason = failure_reason(TRACEBACK)
    assert reason == ('rclpy._rclpy_pybind11.RCLInvalidROSArgsError: Failed to parse ROS arguments: Error parsing '
                      'near line 3 (File "/x/smarticle_driver/gait_node.py", line 50, in __init__)')


def test_without_a_traceback_the_last_error_line_else_the_last_line() -> None:
    log = ('[INFO] [1.0] [sim_bridge]: 2 robots\n'
           '[FATAL] [1.2] [smarticle-compose]: cannot start: node sim_bridge: sim_bridge.scene must be one of '
           'dense, pair, random, got \'triangle\'\n[INFO] [1.3] [x]: bye\n')
    assert failure_reason(log) == ("[smarticle-compose] cannot start: node sim_bridge: sim_bridge.scene must be one "
                                   "of dense, pair, random, got 'triangle'")
    assert failure_reason('starting\nsegfault here\n\n') == 'segfault here'
    assert failure_reason('') is None


def test_summaries_merge_per_robot_and_keep_the_other_reports() -> None:
    bridge = '\n'.join(f'[INFO] [9.0] [sim_bridge]: {summary_line(k, {"commands": 100 + k, "contacts": 3})}'
                       for k in range(2))
    gait = f'[INFO] [9.1] [smarticle_1.gait]: {summary_line(1, {"commands": 99, "halts": 2})}\n'
    monitor = f'[INFO] [9.2] [glider_monitor]: {report_line("gliders: none")}\n'
    robots, others = gather_summaries([bridge, gait + monitor + 'summary: robot 5: not a log line\n'])
    assert robots == {0: {'commands': '100', 'contacts': '3'},
                      1: {'commands': '101', 'contacts': '3', 'halts': '2'}}      # the larger count kept
    assert others == ['gliders: none']
