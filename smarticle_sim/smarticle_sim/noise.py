"""Noise with a cause: the seeded draws behind ``settings.NoiseConfig``.

Three sources a user can name and set (docs/sim_core.md, "Noise with a cause"):

* each robot's gait clock runs slightly fast or slow (``clock_rates``; applied by ``runner.GaitController``);
* each quarter's servo command goes out after a delay of up to one servo PWM frame (``ServoDelays``;
  applied by ``runner.GaitController``);
* the body-plate friction varies smoothly across the plate (``FrictionField``; applied by
  ``physics.Physics.update_plate_friction``, called once per control tick by ``runner.Runner``).

Every draw comes from its own NumPy stream, keyed by the trial seed and the source (and the robot), never
from the scene builder's stream: a seed places the robots the same with or without noise, and switching
one source on does not change the draws of another.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import ConfigError
from .settings import FRICTION_CLIP, NoiseConfig

#: Entropy word that separates the noise streams from the scene builders' ``default_rng(seed)``.
_STREAM = 0x6E6F697365   # 'noise'
#: Source keys of the streams.
CLOCK, SERVO, FRICTION = 0, 1, 2
#: Clock-rate draws are clipped at this many standard deviations.
CLOCK_CLIP = 4.0
#: Grid points per correlation length of the friction field, and the largest grid side allowed.
_POINTS_PER_LENGTH = 8
_MAX_GRID = 2048


def noise_rng(seed: int, source: int, *keys: int) -> np.random.Generator:
    """The random stream of one noise ``source`` (and e.g. robot) for the trial ``seed``."""
    return np.random.default_rng([int(seed), _STREAM, int(source), *(int(k) for k in keys)])


def clock_rates(noise: NoiseConfig, n: int, seed: int) -> np.ndarray:
    """(n,) relative clock-rate offsets eps_k ~ Normal(0, clock_rate_sd), clipped at 4 sd; zeros if off."""
    if noise.clock_rate_sd == 0.0:
        return np.zeros(n)
    z = noise_rng(seed, CLOCK).standard_normal(n)
    return noise.clock_rate_sd * np.clip(z, -CLOCK_CLIP, CLOCK_CLIP)


class ServoDelays:
    """Per-robot streams of servo command delays, uniform in [0, jitter] seconds (one draw per command)."""

    def __init__(self, jitter: float, n: int, seed: int) -> None:
        if not (math.isfinite(jitter) and jitter >= 0.0):
            raise ConfigError(f'NoiseConfig.servo_jitter must be a finite number >= 0, got {jitter!r}')
        self.jitter = float(jitter)
        self._streams = [noise_rng(seed, SERVO, k) for k in range(n)]

    def draw(self, robot: int) -> float:
        """The delay (s) of robot ``robot``'s next command."""
        return float(self._streams[robot].uniform(0.0, self.jitter))


class FrictionField:
    """A seeded smooth Gaussian random field of relative body-plate friction over the plate.

    ``factor(xy)`` = 1 + sd * z(x, y), where z is a stationary Gaussian field with unit variance and
    correlation exp(-d^2 / (2 length^2)), clipped at ``FRICTION_CLIP`` sd. It is made by filtering white
    noise on a grid (``length / 8`` spacing, padded by 3 lengths beyond the plate, periodic FFT
    convolution with a Gaussian kernel normalised to unit output variance) and read bilinearly.
    """

    def __init__(self, sd: float, length: float, plate_size: float, seed: int) -> None:
        if not (math.isfinite(sd) and sd >= 0.0):
            raise ConfigError(f'NoiseConfig.friction_sd must be a finite number >= 0, got {sd!r}')
        if not (math.isfinite(length) and length > 0.0):
            raise ConfigError(f'NoiseConfig.friction_length must be a positive length (m), got {length!r}')
        self.sd = float(sd)
        self.length = float(length)
        self.spacing = self.length / _POINTS_PER_LENGTH
        half = plate_size / 2.0 + 3.0 * self.length
        n = math.ceil(2.0 * half / self.spacing) + 1
        if n > _MAX_GRID:
            raise ConfigError(f'NoiseConfig.friction_length: {length!r} m is too short for a {plate_size} m plate '
                              f'(a {n} x {n} grid); use at least {8.0 * 2.0 * half / _MAX_GRID:.4f} m')
        self.origin = -half
        self.n = n
        white = noise_rng(seed, FRICTION).standard_normal((n, n))
        # Gaussian kernel of sd length / sqrt(2): filtered white noise then has correlation exp(-d^2 / (2 l^2))
        d = np.minimum(np.arange(n), n - np.arange(n)) * self.spacing
        sigma = self.length / math.sqrt(2.0)
        k1 = np.exp(-0.5 * (d / sigma) ** 2)
        kernel = np.outer(k1, k1)
        kernel /= math.sqrt(float((kernel ** 2).sum()))   # unit output variance
        z = np.fft.irfft2(np.fft.rfft2(white) * np.fft.rfft2(kernel), s=(n, n))
        self.grid = np.clip(z, -FRICTION_CLIP, FRICTION_CLIP)   # z[i, j] at x = origin + i h, y = origin + j h

    def z(self, xy: np.ndarray) -> np.ndarray:
        """The unit field at positions ``xy`` (N, 2) in metres (bilinear; clamped to the grid)."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        u = np.clip((xy - self.origin) / self.spacing, 0.0, self.n - 1.000001)
        i = u.astype(int)
        f = u - i
        g = self.grid
        i0, j0 = i[:, 0], i[:, 1]
        fx, fy = f[:, 0], f[:, 1]
        return ((1 - fx) * (1 - fy) * g[i0, j0] + fx * (1 - fy) * g[i0 + 1, j0]
                + (1 - fx) * fy * g[i0, j0 + 1] + fx * fy * g[i0 + 1, j0 + 1])

    def factor(self, xy: np.ndarray) -> np.ndarray:
        """(N,) friction factors 1 + sd * z at positions ``xy`` (N, 2) (m)."""
        return 1.0 + self.sd * self.z(xy)
