"""Phase drift study: how far apart in phase the robots' gaits get under the noise, measured from a trial.

The paper's robots start in phase (an audio pulse) and drift apart in phase. ``phase_drift`` runs a batch
trial and times, for every robot, each downward zero crossing of arm 1 (the middle of the quarter-0
stroke, once per period of the robot's own clock); a robot's phase lead at its n-th crossing is the mean
crossing time of all robots minus its own, in periods. The clock-rate noise predicts a lead growing as
n (eps_k - mean eps) (``expected``); servo jitter and collisions that stall an arm add scatter on top.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .batch import run_trial, scene_period
from .errors import SimError
from .noise import clock_rates
from .scenes import Scene
from .settings import SimConfig

#: Hysteresis (rad) of the zero-crossing detector: arm 1 must come from above +h and reach below -h.
_HYSTERESIS = 0.3


@dataclass(frozen=True)
class PhaseDrift:
    """Measured and expected phase leads of every robot at each of its first ``len(periods)`` periods."""

    periods: np.ndarray        # (M,) period index n (0 = the first crossing after the start)
    lead: np.ndarray           # (M, N) measured phase lead (periods) against the robots' mean
    expected: np.ndarray       # (M, N) the clock-rate prediction n (eps_k - mean eps)
    clock_rates: np.ndarray    # (N,) the drawn eps_k
    trouble: str               # '' unless the trial stopped early

    def spread(self) -> np.ndarray:
        """(M,) standard deviation of the measured leads across robots (periods)."""
        return self.lead.std(axis=1)

    def expected_spread(self) -> np.ndarray:
        """(M,) standard deviation of the expected leads across robots (periods)."""
        return self.expected.std(axis=1)


def downward_crossings(time: np.ndarray, angle: np.ndarray, min_gap: float) -> np.ndarray:
    """Times where ``angle`` falls from above +h through 0 to below -h (linear interpolation at 0).

    Crossings closer than ``min_gap`` (s) to the previous one are dropped (an arm pushed back and forth
    across zero by a collision).
    """
    out: list[float] = []
    armed = False
    last = -np.inf
    for i in range(1, len(time)):
        if angle[i - 1] > _HYSTERESIS:
            armed = True
        if armed and angle[i - 1] >= 0.0 > angle[i]:
            j = i
            while j < len(time) and angle[j] > -_HYSTERESIS:
                j += 1
            if j == len(time):
                break
            t = time[i - 1] + (time[i] - time[i - 1]) * angle[i - 1] / (angle[i - 1] - angle[i])
            if t - last >= min_gap:
                out.append(float(t))
                last = t
            armed = False
    return np.array(out)


def phase_drift(config: SimConfig, scene: Scene, periods: float) -> PhaseDrift:
    """Run ``scene`` for ``periods`` gait periods and measure the robots' phase leads (see module doc)."""
    period = scene_period(scene)
    rec = run_trial(config, scene, periods, sample_every=1)
    n = rec.poses.shape[1]
    crossings = [downward_crossings(rec.time, rec.arm_angles[:, k, 0], 0.5 * period) for k in range(n)]
    m = min(len(c) for c in crossings)
    if m < 2:
        raise SimError(f'phase drift: robot arms crossed zero fewer than twice in {periods:g} periods')
    times = np.column_stack([c[:m] for c in crossings])          # (M, N)
    lead = (times.mean(axis=1, keepdims=True) - times) / period
    eps = clock_rates(config.noise, n, config.noise.trial_seed(scene.seed))
    index = np.arange(m, dtype=float)
    # robot k's n-th crossing comes at t0 + (n + c) T / (1 + eps_k): a lead of about n (eps_k - mean eps)
    expected = index[:, None] * (eps - eps.mean())[None, :]
    return PhaseDrift(index, lead, expected, eps, rec.trouble)


def format_phase_drift(study: PhaseDrift, every: int = 10) -> str:
    """A table of the phase spread across robots every ``every`` periods (measured vs clock prediction)."""
    spread, expected = study.spread(), study.expected_spread()
    eps = study.clock_rates
    lines = [f'clock rates eps_k (%): {" ".join(f"{100 * e:+.3f}" for e in eps)}',
             f'{"period":>6} | {"spread sd (periods)":>19} | {"expected sd":>11} | {"max-min":>7} | '
             f'{"rms measured - expected":>23}']
    rows = list(range(0, len(spread), max(1, every)))
    if rows[-1] != len(spread) - 1:
        rows.append(len(spread) - 1)
    for i in rows:
        lead = study.lead[i]
        residual = float(np.sqrt(np.mean((lead - study.expected[i]) ** 2)))
        lines.append(f'{int(study.periods[i]):>6} | {spread[i]:>19.4f} | {expected[i]:>11.4f} | '
                     f'{lead.max() - lead.min():>7.4f} | {residual:>23.4f}')
    if study.trouble:
        lines.append(f'stopped early: {study.trouble}')
    return '\n'.join(lines)
