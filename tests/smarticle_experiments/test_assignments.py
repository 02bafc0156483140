"""``--set NAME=VALUE``: one parser for the study commands of smarticle-experiments (p6, physics-study)."""

from __future__ import annotations

import pytest

from smarticle_experiments.assignments import parse_assignments, parse_value


def test_values_take_the_type_their_text_has() -> None:
    assert parse_value('none') is None and parse_value('True') is True and parse_value('false') is False
    assert parse_value('1/480') == pytest.approx(1.0 / 480.0)
    assert parse_value('10') == 10 and isinstance(parse_value('10'), int)
    assert parse_value('0.8') == 0.8 and parse_value('round') == 'round'
    assert parse_value('1/0') == '1/0' and parse_value('a/b') == 'a/b'   # the text, for the field to refuse


def test_assignments_name_their_fields_and_refuse_an_item_without_one() -> None:
    assert parse_assignments(['contact_erp=0.1', ' restitution = 0.8', 'restitution=0.7']) == {
        'contact_erp': 0.1, 'restitution': 0.7}      # the later item wins
    for bad in ('restitution', '=0.8'):
        with pytest.raises(ValueError, match='expected NAME=VALUE'):
            parse_assignments([bad])
