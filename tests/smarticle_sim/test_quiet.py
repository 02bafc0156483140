"""PyBullet's chatter stays off the terminal: the import banner, the client's 'argv[0]=', C-level writes."""

import subprocess
import sys

PROBE = '''
import os, sys
from smarticle_sim.quiet import silenced_output
print('before', flush=True)
with silenced_output():
    print('python out')
    print('python err', file=sys.stderr)
    os.write(1, b'fd one\\n')
    os.write(2, b'fd two\\n')
print('after', flush=True)
print('err after', file=sys.stderr, flush=True)
'''


def run(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, timeout=120, check=True)


def test_block_swallows_python_and_descriptor_writes_and_restores_both_streams():
    done = run(PROBE)
    assert done.stdout.split() == ['before', 'after']
    assert done.stderr.strip() == 'err after'


def test_importing_the_physics_and_connecting_print_nothing():
    done = run('import smarticle_sim.physics as p\np.quiet_client().disconnect()\nprint("ok")')
    assert done.stdout == 'ok\n'
    assert 'pybullet build time' not in done.stderr
    assert done.stderr == ''


def test_an_error_in_the_block_still_surfaces():
    done = subprocess.run([sys.executable, '-c',
                           'from smarticle_sim.quiet import silenced_output\n'
                           'with silenced_output():\n    raise ValueError("seen")'],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode != 0
    assert 'ValueError: seen' in done.stderr
