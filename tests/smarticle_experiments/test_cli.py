"""The command line: bad input is one line, exit code 2, nothing written."""

from __future__ import annotations

import re
import socket
import warnings
from pathlib import Path

import pytest
import yaml

from smarticle_experiments.cli import main


def spec_file(tmp_path: Path, **data: object) -> str:
    """Write a spec YAML (a new file each call) and return its path."""
    base = {'name': 'tiny', 'kind': 'dense', 'periods': 2, 'params': {'robots': 3}, 'seeds': 2}
    path = tmp_path / f'tiny{len(list(tmp_path.glob("*.yaml")))}.yaml'
    path.write_text(yaml.safe_dump({**base, **data}))
    return str(path)


def free_port() -> int:
    """A local TCP port nobody listens on."""
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


@pytest.mark.parametrize('case', ['unknown key', 'zero trials', 'negative periods', 'empty grid', 'zero seeds',
                                  'no such spec', 'dead scheduler', 'bad seeds', 'seeds and trials',
                                  'a spec one off a shipped name', 'an archived spec', 'trials per grid point'])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(case: str, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / 'out'
    argv = {
        'unknown key': ['run', spec_file(tmp_path, colour='red')],
        'zero trials': ['run', spec_file(tmp_path), '--trials', '0'],
        'negative periods': ['run', spec_file(tmp_path), '--periods', '-3'],
        'empty grid': ['run', spec_file(tmp_path, grid={'alpha_max_deg': []})],
        'zero seeds': ['run', spec_file(tmp_path, seeds=0)],
        'no such spec': ['run', 'p99'],
        'dead scheduler': ['run', spec_file(tmp_path), '--scheduler', f'tcp://127.0.0.1:{free_port()}'],
        'bad seeds': ['run', spec_file(tmp_path), '--seeds', '5..2'],
        'seeds and trials': ['run', spec_file(tmp_path), '--seeds', '0..1', '--trials', '2'],
        'a spec one off a shipped name': ['run', 'p8'],
        'an archived spec': ['run', 'p1_fine'],
        'trials per grid point': ['run', 'p4', '--trials', '24'],   # p4 has 1152 grid points: not 24 seeds of each
    }[case]
    try:
        code = main([*argv, '--out', str(out), '--no-progress'])
    except SystemExit as exc:   # argparse's own refusals
        code = int(exc.code or 0)
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and err.startswith('smarticle-experiments: error:')
    cause = {'unknown key': 'colour', 'zero trials': '--trials', 'negative periods': '--periods',
             'empty grid': 'grid.alpha_max_deg', 'zero seeds': 'seeds', 'no such spec': 'p99',
             'dead scheduler': 'does not answer', 'bad seeds': '--seeds',
             'seeds and trials': '--trials and --seeds', 'a spec one off a shipped name': 'did you mean p7',
             'an archived spec': 'archive/README.md', 'trials per grid point': 'multiple of 1152'}[case]
    assert cause in err
    assert not out.exists()


def test_list_names_the_shipped_experiments(capsys: pytest.CaptureFixture[str]) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter('error')   # a spec's unconverged grid point is noted on its line, not warned about
        assert main(['list']) == 0
    listed = capsys.readouterr().out
    for name in ('p1', 'p4', 'p5', 'p6', 'p7', 'accuracy'):
        assert f'\n{name} ' in '\n' + listed
    # each spec's trials and its run time on 2 cores: P1's 151 dense trials take hours, P7's seconds
    p1, p4, p7 = (next(line for line in listed.splitlines() if line.startswith(f'{n} ')) for n in ('p1', 'p4', 'p7'))
    assert re.search(r' 151 trials +1\.\d h ', p1) and re.search(r' 1152 trials +\d+ min ', p4), (p1, p4)
    assert re.search(r' 24 trials +\d+ s ', p7), p7
    assert 'run time on 2 idle cores' in listed.splitlines()[0]
    assert 'NotConvergedWarning' in next(line for line in listed.splitlines() if line.startswith('accuracy '))


def test_list_groups_the_current_specs_by_tag_and_all_adds_the_rest(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['list']) == 0
    listed = capsys.readouterr().out
    paper = listed.split('# paper\n')[1].split('\n# ')[0]
    assert [line.split()[0] for line in paper.splitlines()] == ['p1', 'p2', 'p3', 'p4', 'p5', 'p6', 'p7']
    assert '# benchmark' in listed and '# diagnostic' in listed and 'p1_fine ' not in listed
    assert main(['list', '--all']) == 0
    everything = capsys.readouterr().out
    assert '# archived' in everything and '\np1_fine' in everything   # the archive of a source tree


def test_list_into_a_closed_pipe_ends_quietly_and_version_prints() -> None:
    """``smarticle-experiments list | head -1``: no BrokenPipeError traceback; ``--version`` names the package."""
    import subprocess
    import sys

    command = f'{sys.executable} -m smarticle_experiments.cli list | head -1'
    done = subprocess.run(['bash', '-c', command], capture_output=True, text=True, timeout=120, check=False)
    assert done.stdout.startswith('# ') and 'Traceback' not in done.stderr and 'BrokenPipe' not in done.stderr
    version = subprocess.run([sys.executable, '-m', 'smarticle_experiments.cli', '--version'], capture_output=True,
                             text=True, timeout=60, check=False)
    assert version.returncode == 0 and version.stdout.startswith('smarticle-experiments ')


def test_a_shipped_spec_is_found_whatever_its_case(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['status', 'P7', '--out', str(tmp_path / 'out')]) == 0
    assert capsys.readouterr().out.startswith('p7: 24 trials: 0 done')


def test_trials_counts_trials_in_all(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--trials 4`` of a spec of 2 grid points is 4 trials (seeds 0 and 1 at each), not 4 seeds of each."""
    path = spec_file(tmp_path, grid={'alpha_max_deg': [80, 90]})
    assert main(['status', path, '--trials', '4', '--out', str(tmp_path / 'out')]) == 0
    assert capsys.readouterr().out.startswith('tiny: 4 trials: 0 done')
    assert main(['status', path, '--seeds', '0..3', '--out', str(tmp_path / 'out')]) == 0
    assert capsys.readouterr().out.startswith('tiny-seeds-0-3: 8 trials: 0 done')


def test_run_says_the_trials_and_their_run_time_before_it_starts(tmp_path: Path) -> None:
    from smarticle_experiments.cli import build_parser, resolve, run_plan

    args = build_parser().parse_args(['run', 'p4', '--workers', '2', '--out', str(tmp_path / 'out')])
    line = run_plan(resolve(args), args)
    assert line.startswith('p4: 1152 trials (1152 grid points x 1 seeds) in bullet, 1152 to run: about '), line
    assert re.search(r'about \d+ min on 2 cores', line), line
    args = build_parser().parse_args(['run', 'p1', '--trials', '10', '--workers', '1', '--out', str(tmp_path)])
    assert re.search(r'p1: 10 trials .* 10 to run: about \d+ min on 1 core ', run_plan(resolve(args), args))


def test_report_of_a_spec_never_run_says_so(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['report', spec_file(tmp_path), '--out', str(tmp_path / 'out')]) == 2
    assert 'run it first' in capsys.readouterr().err


def test_a_report_over_some_of_the_seeds_sits_beside_the_whole_ones(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    from smarticle_experiments.spec import load_spec
    from smarticle_experiments.store import ResultStore

    path = spec_file(tmp_path, name='lone', kind='single', params={}, seeds={'start': 10, 'count': 4},
                     report=['drift'])
    spec = load_spec(path)
    store = ResultStore(tmp_path / 'out' / spec.store)
    for t in spec.trials(spec.code()):
        store.write({'key': t.key, 'kind': t.kind, 'seed': t.seed, 'point': {}, 'status': 'ok',
                     'result': {'drift_um_per_cycle': float(t.seed), 'trouble': '', 'heading_deg': 0.0, 'cycles': 20,
                                'step_um_per_cycle': float(t.seed)}})
    assert main(['report', path, '--seeds', '11..12', '--out', str(tmp_path / 'out')]) == 0
    part = (store.folder / 'report-lone-seeds-11-12' / 'report.md').read_text()
    assert '| 90 | 2 | 11.5 [' in part and '11, 12' in part
    assert main(['report', path, '--out', str(tmp_path / 'out')]) == 0
    assert '| 90 | 4 | 11.5 [' in (store.folder / 'report-lone' / 'report.md').read_text()


def test_a_report_names_head_and_the_trials_code_version_apart() -> None:
    """HEAD is the source tree's commit now; the trials' code version is the trial code's source hash (their key)."""
    import subprocess

    from smarticle_experiments.report import code_line

    root = Path(__file__).resolve().parents[2]
    head = subprocess.run(['git', '-C', str(root), 'rev-parse', 'HEAD'], capture_output=True, text=True,
                          check=True).stdout.strip()
    line = code_line({'smarticle_experiments': '0.1', 'source': 'abc', 'numpy': '1', 'pybullet': '2'})
    assert f'HEAD {head}' in line, line
    assert "the trial code's source hash abc, smarticle_experiments 0.1, numpy 1, pybullet 2." in line, line


def test_report_summary_prints_one_line_per_claim_from_the_store(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """``report --summary``: the paper specs' claims from the newest stored trials, whatever code version ran
    them; a paper spec without stored trials is one 'not run' line."""
    from smarticle_experiments.spec import load_spec
    from smarticle_experiments.store import ResultStore

    spec = load_spec('p7')
    store = ResultStore(tmp_path / 'out' / spec.store)
    for t in spec.trials({'commit': 'an older one'}):   # stored by another code version: still found
        store.write({'key': t.key, 'kind': t.kind, 'params': dict(t.params), 'seed': t.seed, 'point': dict(t.point),
                     'status': 'ok', 'end_unix': 1.0,
                     'result': {'drift_um_per_cycle': 70.0 + t.seed, 'trouble': '', 'heading_deg': 0.0, 'cycles': 20,
                                'step_um_per_cycle': 70.0}})
    assert main(['report', '--summary', '--out', str(tmp_path / 'out')]) == 0
    table = capsys.readouterr().out
    p7 = [line for line in table.splitlines() if line.startswith('| p7 |')]
    assert len(p7) == 1 and 'P7 drift per cycle at 90 deg' in p7[0] and '| 73.5 [' in p7[0]
    assert '| 24 of 24 |' in p7[0] and 'report-p7' in p7[0]
    assert '| p1 | ' in table and 'not run' in next(line for line in table.splitlines() if line.startswith('| p1 |'))
    assert main(['report', 'p7', '--summary', '--out', str(tmp_path / 'out')]) == 2
