"""The architecture of docs/architecture.md, checked: packages import only layers below them, no circles.

Every import statement of every module (top level and inside functions) counts, so a circle cannot hide
behind a deferred import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: Package -> layer. A package may import packages of lower layers only; packages of one layer are
#: independent of each other. docs/architecture.md draws this.
LAYERS: dict[str, int] = {
    'smarticle_common': 0,
    'smarticle_driver': 1,
    'smarticle_feedback': 1,
    'smarticle_sim': 1,
    'smarticle_tracking': 1,
    'smarticle_bags': 2,
    'smarticle_experiments': 3,
    'smarticle_bringup': 3,
    'smarticle_example_controller': 4,    # examples/: a user's own package, on top of the stack
}

#: The folders of each package's code (its Python package and its scripts).
PACKAGE_DIRS: dict[str, Path] = {
    name: (ROOT / 'bags' / name if name == 'smarticle_bags' else
           ROOT / 'examples' / name if name == 'smarticle_example_controller' else ROOT / name) for name in LAYERS
}


def package_files(package: str) -> list[Path]:
    """Every .py file of ``package``'s folder (modules, scripts, benchmarks), not its build output."""
    folder = PACKAGE_DIRS[package]
    return sorted(p for p in folder.rglob('*.py') if 'build' not in p.parts and p.name != 'setup.py')


def module_name(package: str, path: Path) -> str:
    """Dotted module name of ``path`` inside ``package`` (scripts get a name under their folder)."""
    rel = path.relative_to(PACKAGE_DIRS[package]).with_suffix('')
    parts = list(rel.parts)
    if parts[-1] == '__init__':
        parts = parts[:-1]
    return '.'.join(parts) if parts and parts[0] == package else '.'.join([package, *parts])


def imports_of(path: Path, module: str) -> set[str]:
    """Absolute names of every module ``path`` imports (relative imports resolved against ``module``)."""
    tree = ast.parse(path.read_text(encoding='utf-8'), filename=str(path))
    is_package = path.name == '__init__.py'
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split('.')
                base = base[:len(base) - node.level + (1 if is_package else 0)]
                target = '.'.join([*base, node.module] if node.module else base)
            else:
                target = node.module or ''
            found.add(target)
            found.update(f'{target}.{alias.name}' for alias in node.names)
    return found


def graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports."""
    modules: dict[str, Path] = {}
    for package in LAYERS:
        for path in package_files(package):
            modules[module_name(package, path)] = path
    edges: dict[str, set[str]] = {}
    for name, path in modules.items():
        edges[name] = {m for m in imports_of(path, name) if m in modules and m != name}
    return edges


def test_every_package_is_on_the_map() -> None:
    present = {p.parent.name for pattern in ('*/package.xml', '*/*/package.xml') for p in ROOT.glob(pattern)}
    assert present <= set(LAYERS), f'packages without a layer: {sorted(present - set(LAYERS))}'


@pytest.mark.parametrize('package', sorted(LAYERS))
def test_packages_import_only_layers_below(package: str) -> None:
    wrong = []
    for path in package_files(package):
        for target in imports_of(path, module_name(package, path)):
            other = target.split('.')[0]
            if other in LAYERS and other != package and LAYERS[other] >= LAYERS[package]:
                wrong.append(f'{path.relative_to(ROOT)} imports {target} (layer {LAYERS[other]} >= '
                             f'{LAYERS[package]})')
    assert not wrong, '\n'.join(wrong)


def test_no_import_circle_between_modules() -> None:
    edges = graph()
    state: dict[str, int] = {}
    stack: list[str] = []
    circles: list[list[str]] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 1:
                circles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(edges):
        if node not in state:
            visit(node)
    assert not circles, '\n'.join(' -> '.join(c) for c in circles)


def test_the_checker_sees_a_circle_and_an_upward_import(tmp_path: Path) -> None:
    """The checks above can fail: a planted upward import and circle are found."""
    up = tmp_path / 'mod.py'
    up.write_text('def f():\n    from smarticle_bringup.demo import main\n    from . import other\n')
    found = imports_of(up, 'smarticle_sim.mod')
    assert 'smarticle_bringup.demo' in found and 'smarticle_sim.other' in found
