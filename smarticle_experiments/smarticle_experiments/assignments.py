"""``NAME=VALUE`` settings from the command line (``--set``), parsed one way for every tool."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any


def parse_value(text: str) -> Any:
    """'none' -> None, 'true'/'false' -> bool, 'a/b' -> a/b, ints stay int, numbers float, else the text."""
    low = text.lower()
    if low == 'none':
        return None
    if low in ('true', 'false'):
        return low == 'true'
    if text.count('/') == 1:
        a, b = text.split('/')
        try:
            return float(a) / float(b)
        except (ValueError, ZeroDivisionError):
            return text
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def parse_assignments(items: Sequence[str]) -> dict[str, Any]:
    """``NAME=VALUE`` strings to {name: value} (values by ``parse_value``, later items win); an item without
    a name or an '=' raises ValueError naming it."""
    out: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition('=')
        if not sep or not name.strip():
            raise ValueError(f'{item!r}: expected NAME=VALUE')
        out[name.strip()] = parse_value(value.strip())
    return out
