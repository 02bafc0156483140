"""Exceptions of the smarticle_sim physics core."""

from __future__ import annotations


class SimError(Exception):
    """Base class of every smarticle_sim error."""


class ConfigError(SimError, ValueError):
    """An invalid simulation setting; the message names the field and the accepted values."""


class SceneError(SimError, ValueError):
    """A scene that cannot be simulated (overlapping robots, off the plate, bad pair coordinates)."""


class SimTrouble(SimError, RuntimeError):
    """The simulation went wrong (NaN, flip, fall, penetration, runaway speed) and was stopped."""

    def __init__(self, robot: int, time: float, quantity: str, value: float, limit: str) -> None:
        self.robot = robot
        self.time = time
        self.quantity = quantity
        self.value = value
        super().__init__(f'sim trouble: robot {robot} at t = {time:.4f} s: {quantity} = {value:.6g} '
                         f'({limit}); lower the time step, raise solver iterations or check the scene')
