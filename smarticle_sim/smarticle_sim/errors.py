"""Exceptions of the smarticle_sim physics core."""

from __future__ import annotations


class SimError(Exception):
    """Base class of every smarticle_sim error."""


class ConfigError(SimError, ValueError):
    """An invalid simulation setting; the message names the field and the accepted values."""


class NotConvergedWarning(UserWarning):
    """A setting the simulation accepts but whose results are not converged in the time step."""


class SceneError(SimError, ValueError):
    """A scene that cannot be simulated (overlapping robots, off the plate, bad pair coordinates)."""


class SimTrouble(SimError, RuntimeError):
    """The simulation went wrong (NaN, flip, fall, penetration, runaway speed) and was stopped.

    ``physical`` marks an end that is physics, not numerics (a robot pushed or gliding off the plate):
    the advice is then a larger plate, not a smaller step.
    """

    def __init__(self, robot: int, time: float, quantity: str, value: float, limit: str,
                 physical: bool = False) -> None:
        self.robot = robot
        self.time = time
        self.quantity = quantity
        self.value = value
        self.physical = physical
        advice = ('a physical end, not numerical trouble: a larger plate_size keeps it on the plate' if physical
                  else 'lower the time step, raise solver iterations or check the scene')
        super().__init__(f'sim trouble: robot {robot} at t = {time:.4f} s: {quantity} = {value:.6g} '
                         f'({limit}); {advice}')
