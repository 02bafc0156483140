"""Calling a node's parameter services over DDS, as ``ros2 param set`` / ``get`` do."""

from __future__ import annotations

from typing import Any

from tests.helpers.ros import call_service


def _call(node: Any, service: str, srv_type: Any, request: Any, timeout: float = 15.0) -> Any:
    # getting a parameter, or setting one to a value, may be asked again if the answer is lost
    return call_service(node, srv_type, service, request, timeout, attempts=3)


def set_parameter(node: Any, target: str, name: str, value: Any) -> tuple[bool, str]:
    """``ros2 param set target name value``: (successful, reason)."""
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    request = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
    result = _call(node, f'{target}/set_parameters', SetParameters, request).results[0]
    return result.successful, result.reason


def get_parameter(node: Any, target: str, name: str) -> Any:
    """``ros2 param get target name``: the value."""
    from rcl_interfaces.srv import GetParameters
    from rclpy.parameter import parameter_value_to_python

    values = _call(node, f'{target}/get_parameters', GetParameters, GetParameters.Request(names=[name])).values
    return parameter_value_to_python(values[0])
