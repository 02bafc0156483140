"""Every package a board can install: its package.xml names, as rosdep keys, exactly what its modules import.

``rosdep install --from-paths ros_ws/src`` on a robot board installs what the package.xml files say; a
missing key is a node that fails on the board with an ImportError, an extra one a needless install.
Imports are read from every module (top level and inside functions) and mapped to rosdep keys by
``ROSDEP_KEYS``; keys ending in ``-pip`` are rosdep's pip keys (installed with pip, not apt): see
docs/bringup.md. Every key must resolve: against rosdistro's rules (the copy in
``ros_ws/rosdep/rosdistro_snapshot.yaml``), Jazzy's ROS packages (``ros_ws/rosdep/ros_packages.yaml``) or
the project's own rosdep source (``ros_ws/rosdep/smarticle.yaml``).
"""

from __future__ import annotations

import ast
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]

#: Import name -> rosdep key of every third-party module the packages import (apt keys, and pip keys
#: ending in -pip where Ubuntu 24.04 has no package). ROS message and client packages are their own key.
ROSDEP_KEYS: dict[str, str] = {
    'numpy': 'python3-numpy',
    'yaml': 'python3-yaml',
    'serial': 'python3-serial',
    'matplotlib': 'python3-matplotlib',
    'cv2': 'python3-opencv',
    'scipy': 'python3-scipy',
    'pandas': 'python3-pandas',
    'tqdm': 'python3-tqdm',
    'dask': 'python3-distributed-pip',
    'distributed': 'python3-distributed-pip',
    'pyarrow': 'python3-pyarrow-pip',
    'pybullet': 'python3-pybullet-pip',
    'pybullet_data': 'python3-pybullet-pip',
    'pybullet_utils': 'python3-pybullet-pip',
    'zstandard': 'python3-zstandard',
    'lz4': 'python3-lz4',
    'pytest': 'python3-pytest',
    'mcap': 'python3-mcap-pip',
    'mcap_ros2': 'python3-mcap-ros2-support-pip',
    'foxglove': 'python3-foxglove-sdk-pip',
    'mujoco': 'python3-mujoco-pip',
    'PIL': 'python3-pil',
}
#: ROS 2 packages the code imports by their own name (client library, message packages).
ROS_PACKAGES = {'rclpy', 'std_msgs', 'sensor_msgs', 'geometry_msgs', 'diagnostic_msgs', 'visualization_msgs',
                'rosgraph_msgs', 'rcl_interfaces', 'lifecycle_msgs', 'builtin_interfaces', 'ament_index_python',
                'tf2_msgs'}
PACKAGE_XMLS = (sorted(ROOT.glob('*/package.xml')) + sorted(ROOT.glob('bags/*/package.xml'))
                + sorted(ROOT.glob('examples/*/package.xml')))
OURS = {p.parent.name for p in PACKAGE_XMLS}
#: Keys a package needs at run time without importing them: pandas writes Parquet through pyarrow.
RUNTIME_ONLY = {'smarticle_experiments': {'python3-pyarrow-pip': 'pandas.DataFrame.to_parquet (store.py)'}}
ROSDEP = ROOT / 'ros_ws' / 'rosdep'
DEPEND_TAGS = ('depend', 'exec_depend', 'build_depend', 'build_export_depend', 'buildtool_depend',
               'test_depend', 'doc_depend')


def declared(package_xml: Path) -> set[str]:
    """Run-time dependencies of a package.xml (<depend>, <exec_depend>)."""
    root = ET.parse(package_xml).getroot()
    return {e.text.strip() for tag in ('depend', 'exec_depend') for e in root.iter(tag) if e.text}


def imported(folder: Path, package: str) -> dict[str, str]:
    """Rosdep key -> one module that needs it, for every import of the package's modules."""
    stdlib = set(sys.stdlib_module_names)
    needs: dict[str, str] = {}
    for path in sorted((folder / package).rglob('*.py')):
        tree = ast.parse(path.read_text(encoding='utf-8'))
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else [])
            for name in names:
                top = name.split('.')[0]
                if top in stdlib or top == package or top == '__future__':
                    continue
                key = top if top in ROS_PACKAGES or top in OURS else ROSDEP_KEYS.get(top)
                assert key is not None, f'{path.relative_to(ROOT)} imports {top!r}: add its rosdep key to ROSDEP_KEYS'
                needs.setdefault(key, str(path.relative_to(ROOT)))
    for path in sorted((folder / 'launch').glob('*.launch.xml')):     # nodes its launch files start
        for node in ET.parse(path).getroot().iter('node'):
            if '$(' not in node.attrib['pkg']:      # a user's package, given as a launch argument
                needs.setdefault(node.attrib['pkg'], str(path.relative_to(ROOT)))
    needs.pop(package, None)
    needs.update(RUNTIME_ONLY.get(package, {}))
    return needs


@pytest.mark.parametrize('package_xml', PACKAGE_XMLS, ids=lambda p: p.parent.name)
def test_package_xml_names_exactly_what_the_modules_import(package_xml: Path) -> None:
    package = package_xml.parent.name
    needs = imported(package_xml.parent, package)
    have = declared(package_xml)
    missing = {key: where for key, where in needs.items() if key not in have}
    assert not missing, f'{package_xml.relative_to(ROOT)} lacks <exec_depend> for: {missing}'
    # message packages are also imported by name through the topic contract (topics.message_class), so
    # only Python libraries and our own packages must be imported statically
    unused = sorted(k for k in have - set(needs) if k not in ROS_PACKAGES)
    assert not unused, f'{package_xml.relative_to(ROOT)} declares keys no module imports: {unused}'


def test_the_readme_apt_line_installs_the_board_packages() -> None:
    """The README's apt line covers the apt keys of the packages a board runs (driver, feedback, common)."""
    readme = (ROOT / 'README.md').read_text(encoding='utf-8')
    line = next(line for line in readme.splitlines() if line.startswith('sudo apt install'))
    board = set()
    for name in ('smarticle_common', 'smarticle_driver', 'smarticle_feedback', 'smarticle_bringup'):
        board |= {key for key in declared(ROOT / name / 'package.xml')
                  if key.startswith('python3-') and not key.endswith('-pip')}
    missing = sorted(board - set(line.split()))
    assert not missing, f'the README apt line misses {missing}'
    assert 'ros-jazzy-ros-base' in line.split()


def test_every_pip_key_is_documented() -> None:
    doc = (ROOT / 'docs' / 'bringup.md').read_text(encoding='utf-8')
    for key in sorted({k for k in ROSDEP_KEYS.values() if k.endswith('-pip')}):
        assert f'`{key}`' in doc, f'docs/bringup.md does not list the pip key {key}'


def _rules(name: str) -> dict[str, object]:
    return yaml.safe_load((ROSDEP / name).read_text(encoding='utf-8'))


@pytest.mark.parametrize('package_xml', PACKAGE_XMLS, ids=lambda p: p.parent.name)
def test_every_rosdep_key_resolves(package_xml: Path) -> None:
    """Each key of every dependency tag is ours, a Jazzy ROS package, a rosdistro rule or one of our rules."""
    upstream, ros, custom = (_rules(n) for n in ('rosdistro_snapshot.yaml', 'ros_packages.yaml', 'smarticle.yaml'))
    root = ET.parse(package_xml).getroot()
    keys = {e.text.strip() for tag in DEPEND_TAGS for e in root.iter(tag) if e.text}
    unresolved = sorted(k for k in keys if k not in OURS and k not in ros and k not in upstream and k not in custom)
    assert not unresolved, (f'{package_xml.relative_to(ROOT)}: no rosdep rule for {unresolved}; add the '
                            'rule to ros_ws/rosdep/smarticle.yaml (or its upstream entry to the snapshot)')
    for key in keys & set(custom):
        rule = custom[key]
        assert isinstance(rule, dict) and 'ubuntu' in rule, f'smarticle.yaml: {key} has no ubuntu rule'


def test_the_project_rules_add_keys_rosdistro_lacks_and_pin_what_requirements_name() -> None:
    """smarticle.yaml shadows no rosdistro key; its pip packages are the ones requirements.txt installs."""
    upstream, custom = _rules('rosdistro_snapshot.yaml'), _rules('smarticle.yaml')
    assert not set(upstream) & set(custom)
    wanted: set[str] = set()
    for line in (ROOT / 'requirements.txt').read_text(encoding='utf-8').splitlines():
        if line.strip() and not line.startswith('#'):       # name[extra,...]>=version: the extras install too
            name, _, extras = line.split('>=')[0].strip().lower().partition('[')
            wanted |= {name, *extras.rstrip(']').split(',')} - {''}
    for key, rule in custom.items():
        assert key.endswith('-pip') == ('pip' in str(rule)), f'{key}: a -pip key has pip rules, others apt'
        pip = rule['ubuntu'].get('pip') if isinstance(rule['ubuntu'], dict) else None
        for name in (pip or {}).get('packages', []):
            assert name.lower() in wanted, f'{key}: {name} is not in requirements.txt'
    used = set().union(*(declared(p) for p in PACKAGE_XMLS))
    assert set(custom) <= used, f'smarticle.yaml has rules no package uses: {sorted(set(custom) - used)}'
    assert set(upstream) <= used | {'python3-pytest'}


def test_bringup_doc_adds_the_project_rosdep_source() -> None:
    doc = (ROOT / 'docs' / 'bringup.md').read_text(encoding='utf-8')
    assert 'yaml file://' in doc and 'ros_ws/rosdep/smarticle.yaml' in doc
    for key in _rules('smarticle.yaml'):
        assert f'`{key}`' in doc, f'docs/bringup.md does not list {key}'
