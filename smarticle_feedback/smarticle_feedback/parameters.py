"""Parameters of the `feedback` node, declared once (node and shipped ``config/feedback.yaml``).

No rclpy here: tests, the batch experiments and the node all build the same ``FeedbackConfig`` from
these values. One window per FSR face (``<face>_min``, ``<face>_max``, ``<face>_enabled``) so faces can
be enabled one at a time; the windows and the debounce may change at run time (``ros2 param set``,
applied from the next sample on); the default window is the one calibrated from simulated C2 collisions of the
``feedback`` robot (docs/feedback.md).
"""

from __future__ import annotations

from typing import Any

from smarticle_common import topics
from smarticle_common.facts import GAIT_PERIOD
from smarticle_common.params import ROBOT_ID_PARAM, ParameterError, ParamSpec

from .controller import FeedbackConfig, ImpactWindow
from .errors import FeedbackConfigError

NODE_NAME = 'feedback'

#: Default impact windows (f_min N, f_max N, enabled) per face, from `smarticle-feedback-calibrate` on the
#: compression signature of the P6 C2 pair (the harvested start with the cited noise; `smarticle-experiments
#: c2-collisions --seed S --periods 150`, seeds 1-5 pooled: the enabled faces catch 42 of 118 compression events
#: and 0 of 66 bracing ones; held out, seeds 6 and 7: 3 of 5 and 2 of 4 compression, 0 bracing; docs/feedback.md).
#: arm1_back and arm2_front separate compression from bracing by less than the tool's 0.3 (6 of 48 and
#: 5 of 16 compression caught): disabled.
DEFAULT_WINDOWS: dict[str, tuple[float, float, bool]] = {
    'arm1_front': (7.37, 15.07, True),
    'arm1_back': (10.02, 14.9, False),
    'arm2_front': (9.11, 17.04, False),
    'arm2_back': (6.49, 15.33, True),
}


def _face_params() -> tuple[ParamSpec, ...]:
    specs: list[ParamSpec] = []
    for face in topics.FSR_FACES:
        f_min, f_max, enabled = DEFAULT_WINDOWS[face]
        specs += [
            ParamSpec(f'{face}_min', f_min, f'impact window of {face}: lowest force (N)', 0.0, 1000.0,
                      runtime=True),
            ParamSpec(f'{face}_max', f_max, f'impact window of {face}: highest force (N)', 0.0, 1000.0,
                      runtime=True),
            ParamSpec(f'{face}_enabled', enabled, f'whether an impact on {face} halts the arms', runtime=True),
        ]
    return tuple(specs)


PARAMS: tuple[ParamSpec, ...] = (
    ROBOT_ID_PARAM,
    *_face_params(),
    ParamSpec('debounce_samples', 1, 'consecutive FSR samples of one face inside its window that make an '
              'impact', 1, 1000, runtime=True),
    ParamSpec('period', GAIT_PERIOD, "gait period T (s): use the gait node's period; at most one halt "
              'per period', 0.05, 60.0),
    ParamSpec('phase', 0.0, "gait phase of this robot (fraction of a period): use the gait node's phase",
              0.0, 0.999999),
    ParamSpec('clock_rate_offset', 0.0, "relative error of this robot's board clock: use the gait node's "
              'clock_rate_offset, so that both read gait periods on the same clock (0 on a real board)',
              -0.05, 0.05),
    ParamSpec('diagnostics_period', 1.0, 'seconds (wall) between /diagnostics messages', 0.05, 60.0),
    ParamSpec('start_at', -1.0, "the gait's start time (s): use the gait node's start_at (on a board seconds "
              'since 1970); negative = take it from /smarticles/start', -1.0, 1e10),
    ParamSpec('lockstep', False, "the simulation's lock-step mode: publish the decision on every FSR sample "
              '(/smarticle_<k>/feedback_decision) for a gait node with wait_for_feedback:=true, and take a '
              'repeated sample (same stamp) only once'),
)


def config_from_values(values: dict[str, Any]) -> FeedbackConfig:
    """Build the controller config from checked parameter values; ParameterError says what is wrong."""
    try:
        windows = tuple(ImpactWindow(values[f'{face}_min'], values[f'{face}_max'], values[f'{face}_enabled'])
                        for face in topics.FSR_FACES)
        return FeedbackConfig(windows, values['debounce_samples'], values['period'], values['phase'])
    except FeedbackConfigError as err:
        raise ParameterError(f'node {NODE_NAME}: {err}') from err


def default_values(**changes: Any) -> dict[str, Any]:
    """The PARAMS defaults with some values changed (checked like the node checks them)."""
    values = {spec.name: spec.default for spec in PARAMS}
    unknown = set(changes) - set(values)
    if unknown:
        raise ParameterError(f'unknown {NODE_NAME} parameter(s): {", ".join(sorted(unknown))}')
    values.update(changes)
    return {spec.name: spec.check(values[spec.name], f'{NODE_NAME} parameter') for spec in PARAMS}
