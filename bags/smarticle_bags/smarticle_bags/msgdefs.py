"""Full ROS 2 message definitions (``ros2msg`` schemas) and type hashes from the installed .msg files.

rosbag2 stores, for each topic type, the type's .msg text followed by every type it depends on::

    <text of pkg/msg/Name.msg>
    ================================================================================
    MSG: dep_pkg/Dep
    <text of dep_pkg/msg/Dep.msg>

This module builds the same text from the ``share/<pkg>/msg/*.msg`` files that every ROS 2 install
(and the ``ros-jazzy-*`` PyPI wheels) ships, and reads the RIHS01 type hash from the ``.json`` file
next to it. It imports no ROS code.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import sys
from functools import lru_cache
from pathlib import Path

from .errors import MessageDefinitionError

SEPARATOR = '=' * 80

PRIMITIVES = frozenset({
    'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16', 'uint16', 'int32',
    'uint32', 'int64', 'uint64', 'string', 'wstring',
})

_TYPE_NAME = re.compile(r'^([A-Za-z][\w]*)/(?:msg/)?([A-Za-z][\w]*)$')


def split_type(type_name: str) -> tuple[str, str]:
    """Return (package, Name) of ``pkg/msg/Name`` or ``pkg/Name``; raise MessageDefinitionError."""
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise MessageDefinitionError(f'message type must look like pkg/msg/Name, got {type_name!r}')
    return match.group(1), match.group(2)


def share_dirs() -> list[Path]:
    """Return the ``share`` folders searched for .msg files (AMENT_PREFIX_PATH, then this Python's prefix)."""
    prefixes = [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    prefixes += [sys.prefix, sys.base_prefix]
    seen: list[Path] = []
    for prefix in prefixes:
        share = Path(prefix) / 'share'
        if share.is_dir() and share not in seen:
            seen.append(share)
    return seen


@lru_cache(maxsize=None)
def _package_share(package: str) -> Path | None:
    """Return ``share/<package>`` for a message package, or None if it is not installed."""
    for share in share_dirs():
        if (share / package).is_dir():
            return share / package
    spec = importlib.util.find_spec(package) if package.isidentifier() else None
    if spec is not None and spec.origin:
        # <prefix>/lib/pythonX.Y/site-packages/<package>/__init__.py -> <prefix>/share/<package>
        for parent in Path(spec.origin).resolve().parents:
            candidate = parent / 'share' / package
            if candidate.is_dir():
                return candidate
    return None


def msg_file(type_name: str) -> Path:
    """Return the path of the installed .msg file of ``type_name`` or raise MessageDefinitionError."""
    package, name = split_type(type_name)
    share = _package_share(package)
    if share is None:
        raise MessageDefinitionError(
            f'message package {package!r} is not installed (no share/{package} under '
            f'{", ".join(str(s) for s in share_dirs()) or "AMENT_PREFIX_PATH"}); '
            'install it or source its workspace')
    path = share / 'msg' / f'{name}.msg'
    if not path.is_file():
        raise MessageDefinitionError(f'{type_name}: no file {path}')
    return path


def field_types(text: str, package: str) -> list[str]:
    """Return the complex field types (``pkg/Name``) that a .msg text uses, in order of appearance."""
    deps: list[str] = []
    for raw in text.splitlines():
        line = raw.split('#', 1)[0].strip()
        if not line:
            continue
        parts = line.split()
        if len(parts) < 2:
            raise MessageDefinitionError(f'{package}: cannot parse .msg line {raw!r}')
        base = re.sub(r'\[.*\]$', '', parts[0])
        base = re.sub(r'<=\d+$', '', base)
        if base in PRIMITIVES or '=' in parts[1] or (len(parts) > 2 and parts[2].startswith('=')):
            continue
        if base == 'Header':
            base = 'std_msgs/Header'
        elif '/' not in base:
            base = f'{package}/{base}'
        pkg, name = split_type(base)
        dep = f'{pkg}/{name}'
        if dep not in deps:
            deps.append(dep)
    return deps


@lru_cache(maxsize=None)
def full_definition(type_name: str) -> str:
    """Return the rosbag2-style ``ros2msg`` text of ``type_name`` with all its dependencies."""
    package, name = split_type(type_name)
    root = msg_file(type_name).read_text(encoding='utf-8')
    parts = [root]
    seen = {f'{package}/{name}'}

    def append(pkg: str, text: str) -> None:
        for dep in field_types(text, pkg):
            if dep in seen:
                continue
            seen.add(dep)
            dep_text = msg_file(dep).read_text(encoding='utf-8')
            parts.append(f'\n{SEPARATOR}\nMSG: {dep}\n{dep_text}')
            append(split_type(dep)[0], dep_text)

    append(package, root)
    return ''.join(parts)


@lru_cache(maxsize=None)
def type_hash(type_name: str) -> str:
    """Return the RIHS01 type description hash of ``type_name`` (empty if the .json is missing)."""
    path = msg_file(type_name).with_suffix('.json')
    package, name = split_type(type_name)
    try:
        data = json.loads(path.read_text(encoding='utf-8'))
    except (OSError, ValueError):
        return ''
    for entry in data.get('type_hashes', []):
        if entry.get('type_name') == f'{package}/msg/{name}':
            return str(entry.get('hash_string', ''))
    return ''


def normalize_type(type_name: str) -> str:
    """Return ``pkg/msg/Name`` for ``pkg/Name`` or ``pkg/msg/Name``."""
    package, name = split_type(type_name)
    return f'{package}/msg/{name}'
