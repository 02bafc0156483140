"""Typed results: the stored dict leaves unset optional fields out, and a stored dict reads back typed."""

from __future__ import annotations

import json

import pytest

from smarticle_experiments.results import InadmissiblePairResult, P6Result, SingleResult


def test_optional_fields_are_stored_only_when_set_and_read_back() -> None:
    plain = P6Result(lifetime_periods=12, censored=False, halts=3, trouble='', r0_bl=1.47, theta0_deg=99.0,
                     phi0_deg=7.0, final_r_bl=None)
    stored = plain.as_dict()
    assert 'travel_w' not in stored and 'contact_periods' not in stored
    assert stored['final_r_bl'] is None   # a required field that is None stays (null in the store)
    detailed = P6Result(**{**stored, 'travel_w': 0.4, 'contact_periods': [1, 2]})
    assert detailed.as_dict()['contact_periods'] == [1, 2]
    assert P6Result.from_dict(json.loads(json.dumps(detailed.as_dict()))) == detailed
    assert P6Result.from_dict({**stored, 'unknown_key': 1}) == plain   # keys a reader does not know are ignored


def test_a_stored_result_missing_a_required_field_is_refused() -> None:
    with pytest.raises(TypeError):
        SingleResult.from_dict({'drift_um_per_cycle': 75.0})
    bad = InadmissiblePairResult(r0_bl=0.3, theta0_deg=0.0, phi0_deg=180.0, admissible=False, why='overlap',
                                 trouble='', gliders=[])
    assert bad.as_dict() == {'r0_bl': 0.3, 'theta0_deg': 0.0, 'phi0_deg': 180.0, 'admissible': False,
                             'why': 'overlap', 'trouble': '', 'gliders': []}
