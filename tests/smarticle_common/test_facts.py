"""Robot facts: the presets match the paper, nonsense is refused with the field named, one definition each."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from smarticle_common.errors import RobotSpecError
from smarticle_common.facts import (BODY_LENGTH, FEEDBACK, GAIT_PERIOD, R_BIND_BL, SMALL, TAG_SIZE, RobotSpec,
                                    robot_preset)

ROOT = Path(__file__).resolve().parents[2]


def test_small_preset_is_the_papers_robot() -> None:
    assert SMALL.total_mass == pytest.approx(0.0348)
    assert SMALL.body_mass + 2 * SMALL.arm_mass == pytest.approx(0.0348)
    assert (SMALL.arm_length, SMALL.arm_thickness) == (0.050, 0.003)
    assert (SMALL.body_width, SMALL.body_depth) == (0.054, 0.022)
    assert SMALL.body_length == SMALL.body_width == 0.054
    assert SMALL.arm_clearance > 0 and SMALL.arm_clearance + SMALL.arm_height <= SMALL.body_height


def test_feedback_preset() -> None:
    assert robot_preset('feedback') is FEEDBACK
    assert FEEDBACK.total_mass == pytest.approx(0.175)
    assert (FEEDBACK.arm_length, FEEDBACK.arm_thickness) == (0.060, 0.007)
    assert (FEEDBACK.body_width, FEEDBACK.body_depth) == (0.065, 0.035)


def test_unknown_preset_refused() -> None:
    with pytest.raises(RobotSpecError, match="'huge'.*small"):
        robot_preset('huge')


@pytest.mark.parametrize('field, value', [('total_mass', -0.01), ('arm_mass', 0.0), ('arm_length', math.nan),
                                          ('servo_torque', -1.0)])
def test_bad_robot_values_refused(field: str, value: float) -> None:
    values = {**SMALL.__dict__, field: value}
    with pytest.raises(RobotSpecError, match=f'RobotSpec.{field}'):
        RobotSpec(**values)


def test_arms_heavier_than_robot_refused() -> None:
    with pytest.raises(RobotSpecError, match='arm_mass'):
        RobotSpec(**{**SMALL.__dict__, 'arm_mass': 0.02})



def test_facts_have_the_papers_values() -> None:
    assert GAIT_PERIOD == 1.6
    assert BODY_LENGTH == SMALL.body_width == 0.054
    assert TAG_SIZE == 0.018
    assert R_BIND_BL == 1.6


@pytest.mark.parametrize('pattern', [
    r'(DEFAULT_PERIOD|GAIT_PERIOD|PERIOD|period)\b[^=\n(]*[:=,]\s*1\.6\b',
    r'(BODY_LENGTH|BODY_WIDTH|body_width)\b[^=\n]*[:=,]\s*0\.054\b',
    r'^\s*R_BIND_BL\s*=',
    r'(TAG_SIZE|tag_size)\b[^=\n]*[:=,]\s*0\.018\b',
    r'^\s*(def pair_coordinates|class PairCoordinates|def wrap_angle|def wrap_2pi|def wrap_pi)\b',
])
def test_each_fact_is_defined_once(pattern: str) -> None:
    """A grep over the packages finds one definition of each fact and conversion: in smarticle_common."""
    regex = re.compile(pattern, re.M)
    hits = []
    for path in ROOT.glob('*/**/*.py'):
        if '.venv' in path.parts or 'tests' in path.parts or 'ros_ws' in path.parts:
            continue
        hits += [(path.relative_to(ROOT), m.group(0).strip()) for m in regex.finditer(path.read_text())]
    assert hits, f'no definition of {pattern}'
    assert all(str(path).startswith('smarticle_common/') for path, _ in hits), hits
