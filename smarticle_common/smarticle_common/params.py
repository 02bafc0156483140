"""Parameter tables: names, defaults, descriptions and ranges of a node's parameters, declared once.

A node lists its parameters once as ``ParamSpec`` rows; ``smarticle_common.node.declare_and_read``
declares them on the node and returns the values, and ``defaults_yaml`` renders the shipped YAML file of
defaults (a test checks each package's ``config/*.yaml`` against its table). ``check_params_file`` reads a
ROS parameters file the way rcl will, so a malformed one is one line naming the file and line instead of
rcl's traceback. No rclpy here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import yaml

from . import topics
from .errors import CommonError


class ParameterError(CommonError):
    """A parameter value that is missing, of the wrong type or out of range."""


@dataclass(frozen=True)
class ParamSpec:
    """One declared parameter: name, default value (its type is the parameter's type), meaning."""

    name: str
    default: Any
    description: str
    minimum: float | None = None
    maximum: float | None = None
    #: True if the node applies a change at run time; every other parameter is read-only once declared.
    runtime: bool = False

    def check(self, value: Any, source: str = 'parameter') -> Any:
        """Return ``value`` if it has the default's type and lies in range, else raise ParameterError."""
        want = type(self.default)
        if want is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if not isinstance(value, want) or (want is int and isinstance(value, bool)):
            raise ParameterError(f'{source} {self.name!r}: expected {want.__name__}, got {value!r}')
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            if value != value:
                raise ParameterError(f'{source} {self.name!r}: NaN is not allowed')
            if self.minimum is not None and value < self.minimum:
                raise ParameterError(f'{source} {self.name!r}: {value} is below the minimum {self.minimum}')
            if self.maximum is not None and value > self.maximum:
                raise ParameterError(f'{source} {self.name!r}: {value} is above the maximum {self.maximum}')
        return value


def node_key(node_name: str) -> str:
    """The section key of a shipped parameter file: ``/**/<node>``, the node in any namespace.

    A bare ``<node>:`` key matches only a node in the root namespace, so a robot's node started in
    ``/smarticle_<k>`` would silently skip it.
    """
    return f'/**/{node_name}'


def defaults_yaml(node_name: str, specs: tuple[ParamSpec, ...]) -> str:
    """Render the ROS parameters file of the defaults of ``specs`` for node ``node_name`` (any namespace)."""
    params = {spec.name: spec.default for spec in specs}
    return yaml.safe_dump({node_key(node_name): {'ros__parameters': params}}, sort_keys=False)


def read_defaults_yaml(path: str, node_name: str) -> dict[str, Any]:
    """Read the ``ros__parameters`` of ``node_name`` (``/**/<node>``, ``<node>`` or ``/**``) from a ROS
    parameters file."""
    with open(path, encoding='utf-8') as handle:
        data = yaml.safe_load(handle)
    for key in (node_key(node_name), node_name, '/**'):
        if isinstance(data, dict) and key in data:
            return dict(data[key]['ros__parameters'])
    raise ParameterError(f'{path}: no section {node_name!r} with ros__parameters')


def _line(node: yaml.Node) -> int:
    return node.start_mark.line + 1


def _check_parameters(path: str, node: yaml.Node) -> None:
    """The inside of a ``ros__parameters`` mapping: values, nested names, lists of one type."""
    if not isinstance(node, yaml.MappingNode):
        raise ParameterError(f'{path}:{_line(node)}: ros__parameters must be a mapping of names to values')
    for key, value in node.value:
        if isinstance(value, yaml.MappingNode):
            _check_parameters(path, value)
        elif isinstance(value, yaml.SequenceNode):
            if any(not isinstance(item, yaml.ScalarNode) for item in value.value):
                raise ParameterError(f'{path}:{_line(value)}: parameter {key.value!r}: a list holds plain values '
                                     'only')
            if len({item.tag for item in value.value}) > 1:
                raise ParameterError(f'{path}:{_line(value)}: parameter {key.value!r}: every value of a list must '
                                     'have one type (' + ', '.join(item.value for item in value.value) + ')')


def _check_sections(path: str, node: yaml.Node) -> None:
    """Node names (nested namespaces) down to their ``ros__parameters``."""
    if not isinstance(node, yaml.MappingNode):
        return
    for key, value in node.value:
        if key.value == 'ros__parameters':
            _check_parameters(path, value)
        elif isinstance(value, yaml.MappingNode):
            _check_sections(path, value)
        else:
            raise ParameterError(f'{path}:{_line(key)}: {key.value!r} has a value outside ros__parameters (a '
                                 'parameters file is node name: ros__parameters: name: value)')


def check_params_file(path: str) -> None:
    """Read the ROS parameters file ``path`` as rcl will: ParameterError, one line naming the file and the
    line, if it cannot be read, is not YAML or has values outside ``ros__parameters`` or lists of mixed type."""
    try:
        with open(path, encoding='utf-8') as handle:
            text = handle.read()
    except OSError as err:
        raise ParameterError(f'{path}: cannot read the parameter file ({err.strerror})') from None
    except UnicodeDecodeError:
        raise ParameterError(f'{path}: the parameter file is not UTF-8 text') from None
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as err:
        mark = getattr(err, 'problem_mark', None) or getattr(err, 'context_mark', None)
        where = f':{mark.line + 1}' if mark is not None else ''
        problem = getattr(err, 'problem', None) or str(err).splitlines()[0]
        context = getattr(err, 'context', None)
        raise ParameterError(f'{path}{where}: malformed YAML in the parameter file: {problem}'
                             + (f' ({context})' if context else '')) from None
    if root is not None:
        _check_sections(path, root)


def params_files(args: Sequence[str]) -> list[str]:
    """The files given with ``--params-file`` in a command line's ``--ros-args`` part(s)."""
    return [args[i + 1] for i, word in enumerate(args[:-1]) if word == '--params-file']


#: The robot_id parameter of per-robot nodes: -1 takes the id from the node's namespace.
ROBOT_ID_PARAM = ParamSpec('robot_id', -1, 'robot id k: topics live under /smarticle_<k>; -1 = the k of the '
                           "node's namespace /smarticle_<k> (0 outside one); a value that disagrees with the "
                           'namespace is refused', -1, topics.MAX_ROBOT_ID)
