"""A ROS parameters file read as rcl reads it: a malformed one is one line naming the file and line, before
rcl's traceback, for a node and for a launch alike."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from smarticle_common.launching import executable
from smarticle_common.params import ParameterError, check_params_file, params_files

ROOT = Path(__file__).resolve().parents[2]

#: name -> (file text, line the message names, what it says). rcl refuses every one of them too.
BAD = {
    'unclosed list': ('/**:\n  ros__parameters:\n    period: [1.6\n    alpha_max_deg: 3\n', 4,
                      'malformed YAML in the parameter file'),
    'bad indentation': ('/**:\n  ros__parameters:\n    period: 1.6\n   alpha_max_deg: 3\n', 4,
                        'malformed YAML in the parameter file'),
    'tab': ('/**:\n  ros__parameters:\n\tperiod: 1.6\n', 3, 'malformed YAML in the parameter file'),
    'value outside ros__parameters': ('/**:\n  period: 1.6\n', 2, "'period' has a value outside ros__parameters"),
    'list of mixed types': ('/**:\n  ros__parameters:\n    ids: [1, "two"]\n', 3,
                            "parameter 'ids': every value of a list must have one type"),
}


@pytest.mark.parametrize('case', sorted(BAD))
def test_a_malformed_parameter_file_is_one_line_naming_file_and_line(case: str, tmp_path: Path) -> None:
    text, line, says = BAD[case]
    path = tmp_path / 'bad.yaml'
    path.write_text(text, encoding='utf-8')
    with pytest.raises(ParameterError) as err:
        check_params_file(str(path))
    message = str(err.value)
    assert message.startswith(f'{path}:{line}: ') and says in message and '\n' not in message, message


def test_rcl_refuses_what_the_check_refuses_and_takes_the_shipped_files(tmp_path: Path) -> None:
    """The check is no stricter than rcl: every BAD file fails rcl's own parser, every shipped file passes both."""
    shipped = [p for p in [*ROOT.glob('*/config/*.yaml'), *ROOT.glob('*/*/config/*.yaml')]
               if 'ros__parameters' in p.read_text(encoding='utf-8')]
    assert len(shipped) >= 10
    for path in shipped:
        check_params_file(str(path))
    files = []
    for case, (text, _, _) in BAD.items():
        path = tmp_path / f'{case.replace(" ", "_")}.yaml'
        path.write_text(text, encoding='utf-8')
        files.append(str(path))
    code = ('import sys, rclpy\n'
            'for f in sys.argv[1:]:\n'
            '    try:\n'
            "        rclpy.init(args=['x', '--ros-args', '--params-file', f])\n"
            "        print('accepted', f); rclpy.shutdown()\n"
            '    except Exception:\n'
            "        print('refused', f)\n")
    out = subprocess.run([sys.executable, '-c', code, *files, str(shipped[0])], capture_output=True, text=True,
                         timeout=60).stdout.split('\n')
    assert [line.split()[0] for line in out if line] == ['refused'] * len(BAD) + ['accepted'], out


def test_params_files_are_read_from_the_command_line() -> None:
    assert params_files(['gait', '--ros-args', '--params-file', 'a.yaml', '-p', 'x:=1', '--params-file',
                         'b.yaml']) == ['a.yaml', 'b.yaml']
    assert params_files(['gait', '--params-file']) == []


def test_a_node_given_a_malformed_file_exits_2_with_one_line(tmp_path: Path) -> None:
    path = tmp_path / 'bad.yaml'
    path.write_text(BAD['unclosed list'][0], encoding='utf-8')
    result = subprocess.run([executable('gait'), '--ros-args', '--params-file', str(path)], capture_output=True,
                            text=True, timeout=60)
    out = (result.stdout + result.stderr).strip()
    assert result.returncode == 2 and len(out.splitlines()) == 1, out
    assert f'cannot start: {path}:4: malformed YAML' in out and 'Traceback' not in out, out
