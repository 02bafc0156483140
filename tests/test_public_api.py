"""Each package's public API: ``__all__`` names what the docs and examples import, every name resolves, and
every exception class of a package derives from its one error root (exported too)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Package -> (source folder, its error root).
PACKAGES = {
    'smarticle_common': ('smarticle_common/smarticle_common', 'CommonError'),
    'smarticle_sim': ('smarticle_sim/smarticle_sim', 'SimError'),
    'smarticle_driver': ('smarticle_driver/smarticle_driver', 'DriverError'),
    'smarticle_feedback': ('smarticle_feedback/smarticle_feedback', 'FeedbackError'),
    'smarticle_tracking': ('smarticle_tracking/smarticle_tracking', 'TrackingError'),
    'smarticle_bags': ('bags/smarticle_bags/smarticle_bags', 'BagError'),
    'smarticle_experiments': ('smarticle_experiments/smarticle_experiments', 'ExperimentError'),
    'smarticle_bringup': ('smarticle_bringup/smarticle_bringup', 'BringupError'),
}


def exception_classes(folder: Path) -> list[tuple[str, str]]:
    """(module, class) of every class in the package whose name ends in Error (or is SimTrouble)."""
    found = []
    for path in sorted(folder.glob('*.py')):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.ClassDef) and (node.name.endswith('Error') or node.name == 'SimTrouble'):
                found.append((path.stem, node.name))
    return found


@pytest.mark.parametrize('package', sorted(PACKAGES))
def test_every_public_name_resolves_and_the_error_root_is_exported(package: str) -> None:
    module = importlib.import_module(package)
    names = list(module.__all__)
    assert names and len(set(names)) == len(names)
    for name in names:
        assert getattr(module, name) is not None
    assert PACKAGES[package][1] in names


@pytest.mark.parametrize('package', sorted(PACKAGES))
def test_every_error_derives_from_the_package_root(package: str) -> None:
    folder, root_name = PACKAGES[package]
    root = getattr(importlib.import_module(f'{package}.errors'), root_name)
    classes = exception_classes(ROOT / folder)
    assert classes
    for module_name, class_name in classes:
        cls = getattr(importlib.import_module(f'{package}.{module_name}'), class_name)
        assert issubclass(cls, root), f'{package}.{module_name}.{class_name} does not derive from {root_name}'


def test_no_two_packages_share_an_error_name() -> None:
    """One ``SpecError``, one ``CalibrationError``: a name says which package raised it."""
    owners: dict[str, list[str]] = {}
    for package, (folder, _) in PACKAGES.items():
        for _, class_name in exception_classes(ROOT / folder):
            owners.setdefault(class_name, []).append(package)
    shared = {name: where for name, where in owners.items() if len(set(where)) > 1}
    assert not shared
