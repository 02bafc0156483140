"""The one run format on disk: a recorded run (batch trial, demo, bag export) as arrays in an npz file.

S samples, N robots, arrays:

* ``time`` (S,) s; ``poses`` (S, N, 3) x (m), y (m), heading of the body normal (rad, NaN where unseen);
* ``arm_angles`` (S, N, 2) rad (NaN if not known); ``fsr`` (S, N, 4) N, faces in ``fsr_faces`` order
  (zeros if not recorded); ``contacts`` (S, N, N) bool, robot-robot contact at the sample (False if not
  recorded);
* ``body_length`` () m; ``meta`` () JSON string of the settings, scene and outcome (``trouble`` says why
  a run ended early; ``fsr_recorded`` and ``contacts_recorded`` whether those arrays hold data).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .topics import FSR_FACES


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

    @classmethod
    def from_poses(cls, time: np.ndarray, poses: np.ndarray, body_length: float,
                   meta: dict[str, Any] | None = None) -> Recording:
        """A recording of poses only (e.g. from a tracker or a bag): arm angles NaN, no FSR, no contacts."""
        s, n = poses.shape[:2]
        info = {'fsr_recorded': False, 'contacts_recorded': False, 'arm_angles_recorded': False,
                'fsr_faces': list(FSR_FACES), 'trouble': '', **(meta or {})}
        return cls(np.asarray(time, dtype=float), np.asarray(poses, dtype=float), np.full((s, n, 2), np.nan),
                   np.zeros((s, n, len(FSR_FACES))), np.zeros((s, n, n), dtype=bool), float(body_length), info)


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
