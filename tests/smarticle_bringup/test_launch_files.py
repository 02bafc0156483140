"""The launch-file reader: the shipped files resolve as ros2 launch would, and every bad input is one line."""

from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path

import pytest

from smarticle_bringup import launcher
from smarticle_bringup.launch_files import (LaunchFileError, ParamFile, ParamValue, evaluate, package_share,
                                            resolve)

from tests.helpers.ros import ROOT

LAUNCH = ROOT / 'smarticle_bringup' / 'launch'
STACK = ROOT / 'smarticle_bringup' / 'config' / 'stack.yaml'


def names(plan: object) -> list[str]:
    return [node.full_name for node in plan.nodes]  # type: ignore[attr-defined]


def params_of(node: object) -> dict[str, str]:
    return {p.name: p.value for p in node.params if isinstance(p, ParamValue)}  # type: ignore[attr-defined]


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding='utf-8')
    return path


# ------------------------------------------------------------------------------------------ shipped files
@pytest.mark.parametrize('name', sorted(p.name for p in LAUNCH.glob('*.launch.xml')))
def test_every_shipped_file_resolves_with_its_defaults(name: str) -> None:
    given = {'robots': '2', 'params_file': str(STACK)} if name == 'sim_robots.launch.xml' else {}
    plan = resolve(LAUNCH / name, given)             # packages and executables checked too
    assert plan.nodes
    for node in plan.nodes:
        files = [p.path for p in node.params if isinstance(p, ParamFile)]
        assert all(Path(f).is_file() for f in files)
        if node.executable not in ('recorder', 'smarticle-compose'):
            assert files == [str(STACK)], node.full_name     # every node reads the one shared file


def test_board_puts_one_robot_in_its_namespace() -> None:
    plan = resolve(LAUNCH / 'board.launch.xml', {'robot': '3', 'port': '/dev/ttyUSB1'})
    assert names(plan) == ['/smarticle_3/servo_bridge', '/smarticle_3/gait', '/smarticle_3/feedback']
    bridge, gait, _ = plan.nodes
    assert params_of(bridge) == {'port': '/dev/ttyUSB1', 'calibration_dir': str(ROOT / 'smarticle_driver' / 'config'),
                                 'autostart': 'true'}
    calibrated = resolve(LAUNCH / 'board.launch.xml', {'calibration': 'robot3/'})   # smarticle-board-calibrate's --out
    assert params_of(calibrated.nodes[0])['calibration_dir'] == 'robot3/'
    assert params_of(gait) == {'start_at': '-1.0'}
    args = gait.ros_arguments()
    assert args[:5] == ['--ros-args', '-r', '__node:=gait', '-r', '__ns:=/smarticle_3']
    assert args.index('--params-file') < args.index('start_at:=-1.0')   # the value after the file wins
    assert names(resolve(LAUNCH / 'board.launch.xml', {'feedback': 'false'}))[-1] == '/smarticle_0/gait'


def test_sim_separate_starts_every_robot_and_composed_one_host() -> None:
    plan = resolve(LAUNCH / 'sim.launch.xml', {'robots': '3', 'composed': 'false', 'record': 'true'})
    assert names(plan) == ['/sim_bridge', '/glider_monitor',
                           '/smarticle_0/gait', '/smarticle_0/feedback', '/smarticle_1/gait',
                           '/smarticle_1/feedback', '/smarticle_2/gait', '/smarticle_2/feedback', '/recorder']
    assert [n.on_exit_shutdown for n in plan.nodes].count(True) == 1 and plan.nodes[0].on_exit_shutdown
    assert params_of(plan.nodes[0])['robots'] == '3'
    assert params_of(plan.nodes[0])['wait_for_subscribers'] == '2'     # the monitor, and the recorder on top
    assert params_of(plan.nodes[-1])['use_sim_time'] == 'true'          # the bag's log time in sim time
    assert params_of(plan.nodes[2]) == {'lockstep': 'true', 'wait_for_feedback': 'true', 'use_sim_time': 'true'}
    assert params_of(plan.nodes[3]) == {'lockstep': 'true', 'use_sim_time': 'true'}     # the feedback node
    assert params_of(plan.nodes[-1])['output'] == ''
    assert "output:=''" in plan.nodes[-1].ros_arguments()          # an empty value is the empty string
    assert 'regex' not in params_of(plan.nodes[-1])                  # the arena topics only, unless asked
    robots = resolve(LAUNCH / 'sim.launch.xml', {'robots': '2', 'record': 'true', 'record_robots': 'true'})
    pattern = params_of(robots.nodes[-1])['regex']
    assert [t for t in ('/smarticle_1/joint_states', '/smarticle_0/fsr', '/smarticle_1/joint_commands',
                        '/smarticle_0/halt', '/smarticles/poses') if re.search(pattern, t)] == [
        '/smarticle_1/joint_states', '/smarticle_0/fsr', '/smarticle_1/joint_commands']
    open_loop = resolve(LAUNCH / 'sim.launch.xml', {'robots': '2', 'composed': 'false', 'feedback': 'false'})
    assert names(open_loop) == ['/sim_bridge', '/glider_monitor', '/smarticle_0/gait', '/smarticle_1/gait']
    assert params_of(open_loop.nodes[2])['wait_for_feedback'] == 'false'      # no feedback node to wait for
    composed = resolve(LAUNCH / 'sim.launch.xml', {'robots': '5', 'view': 'true'})
    host, monitor, view = composed.nodes
    assert host.executable == 'smarticle-compose' and host.on_exit_shutdown and view.executable == 'smarticle-view'
    assert host.args[0] == str(LAUNCH / 'sim_stack.launch.xml') and 'robots:=5' in host.args
    # the monitor beside the host, in its own process; on the wall clock, so /clock stays in the host
    assert 'monitor:=false' in host.args and monitor.executable == 'glider_monitor'
    assert 'use_sim_time' not in params_of(monitor)
    assert names(resolve(LAUNCH / 'sim_stack.launch.xml', {'robots': '1', 'monitor': 'false'})) == [
        '/sim_bridge', '/smarticle_0/gait', '/smarticle_0/feedback']
    one = resolve(LAUNCH / 'sim.launch.xml', {'robots': '1', 'composed': 'false'})
    assert names(one)[2:] == ['/smarticle_0/gait', '/smarticle_0/feedback']


def test_controller_and_feedback_arguments_put_the_users_nodes_in_place() -> None:
    user = 'smarticle_example_controller/square_stop'
    plan = resolve(LAUNCH / 'sim.launch.xml', {'robots': '3', 'composed': 'false', 'controller': user,
                                               'controller_robots': '0, 2', 'feedback': 'none'})
    assert names(plan)[2:] == ['/smarticle_0/square_stop', '/smarticle_1/gait', '/smarticle_2/square_stop']
    assert params_of(plan.nodes[2]) == {'robot_id': '0', 'lockstep': 'true', 'wait_for_feedback': 'false',
                                        'use_sim_time': 'true'}
    own = resolve(LAUNCH / 'sim.launch.xml', {'robots': '2', 'composed': 'false', 'feedback': 'true',
                                              'feedback_robots': '1', 'controller_params': str(STACK)})
    assert names(own)[2:] == ['/smarticle_0/gait', '/smarticle_1/gait', '/smarticle_1/feedback']
    assert [params_of(n)['wait_for_feedback'] for n in own.nodes[2:4]] == ['false', 'true']
    # composed: the stack's nodes in the host, the user's nodes as processes beside it
    composed = resolve(LAUNCH / 'sim.launch.xml', {'robots': '2', 'controller': user, 'feedback': user})
    assert [n.executable for n in composed.nodes] == ['smarticle-compose', 'glider_monitor'] + ['square_stop'] * 4
    assert 'part:=composable' in composed.nodes[0].args and f'controller:={user}' in composed.nodes[0].args
    hosted = resolve(LAUNCH / 'sim_stack.launch.xml', {'robots': '2', 'controller': user, 'feedback': user,
                                                       'part': 'composable'})
    assert names(hosted) == ['/sim_bridge', '/glider_monitor']
    board = resolve(LAUNCH / 'board.launch.xml', {'robot': '2', 'controller': user, 'feedback': 'none'})
    assert names(board) == ['/smarticle_2/servo_bridge', '/smarticle_2/square_stop']
    assert params_of(board.nodes[1]) == {'robot_id': '2', 'start_at': '-1.0'}
    feedback_only = resolve(LAUNCH / 'board.launch.xml', {'feedback': user})
    assert names(feedback_only) == ['/smarticle_0/servo_bridge', '/smarticle_0/gait', '/smarticle_0/square_stop']
    with pytest.raises(LaunchFileError, match="package 'smarticle_nope'"):
        resolve(LAUNCH / 'sim.launch.xml', {'composed': 'false', 'controller': 'smarticle_nope/x'})


def test_overhead_runs_tracker_monitor_and_recorder() -> None:
    plan = resolve(LAUNCH / 'overhead.launch.xml', {'calibration_file': 'rig.yaml', 'bag': 'run1'})
    assert names(plan) == ['/tracker', '/glider_monitor', '/recorder']
    assert params_of(plan.nodes[0]) == {'calibration_file': 'rig.yaml'}
    assert params_of(plan.nodes[1]) == {'start_at': '-1.0'}
    assert names(resolve(LAUNCH / 'overhead.launch.xml', {'record': 'false'})) == ['/tracker', '/glider_monitor']


def test_find_pkg_share_is_the_package_folder_in_a_checkout() -> None:
    assert package_share('smarticle_bringup') == ROOT / 'smarticle_bringup'
    assert package_share('smarticle_bags') == ROOT / 'bags' / 'smarticle_bags'


# ------------------------------------------------------------------------------------------ the subset
def test_substitutions_conditions_groups_and_includes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv('SMARTICLE_TEST_PORT', '/dev/ttyX')
    write(tmp_path, 'p.yaml', '/**:\n  ros__parameters:\n    period: 1.6\n')
    write(tmp_path, 'child.launch.xml', '''<launch>
      <arg name="k"/>
      <node pkg="smarticle_driver" exec="gait" name="gait_$(var k)" namespace="inner">
        <param from="$(dirname)/p.yaml"/>
      </node>
    </launch>''')
    path = write(tmp_path, 'main.launch.xml', '''<launch>
      <arg name="n" default="2"/>
      <arg name="flag" default="false"/>
      <let name="double" value="$(eval '$(var n) * 2')"/>
      <group>
        <push-ros-namespace namespace="outer"/>
        <let name="n" value="99"/>
        <node pkg="smarticle_driver" exec="gait" name="a">
          <param name="x" value="$(var n)"/>
          <param name="y" value="$(var double)" unless="$(var flag)"/>
          <param name="z" value="no" if="$(var flag)"/>
          <remap from="/smarticles/start" to="/other/start"/>
        </node>
        <include file="child.launch.xml"><arg name="k" value="$(var n)"/></include>
      </group>
      <node pkg="smarticle_driver" exec="gait" name="b" namespace="/abs"
            args="--flag $(env SMARTICLE_TEST_PORT) $(env SMARTICLE_UNSET fallback)">
        <param name="n" value="$(var n)"/>
      </node>
      <node pkg="smarticle_driver" exec="gait" name="c"
            if="$(eval '$(var n) &gt; 5 or &quot;$(var flag)&quot; == &quot;true&quot;')"/>
    </launch>''')
    plan = resolve(path)
    assert plan.arguments == {'n': '2', 'flag': 'false'}
    assert names(plan) == ['/outer/a', '/outer/inner/gait_99', '/abs/b']
    a, child, b = plan.nodes
    assert params_of(a) == {'x': '99', 'y': '4'} and a.remaps == (('/smarticles/start', '/other/start'),)
    assert child.params == (ParamFile(str(tmp_path / 'p.yaml')),)
    assert params_of(b) == {'n': '2'}                 # the group's let did not leak out
    assert b.args == ('--flag', '/dev/ttyX', 'fallback')
    assert names(resolve(path, {'flag': 'true', 'n': '1'}))[-1] == '/c'


def test_eval_handles_arithmetic_and_refuses_code() -> None:
    assert evaluate('2 + 1 < 4') == 'True' and evaluate('7 // 2') == '3' and evaluate("'a' != ''") == 'True'
    assert evaluate('max(1, int("3")) if True else 0') == '3'
    assert evaluate("'pkg/exe'.split('/')[0]") == 'pkg'
    assert evaluate("'2' in '0, 2'.replace(' ', '').split(',')") == 'True'
    assert evaluate("str(1 < 2).lower()") == 'true' and evaluate("'1' not in 'all'.split()") == 'True'
    for bad in ('__import__("os")', 'open("x")', '[1, 2]', '1 +', "'a'.split()", "'a'.join('b')", "(1).real",
                "'abc'[9]"):
        with pytest.raises(ValueError):
            evaluate(bad)


# ------------------------------------------------------------------------------------------ bad input
BAD = {
    'malformed XML': ('<launch>\n  <node pkg="smarticle_driver" exec="gait">\n</launch>\n', 3, 'malformed XML'),
    'unknown package': ('<launch>\n<node pkg="smarticle_nope" exec="gait"/>\n</launch>', 2,
                        "unknown package 'smarticle_nope'"),
    'unknown executable': ('<launch>\n\n<node pkg="smarticle_driver" exec="gaiter"/>\n</launch>', 3,
                           "package 'smarticle_driver' has no executable 'gaiter'"),
    'missing parameter file': ('<launch>\n<node pkg="smarticle_driver" exec="gait">\n'
                               '  <param from="nowhere.yaml"/>\n</node>\n</launch>', 3, 'nowhere.yaml does not exist'),
    'required argument': ('<launch>\n<arg name="robot"/>\n</launch>', 2, "argument 'robot' is required"),
    'undefined variable': ('<launch>\n<node pkg="smarticle_driver" exec="gait" name="$(var who)"/>\n</launch>', 2,
                           '$(var who): no argument or let of that name'),
    'bad condition': ('<launch>\n<node pkg="smarticle_driver" exec="gait" if="maybe"/>\n</launch>', 2,
                      "a condition must be 'true', 'false', '1' or '0'"),
    'unsupported element': ('<launch>\n<executable cmd="ls"/>\n</launch>', 2, 'unsupported element <executable>'),
    'unsupported attribute': ('<launch>\n<node pkg="smarticle_driver" exec="gait" respawn="true"/>\n</launch>', 2,
                              'unsupported attribute(s) respawn'),
    'not a launch file': ('<robot>\n</robot>', 1, 'the root element is <robot>, not <launch>'),
    'missing include': ('<launch>\n<include file="other.launch.xml"/>\n</launch>', 2, 'does not exist'),
    'bad eval': ("<launch>\n<let name='x' value=\"$(eval 'open(1)')\"/>\n</launch>", 2, 'is not supported'),
    'runaway include': ('<launch>\n<include file="$(dirname)/bad.launch.xml"/>\n</launch>', 2,
                        'includes nest deeper than'),
    'malformed parameter file': ('<launch>\n<node pkg="smarticle_driver" exec="gait">\n'
                                 '  <param from="$(dirname)/malformed.yaml"/>\n</node>\n</launch>', 3,
                                 'malformed.yaml:4: malformed YAML in the parameter file'),
    'bad argument value': ('<launch>\n<arg name="robots" default="two"/>\n<arg name="robot" default="0"/>\n'
                           "<let name='more' value=\"$(eval '$(var robot) + 1 &lt; $(var robots)')\"/>\n</launch>",
                           4, "argument robots has a value this file cannot use, 'two'"),
    'unmatched quote in args': ('<launch>\n<arg name="who" default="a\'b"/>\n'
                                '<node pkg="smarticle_driver" exec="gait" args="$(var who)"/>\n</launch>', 3,
                                'No closing quotation'),
}


@pytest.mark.parametrize('case', sorted(BAD))
def test_bad_input_is_one_line_naming_file_and_line(case: str, tmp_path: Path) -> None:
    text, line, message = BAD[case]
    write(tmp_path, 'malformed.yaml', '/**:\n  ros__parameters:\n    period: [1.6\n    alpha_max_deg: 3\n')
    path = write(tmp_path, 'bad.launch.xml', text)
    with pytest.raises(LaunchFileError) as err:
        resolve(path)
    text = str(err.value)
    assert '\n' not in text and message in text, text
    assert text.startswith(f'{path}:{line}:'), text


def test_a_relative_parameter_file_is_the_callers_from_the_working_folder(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """As ``ros2 launch``: ``params_file:=mine.yaml`` names a file in the folder the launch was started from."""
    (tmp_path / 'launch').mkdir()
    (tmp_path / 'work').mkdir()
    launch = tmp_path / 'launch' / 'one.launch.xml'
    launch.write_text('<launch>\n<arg name="params_file"/>\n<node pkg="smarticle_driver" exec="gait">\n'
                      '  <param from="$(var params_file)"/>\n</node>\n</launch>\n')
    (tmp_path / 'work' / 'mine.yaml').write_text('/**:\n  ros__parameters:\n    period: 1.6\n')
    monkeypatch.chdir(tmp_path / 'work')
    plan = resolve(launch, {'params_file': 'mine.yaml'})
    files = [p for p in plan.nodes[0].params if isinstance(p, ParamFile)]
    assert files == [ParamFile(str(tmp_path / 'work' / 'mine.yaml'))]
    monkeypatch.chdir(tmp_path / 'launch')
    with pytest.raises(LaunchFileError, match=f'parameter file {tmp_path}/launch/mine.yaml does not exist'):
        resolve(launch, {'params_file': 'mine.yaml'})


def test_an_unknown_argument_is_refused_naming_the_declared_ones() -> None:
    with pytest.raises(LaunchFileError, match=r'unknown argument\(s\) robot for sim.launch.xml; it declares: bag'):
        resolve(LAUNCH / 'sim.launch.xml', {'robot': '3'})
    with pytest.raises(LaunchFileError, match='not of the form name:=value'):
        launcher.plan_from_command_line([str(LAUNCH / 'sim.launch.xml'), 'robots=3:'])


@pytest.mark.parametrize('words', [
    ['smarticle_bringup', 'sim.launch.xml', 'robot:=1'],
    ['smarticle_bringup', 'nope.launch.xml'],
    ['smarticle_nope', 'sim.launch.xml'],
    [],
])
def test_the_launcher_exits_2_with_one_line_and_starts_nothing(words: list[str], tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    logs = tmp_path / 'logs'
    code = launcher.main([*words, '--log-dir', str(logs)]) if words else launcher.main(['x.launch.xml'])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith('smarticle-launch: ') and '\n' not in err, err
    assert not logs.exists()                        # no process was started (none has a log)


@pytest.mark.parametrize('words, says', [
    (['robots:=two'], "sim_robots.launch.xml:60: argument robots has a value this file cannot use, 'two'"),
    (['robots:=two', 'composed:=false'], "argument robots has a value this file cannot use, 'two'"),
    (['params_file:={bad}'], 'bad.yaml:4: malformed YAML in the parameter file'),
    (['params_file:={bad}', 'composed:=false'], 'bad.yaml:4: malformed YAML in the parameter file'),
])
def test_a_bad_argument_value_or_parameter_file_is_one_line_and_starts_nothing(
        words: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Composed too: the launcher reads the host's own launch file and its parameter files before it starts."""
    bad = write(tmp_path, 'bad.yaml', '/**:\n  ros__parameters:\n    period: [1.6\n    alpha_max_deg: 3\n')
    logs = tmp_path / 'logs'
    code = launcher.main(['smarticle_bringup', 'sim.launch.xml', *(w.format(bad=bad) for w in words),
                          '--log-dir', str(logs)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith('smarticle-launch: ') and '\n' not in err and says in err, err
    assert not logs.exists()


def test_a_controller_is_looked_up_in_its_own_package_only(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A program of the executable's name elsewhere on PATH is never taken for it."""
    fake_bin = tmp_path / 'bin'
    fake_bin.mkdir()
    impostor = fake_bin / 'fold'
    impostor.write_text('#!/bin/sh\nexit 0\n')
    impostor.chmod(0o755)
    monkeypatch.setenv('PATH', f'{fake_bin}:{os.environ["PATH"]}')
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(tmp_path / 'ros'))
    node = resolve(LAUNCH / 'board.launch.xml', {'controller': 'smarticle_example_controller/square_stop'},
                   check_executables=False).nodes[1]
    assert launcher.executable_path(node).endswith('/square_stop')
    with pytest.raises(LaunchFileError) as err:
        launcher.executable_path(dataclasses.replace(node, executable='fold'))
    text = str(err.value)
    assert "executable 'fold' of package 'smarticle_example_controller' not found" in text and '\n' not in text
    assert f'looked in {tmp_path}/ros/lib/smarticle_example_controller' in text and str(impostor) not in text


def test_the_composer_refuses_a_node_it_cannot_host(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from smarticle_bringup import compose

    path = write(tmp_path, 'x.launch.xml', '<launch>\n<node pkg="smarticle_bags" exec="recorder"/>\n</launch>')
    assert compose.main([str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f'smarticle-compose: {path}:2: smarticle_bags/recorder cannot be composed'), err


def test_show_prints_the_command_lines(capsys: pytest.CaptureFixture[str]) -> None:
    assert launcher.main(['smarticle_bringup', 'board.launch.xml', 'robot:=2', '--show']) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 3 and lines[0].split()[0].endswith('servo_bridge')
    assert '__ns:=/smarticle_2' in lines[1] and f'--params-file {STACK}' in lines[1]
