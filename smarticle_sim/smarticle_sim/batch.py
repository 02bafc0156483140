"""A batch trial: run a scene for N gait periods through the one ``Runner`` loop and record its ground truth.

The engine is Bullet's ``Physics`` unless ``run_trial`` is given another (``engines.engine_factory``).

The trial comes back as a ``smarticle_common.runs.Recording`` (the one run format on disk, npz).
Samples are taken at ``DEFAULT_SAMPLE_RATE`` (20 Hz) unless asked otherwise; FSR and contacts are
recorded only when asked (``record_fsr``, ``record_contacts``), so a default run costs little more than
stepping (poses: two PyBullet calls per robot per sample, written into preallocated arrays).
The heading follows ``Physics.poses`` (body normal, [-pi, pi)).
"""

from __future__ import annotations

import math
from dataclasses import asdict
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
from smarticle_common.poses import body_heading
from smarticle_common.runs import Recording
from smarticle_common.topics import FSR_FACES

from .errors import SimError, SimTrouble
from .scenes import Scene
from .engine import Engine, EngineFactory
from .physics import ARM_JOINTS, Physics
from .runner import Controller, GaitController, Hook, Runner
from .settings import SimConfig

#: Builds the extra controllers of a trial (e.g. feedback) from its physics and gait controller; they run
#: before the gait controller in every tick.
ControllerFactory = Callable[[Engine, GaitController], Sequence[Controller]]


def scene_period(scene: Scene) -> float:
    """The gait period shared by the scene's robots (s); SimError if none runs a gait."""
    periods = {r.gait.period for r in scene.robots if r.gait is not None}
    if len(periods) != 1:
        raise SimError(f'scene {scene.name!r} must have robots with one common gait period, '
                       f'got {sorted(periods)}')
    return periods.pop()


#: Default recording rate (Hz): 32 samples per 1.6 s gait period, plenty for poses and pair coordinates.
DEFAULT_SAMPLE_RATE = 20.0


def default_sample_every(config: SimConfig, rate: float = DEFAULT_SAMPLE_RATE) -> int:
    """Control ticks between samples for about ``rate`` samples per second (at least 1)."""
    return max(1, round(1.0 / (rate * config.physics.control_tick)))


class _PoseReader:
    """Reads body poses and arm angles of every robot: two PyBullet calls per robot, one array write.

    The PyBullet calls are per robot anyway, so the heading is computed in the same pass with scalar
    math (numpy ufuncs on arrays of a few robots cost more than they save), and each sample is written
    into the preallocated recording arrays with one bulk assignment per array.
    """

    def __init__(self, physics: Physics) -> None:
        self._pose = physics.client.getBasePositionAndOrientation
        self._joints = physics.client.getJointStates
        self._bodies = physics.body_ids

    def read(self, poses: np.ndarray, arms: np.ndarray) -> None:
        """Write (N, 3) x, y, heading of the body normal into ``poses`` and (N, 2) alphas into ``arms``."""
        pose, joints = self._pose, self._joints
        pose_rows, arm_rows = [], []
        for body in self._bodies:
            (x, y, _), quat = pose(body)
            pose_rows.append((x, y, body_heading(*quat)))
            first, second = joints(body, ARM_JOINTS)
            arm_rows.append((first[0], second[0]))
        poses[...] = pose_rows
        arms[...] = arm_rows


class _EngineReader:
    """Reads body poses and arm angles of any engine (``Engine.poses``, ``Engine.arm_angles``)."""

    def __init__(self, physics: Engine) -> None:
        self._physics = physics

    def read(self, poses: np.ndarray, arms: np.ndarray) -> None:
        """Write (N, 3) x, y, heading of the body normal into ``poses`` and (N, 2) alphas into ``arms``."""
        poses[...] = self._physics.poses()
        arms[...] = self._physics.arm_angles()


def check_run_request(periods: float, sample_every: Any) -> int:
    """``sample_every`` as an int, or SimError if ``periods`` is not > 0 or ``sample_every`` not an integer >= 1."""
    if not (isinstance(periods, (int, float)) and math.isfinite(periods) and periods > 0):
        raise SimError(f'periods must be > 0, got {periods!r}')
    if isinstance(sample_every, bool) or not isinstance(sample_every, (int, np.integer)) or sample_every < 1:
        raise SimError(f'sample_every must be an integer >= 1 tick, got {sample_every!r}')
    return int(sample_every)


def run_trial(config: SimConfig, scene: Scene, periods: float, sample_every: int | None = None,
              record_fsr: bool = False, record_contacts: bool = False,
              progress: bool = False, controllers: ControllerFactory | None = None,
              start_time: float = 0.0, stop: Callable[[Runner], bool] | None = None,
              engine: EngineFactory | None = None, contacts_between_samples: bool = False) -> Recording:
    """Run ``scene`` for ``periods`` gait periods from a synchronised start at ``start_time`` and record it.

    Samples are taken every ``sample_every`` control ticks (the first at t = 0); the default is about
    ``DEFAULT_SAMPLE_RATE`` (20 Hz: every 3 ticks at the default 60 Hz control tick). Poses and arm
    angles are always recorded; FSR forces and robot-robot contacts only when asked (otherwise their
    arrays are zeros / False). A SimTrouble ends the trial early: the recording keeps every sample
    taken so far and ``meta['trouble']`` says why. ``meta['peak_tilt_deg']`` and ``meta['peak_overlap_mm']``
    say how close the run came to the trouble limits (the largest tilt and the deepest overlap at the
    trouble checks). ``controllers`` adds controllers (e.g. feedback) that act before the gait cores in
    every tick; they may record what they did themselves. ``stop`` (asked after every tick) ends the trial
    early; the recording keeps the samples taken so far. ``engine`` builds the world (default: Bullet's
    ``Physics``; its ``run_meta`` joins the meta). With ``contacts_between_samples`` a sample's contacts
    are the pairs that touched at any step since the sample before, not at its instant.
    """
    if sample_every is None:
        sample_every = default_sample_every(config)
    sample_every = check_run_request(periods, sample_every)
    period = scene_period(scene)
    n = len(scene.robots)
    n_faces = len(FSR_FACES)
    meta: dict[str, Any] = {
        'robot': asdict(config.robot), 'physics': asdict(config.physics), 'noise': asdict(config.noise),
        'scene': scene.name,
        'seed': scene.seed, 'periods': periods, 'period': period, 'start_time': start_time,
        'sample_every': sample_every,
        'sample_rate': 1.0 / (sample_every * config.physics.control_tick),
        'fsr_recorded': record_fsr, 'contacts_recorded': record_contacts,
        'fsr_faces': list(FSR_FACES), 'trouble': '',
        'initial': [{'x': r.x, 'y': r.y, 'heading': r.heading, 'alpha1': r.alpha1, 'alpha2': r.alpha2,
                     'phase': r.gait.phase if r.gait else None,
                     'alpha_max': r.gait.alpha_max if r.gait else None, **({'held': True} if r.held else {})}
                    for r in scene.robots],
    }
    physics: Engine = (engine or Physics)(config, scene)
    meta.update(physics.run_meta())
    try:
        gaits = GaitController.for_scene(physics)
        extra = list(controllers(physics, gaits)) if controllers is not None else []
        runner = Runner(physics, [*extra, gaits])
        ticks = runner.ticks_for(start_time + periods * period)
        ticks_per_period = max(1, runner.ticks_for(period))
        capacity = ticks // sample_every + 1
        times = np.empty(capacity)
        poses = np.empty((capacity, n, 3))
        arms = np.empty((capacity, n, 2))
        fsrs = np.zeros((capacity if record_fsr else 0, n, n_faces))
        touching = np.zeros((capacity if record_contacts else 0, n, n), dtype=bool)
        reader = _PoseReader(physics) if isinstance(physics, Physics) else _EngineReader(physics)
        bar = _progress_bar(ticks, progress)
        taken = 0
        seen = np.zeros((n, n), dtype=bool)   # contacts since the last sample (contacts_between_samples)

        def sample(_: Runner) -> None:
            nonlocal taken
            times[taken] = physics.time
            reader.read(poses[taken], arms[taken])
            if record_fsr:
                fsrs[taken] = physics.fsr()
            if record_contacts:
                if contacts_between_samples:
                    touching[taken] = seen
                    seen[:] = False
                else:
                    touching[taken] = physics.robot_contacts()
            taken += 1

        if record_contacts and contacts_between_samples:
            def watch(_: Runner) -> None:
                seen[...] |= physics.robot_contacts()
            runner.step_hooks.append(watch)

        hooks = [Hook(sample_every, sample)]
        if bar is not None:
            hooks.append(Hook(ticks_per_period, lambda _: bar.update(ticks_per_period), at_start=False))
        gaits.start(start_time)
        try:
            runner.run(ticks, hooks, stop)
        except SimTrouble as trouble:
            meta['trouble'] = str(trouble)
        finally:
            if bar is not None:
                bar.close()
            meta['peak_tilt_deg'] = math.degrees(physics.peak_tilt)
            meta['peak_overlap_mm'] = physics.peak_overlap * 1000.0
    finally:
        physics.close()
    fsr_out = fsrs[:taken] if record_fsr else np.zeros((taken, n, n_faces))
    contacts_out = touching[:taken] if record_contacts else np.zeros((taken, n, n), dtype=bool)
    return Recording(times[:taken].copy(), poses[:taken].copy(), arms[:taken].copy(), fsr_out.copy(),
                     contacts_out.copy(), config.robot.body_length, meta)


def _progress_bar(total: int, enabled: bool) -> Any:
    """A tqdm bar counting control ticks, or None."""
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit='tick', desc='sim', dynamic_ncols=True)


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
