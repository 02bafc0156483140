"""The PyBullet simulation of smarticles: settings, scenes, the physics world (and MuJoCo's, behind one engine
interface), the one stepping loop (``Runner``)."""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'SimConfig': 'settings', 'PhysicsConfig': 'settings', 'NoiseConfig': 'settings',
    'NotConvergedWarning': 'settings',
    'Scene': 'scenes', 'RobotPlacement': 'scenes', 'dense_scene': 'scenes', 'pair_scene': 'scenes',
    'random_scene': 'scenes',
    'Runner': 'runner', 'GaitController': 'runner', 'FeedbackController': 'runner',
    'Physics': 'physics', 'PhysicsState': 'engine', 'Engine': 'engine', 'MujocoPhysics': 'mujoco_engine',
    'run_trial': 'batch',
    'SimError': 'errors', 'ConfigError': 'errors', 'SceneError': 'errors', 'SimTrouble': 'errors',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
