"""The stepping loop of batch experiments: run a world for N gait periods and record its ground truth.

The npz format (``docs/sim_core.md``): S samples, N robots, arrays

* ``time`` (S,) s; ``poses`` (S, N, 3) x (m), y (m), heading of the body normal (rad);
* ``arm_angles`` (S, N, 2) rad; ``fsr`` (S, N, 4) N, faces in ``fsr_faces`` order (zeros if not recorded);
* ``contacts`` (S, N, N) bool, robot-robot contact at the sample;
* ``body_length`` () m; ``meta`` () JSON string of the settings, scene and outcome.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from smarticle_driver.topics import FSR_FACES

from .errors import SimError, SimTrouble
from .scenes import Scene
from .settings import SimConfig
from .world import World


@dataclass
class Recording:
    """Sampled ground truth of one trial (arrays as in the module docstring)."""

    time: np.ndarray
    poses: np.ndarray
    arm_angles: np.ndarray
    fsr: np.ndarray
    contacts: np.ndarray
    body_length: float
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def trouble(self) -> str:
        """The SimTrouble message that ended the trial early, or '' if it ran to the end."""
        return str(self.meta.get('trouble', ''))


def scene_period(scene: Scene) -> float:
    """The gait period shared by the scene's robots (s); SimError if none runs a gait."""
    periods = {r.gait.period for r in scene.robots if r.gait is not None}
    if len(periods) != 1:
        raise SimError(f'scene {scene.name!r} must have robots with one common gait period, '
                       f'got {sorted(periods)}')
    return periods.pop()


def run_trial(config: SimConfig, scene: Scene, periods: float, sample_every: int = 1,
              record_fsr: bool = True, record_contacts: bool = True, progress: bool = False) -> Recording:
    """Run ``scene`` for ``periods`` gait periods from a synchronised start at t = 0 and record it.

    Samples are taken every ``sample_every`` control ticks (the first at t = 0). A SimTrouble ends the
    trial early: the recording keeps every sample taken so far and ``meta['trouble']`` says why.
    """
    if not (math.isfinite(periods) and periods > 0):
        raise SimError(f'periods must be > 0, got {periods!r}')
    if sample_every < 1:
        raise SimError(f'sample_every must be >= 1 tick, got {sample_every}')
    period = scene_period(scene)
    n = len(scene.robots)
    meta: dict[str, Any] = {
        'robot': asdict(config.robot), 'physics': asdict(config.physics), 'scene': scene.name,
        'seed': scene.seed, 'periods': periods, 'period': period, 'sample_every': sample_every,
        'fsr_recorded': record_fsr, 'fsr_faces': list(FSR_FACES), 'trouble': '',
        'initial': [{'x': r.x, 'y': r.y, 'heading': r.heading, 'alpha1': r.alpha1, 'alpha2': r.alpha2,
                     'phase': r.gait.phase if r.gait else None,
                     'alpha_max': r.gait.alpha_max if r.gait else None} for r in scene.robots],
    }
    times: list[float] = []
    poses: list[np.ndarray] = []
    arms: list[np.ndarray] = []
    fsrs: list[np.ndarray] = []
    touching: list[np.ndarray] = []
    zero_fsr = np.zeros((n, len(FSR_FACES)))
    zero_contacts = np.zeros((n, n), dtype=bool)
    with World(config, scene) as world:
        ticks = world.ticks_for(periods * period)
        ticks_per_period = max(1, world.ticks_for(period))
        bar = _progress_bar(ticks, progress)

        def sample() -> None:
            state = world.state()
            times.append(state.time)
            poses.append(state.poses)
            arms.append(state.arm_angles)
            fsrs.append(world.fsr() if record_fsr else zero_fsr)
            touching.append(world.robot_contacts() if record_contacts else zero_contacts)

        world.start_gaits(0.0)
        try:
            sample()
            for tick in range(1, ticks + 1):
                world.tick()
                if tick % sample_every == 0:
                    sample()
                if bar is not None and tick % ticks_per_period == 0:
                    bar.update(ticks_per_period)
        except SimTrouble as trouble:
            meta['trouble'] = str(trouble)
        finally:
            if bar is not None:
                bar.close()
    return Recording(np.array(times), np.array(poses).reshape(-1, n, 3), np.array(arms).reshape(-1, n, 2),
                     np.array(fsrs).reshape(-1, n, len(FSR_FACES)), np.array(touching).reshape(-1, n, n),
                     config.robot.body_length, meta)


def _progress_bar(total: int, enabled: bool) -> Any:
    """A tqdm bar counting control ticks, or None."""
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit='tick', desc='sim', dynamic_ncols=True)


def save_npz(recording: Recording, path: str | Path) -> Path:
    """Write ``recording`` to a compressed npz file (format in the module docstring); return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, time=recording.time, poses=recording.poses, arm_angles=recording.arm_angles,
                        fsr=recording.fsr, contacts=recording.contacts,
                        body_length=np.float64(recording.body_length),
                        fsr_faces=np.array(FSR_FACES), meta=np.array(json.dumps(recording.meta)))
    return path


def load_npz(path: str | Path) -> Recording:
    """Read a recording written by ``save_npz``."""
    with np.load(path, allow_pickle=False) as data:
        return Recording(data['time'], data['poses'], data['arm_angles'], data['fsr'], data['contacts'],
                         float(data['body_length']), json.loads(str(data['meta'])))


def plot_trajectories(recording: Recording, path: str | Path) -> Path:
    """Draw the body-centre trajectories (in body lengths) to a PNG with matplotlib's Agg backend."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    path = Path(path)
    bl = recording.body_length
    fig = Figure(figsize=(6, 6), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    xy = recording.poses[:, :, :2] / bl
    for k in range(xy.shape[1]):
        line, = ax.plot(xy[:, k, 0], xy[:, k, 1], lw=0.8, label=f'{k}')
        ax.plot(xy[0, k, 0], xy[0, k, 1], 'o', color=line.get_color(), ms=4)
        ax.plot(xy[-1, k, 0], xy[-1, k, 1], 's', color=line.get_color(), ms=4)
    ax.set_aspect('equal')
    ax.set_xlabel('x (BL)')
    ax.set_ylabel('y (BL)')
    end = recording.time[-1] if len(recording.time) else 0.0
    title = f'{recording.meta.get("scene", "")}: {xy.shape[1]} robots, {end:.1f} s (o start, s end)'
    ax.set_title(title + ('  TROUBLE' if recording.trouble else ''), fontsize=9)
    ax.legend(fontsize=7, loc='best')
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    return path
