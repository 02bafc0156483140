"""Parameter tables: names, defaults, descriptions and ranges of a node's parameters, declared once.

A node lists its parameters once as ``ParamSpec`` rows; ``smarticle_common.node.declare_and_read``
declares them on the node and returns the values, and ``defaults_yaml`` renders the shipped YAML file of
defaults (a test checks each package's ``config/*.yaml`` against its table). No rclpy here.
"""

from __future__ import annotations

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


#: The robot_id parameter of per-robot nodes: -1 takes the id from the node's namespace.
ROBOT_ID_PARAM = ParamSpec('robot_id', -1, 'robot id k: topics live under /smarticle_<k>; -1 = the k of the '
                           "node's namespace /smarticle_<k> (0 outside one); a value that disagrees with the "
                           'namespace is refused', -1, topics.MAX_ROBOT_ID)
