"""Which topics to record or play: explicit names, a regular expression, or all; and topic remapping."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterable

from .errors import TopicSelectionError

_NAME = re.compile(r'^/?[A-Za-z_~{][\w{}~]*(/[A-Za-z_{][\w{}]*)*$')


def normalize_topic(name: str) -> str:
    """Return ``name`` as an absolute topic name or raise TopicSelectionError if it is not a valid one."""
    name = name.strip()
    if not _NAME.match(name):
        raise TopicSelectionError(f'{name!r} is not a valid ROS topic name')
    return name if name.startswith('/') else '/' + name


def split_names(text: str | Iterable[str]) -> tuple[str, ...]:
    """Split a comma- or space-separated list (or join an iterable) of topic names into a tuple."""
    items = re.split(r'[\s,]+', text) if isinstance(text, str) else list(text)
    return tuple(normalize_topic(item) for item in items if item.strip())


def _compile(pattern: str, what: str) -> re.Pattern[str] | None:
    """Compile a regular expression or raise TopicSelectionError naming the option."""
    if not pattern:
        return None
    try:
        return re.compile(pattern)
    except re.error as err:
        raise TopicSelectionError(f'{what} {pattern!r} is not a valid regular expression: {err}') from err


@dataclass(frozen=True)
class TopicFilter:
    """Topic choice as ``ros2 bag record`` makes it: names, ``-e`` regex, ``-a`` all, ``--exclude-regex``."""

    topics: tuple[str, ...] = ()
    regex: str = ''
    exclude_regex: str = ''
    all: bool = False
    include_hidden: bool = False

    def __post_init__(self) -> None:
        """Check the names and patterns; at least one way of choosing topics is needed."""
        object.__setattr__(self, 'topics', split_names(self.topics))
        _compile(self.regex, 'regex (-e)')
        _compile(self.exclude_regex, 'exclude regex (-x)')
        if not (self.topics or self.regex or self.all):
            raise TopicSelectionError('no topics chosen: give topic names, -e/--regex REGEX or -a/--all')

    def matches(self, name: str) -> bool:
        """True if topic ``name`` is chosen."""
        exclude = _compile(self.exclude_regex, 'exclude regex (-x)')
        if exclude is not None and exclude.search(name):
            return False
        if name in self.topics:
            return True
        if not self.include_hidden and any(part.startswith('_') for part in name.split('/')):
            return False
        regex = _compile(self.regex, 'regex (-e)')
        if regex is not None and regex.search(name):
            return True
        return self.all

    def choose(self, available: Iterable[tuple[str, list[str]]]) -> dict[str, str]:
        """Return {topic: type} of the chosen (name, types) pairs; multi-typed topics are left out."""
        chosen: dict[str, str] = {}
        for name, types in available:
            if len(types) == 1 and self.matches(name):
                chosen[name] = types[0]
        return chosen


def parse_remaps(items: Iterable[str]) -> dict[str, str]:
    """Parse ``from:=to`` remappings (as given to ``--remap``) into a dict of absolute names."""
    remaps: dict[str, str] = {}
    for item in items:
        for part in (p for p in re.split(r'[\s,]+', item) if p):
            if ':=' not in part:
                raise TopicSelectionError(f'remapping {part!r} must look like /old_topic:=/new_topic')
            old, new = part.split(':=', 1)
            remaps[normalize_topic(old)] = normalize_topic(new)
    return remaps
