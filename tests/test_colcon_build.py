"""`colcon build` of ros_ws gives an install space where `ros2 run` and ament_index find everything."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {'smarticle_common': 'smarticle_common', 'smarticle_driver': 'smarticle_driver',
            'smarticle_sim': 'smarticle_sim', 'smarticle_feedback': 'smarticle_feedback',
            'smarticle_tracking': 'smarticle_tracking', 'smarticle_bags': 'bags/smarticle_bags',
            'smarticle_experiments': 'smarticle_experiments', 'smarticle_bringup': 'smarticle_bringup'}
IGNORE = shutil.ignore_patterns('__pycache__', '*.egg-info', '*.pyc', 'build', 'install', 'log')


def console_scripts(package: str) -> list[str]:
    """Console scripts the package declares (as installed in this environment from its setup.py)."""
    dist = metadata.distribution(package)
    return sorted(ep.name for ep in dist.entry_points if ep.group == 'console_scripts')


@pytest.fixture(scope='module')
def install_space(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Copy the workspace to a temporary folder and colcon-build it there."""
    work = tmp_path_factory.mktemp('colcon')
    for folder in PACKAGES.values():
        shutil.copytree(ROOT / folder, work / folder, ignore=IGNORE)
    shutil.copytree(ROOT / 'ros_ws', work / 'ros_ws', symlinks=True, ignore=IGNORE)
    colcon = Path(sys.executable).parent / 'colcon'
    result = subprocess.run([str(colcon), 'build', '--event-handlers', 'console_direct-'],
                            cwd=work / 'ros_ws', capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return work / 'ros_ws' / 'install'


def sourced_env(install: Path) -> dict[str, str]:
    """The environment after `source install/setup.bash`."""
    out = subprocess.run(['bash', '-c', f'source {install}/setup.bash && env -0'],
                         capture_output=True, check=True, timeout=60).stdout
    return dict(item.split('=', 1) for item in out.decode().split('\0') if '=' in item)


@pytest.mark.slow
def test_every_executable_is_where_ros2_run_looks(install_space: Path) -> None:
    for package in PACKAGES:
        for script in console_scripts(package):
            exe = install_space / package / 'lib' / package / script
            assert exe.is_file() and os.access(exe, os.X_OK), f'missing {exe}'
    assert console_scripts('smarticle_driver') >= ['gait', 'servo_bridge']


@pytest.mark.slow
def test_ament_index_finds_every_package_and_its_config(install_space: Path) -> None:
    env = sourced_env(install_space)
    code = ('from ament_index_python.packages import get_package_share_directory as g, '
            'get_packages_with_prefixes;'
            'import sys, pathlib; names=sys.argv[1:];'
            'print(all(n in get_packages_with_prefixes() for n in names));'
            'print((pathlib.Path(g("smarticle_driver"))/"config"/"gait.yaml").is_file())')
    out = subprocess.run([sys.executable, '-c', code, *PACKAGES], env=env, capture_output=True,
                         text=True, check=True, timeout=60).stdout.split()
    assert out == ['True', 'True']


@pytest.mark.slow
@pytest.mark.integration
def test_built_gait_executable_runs_from_the_install_space_and_publishes(install_space: Path) -> None:
    import rclpy
    from sensor_msgs.msg import JointState

    from smarticle_common import topics

    env = {**sourced_env(install_space), 'ROS_DOMAIN_ID': os.environ['ROS_DOMAIN_ID'],
           'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}
    exe = install_space / 'smarticle_driver' / 'lib' / 'smarticle_driver' / 'gait'
    params = install_space / 'smarticle_driver' / 'share' / 'smarticle_driver' / 'config' / 'gait.yaml'
    proc = subprocess.Popen([sys.executable, str(exe), '--ros-args', '--params-file', str(params),
                             '-p', 'robot_id:=7', '-p', 'autostart:=true'],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    rclpy.init()
    node = rclpy.create_node('colcon_check')
    got: list[JointState] = []
    node.create_subscription(JointState, topics.topic('joint_commands', 7), got.append,
                             topics.qos_profile(topics.Qos.COMMAND))
    try:
        deadline = time.monotonic() + 20.0
        while len(got) < 3 and time.monotonic() < deadline and proc.poll() is None:
            rclpy.spin_once(node, timeout_sec=0.1)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
        proc.terminate()
        output = proc.communicate(timeout=10)[0].decode(errors='replace')
    assert len(got) >= 3, output
    assert list(got[0].name) == list(topics.JOINT_NAMES)
    assert str(install_space) in subprocess.run(
        [sys.executable, '-c', 'import smarticle_driver; print(smarticle_driver.__file__)'],
        env=env, capture_output=True, text=True, check=True).stdout


@pytest.mark.slow
@pytest.mark.integration
def test_the_bringup_launch_files_and_parameter_file_are_installed_for_ros2_launch(install_space: Path) -> None:
    share = install_space / 'smarticle_bringup' / 'share' / 'smarticle_bringup'
    shipped = sorted(p.name for p in (ROOT / 'smarticle_bringup' / 'launch').glob('*.launch.xml'))
    assert shipped and sorted(p.name for p in (share / 'launch').glob('*.launch.xml')) == shipped
    assert (share / 'config' / 'stack.yaml').read_text() == \
        (ROOT / 'smarticle_bringup' / 'config' / 'stack.yaml').read_text()
