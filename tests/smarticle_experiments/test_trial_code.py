"""A trial's code version: the source of the modules its kind runs, found from their imports, on a copy of the
tree outside git. An edit of code a trial runs re-keys it; an edit of the report does not."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from smarticle_experiments.errors import StoreError
from smarticle_experiments.spec import load_spec
from smarticle_experiments.store import ResultStore, code_version, trial_modules
from smarticle_experiments.trial_code import exported_module, locate, module_files, source_hash


def copy_tree(dest: Path) -> list[Path]:
    """Copy the packages of every module the trials run to ``dest/<package>/<package>`` (sources only); return
    the folders to find them in."""
    tops = sorted({name.split('.')[0] for name in module_files(trial_modules())})
    path = []
    for top in tops:
        init = locate(top)
        assert init is not None
        shutil.copytree(init.parent, dest / top / top, ignore=shutil.ignore_patterns('__pycache__'))
        path.append(dest / top)
    return path


def edit(path: list[Path], module: str, text: str) -> None:
    """Append ``text`` (a comment) to the copy's source of ``module``."""
    file = locate(module, path)
    assert file is not None
    file.write_text(file.read_text() + text)


def test_the_trial_code_is_what_the_trials_import_and_not_the_report() -> None:
    names = set(module_files(trial_modules()))
    # the modules the old hand-written list left out are found from the imports
    assert {'smarticle_experiments.configs', 'smarticle_experiments.physics_study', 'smarticle_experiments.p6',
            'smarticle_experiments.c2_harvest', 'smarticle_experiments.results'} <= names
    assert {'smarticle_sim.physics', 'smarticle_sim.runner', 'smarticle_feedback.controller',
            'smarticle_tracking.gliders', 'smarticle_common.gait', 'smarticle_sim'} <= names   # packages' inits too
    assert not {'smarticle_experiments.report', 'smarticle_experiments.cli', 'smarticle_experiments.engine',
                'smarticle_experiments.store'} & names
    assert not any(n.split('.')[0] in ('numpy', 'pybullet', 'os') for n in names)   # libraries: versions apart
    with pytest.raises(StoreError, match="'smarticle_experiments.no_such_kind'"):
        module_files(['smarticle_experiments.no_such_kind'])


def test_every_registered_kind_runs_code_the_default_version_covers() -> None:
    """The default trial code starts at the module of the worker's entry point (``run_kind``), which imports every
    built-in kind: each kind's run function is defined in a module it reaches."""
    from smarticle_experiments import KINDS

    names = set(module_files(trial_modules()))
    for name, kind in KINDS.items():
        run = getattr(kind, 'run', None) or kind.function
        assert run.__module__ in names, (name, run.__module__)
    with pytest.raises(StoreError, match="exports no 'no_such_name'"):
        exported_module('smarticle_experiments', 'no_such_name')


def test_an_edit_of_trial_code_rekeys_stored_trials_and_an_edit_of_the_report_does_not(tmp_path: Path) -> None:
    path = copy_tree(tmp_path / 'tree')
    assert not (tmp_path / 'tree' / '.git').exists()
    code = code_version(path=path)
    assert code == code_version()      # names and bytes, not where the tree is or which commit it is
    spec = load_spec('p7')
    trial = spec.trials(code)[0]
    store = ResultStore(tmp_path / 'store')
    store.write({'key': trial.key, 'kind': trial.kind, 'params': dict(trial.params), 'seed': trial.seed,
                 'point': dict(trial.point), 'status': 'ok', 'result': {'drift_um_per_cycle': 70.0}})

    def found() -> bool:
        key = spec.trials(code_version(path=path))[0].key
        return store.read(key) is not None and key in store.done()

    assert found()
    edit(path, 'smarticle_experiments.report', '\n# a new figure\n')
    assert found()
    edit(path, 'smarticle_experiments.configs', '\n# a change of how a SimConfig is built\n')
    assert not found()


def test_an_edit_of_one_kind_s_module_rekeys_that_kind_and_not_another(tmp_path: Path) -> None:
    """A spec's trials are keyed by the code of their own kind (``ExperimentSpec.code``): the kinds' package imports
    its kinds by name, so one kind's module is not in another's trial code; what both run re-keys both."""
    from smarticle_experiments.kinds import KINDS

    path = copy_tree(tmp_path / 'tree')
    single, dense = KINDS['single'].modules, KINDS['dense'].modules
    assert 'smarticle_experiments.kinds.dense' not in module_files(single, path)
    assert load_spec('p7').code() == code_version(single)
    before = code_version(single, path), code_version(dense, path)
    edit(path, 'smarticle_experiments.kinds.single', '\n# a change of the lone robot\'s trial\n')
    assert code_version(single, path) != before[0]
    assert code_version(dense, path) == before[1]
    edit(path, 'smarticle_experiments.params', '\n# a change both kinds run\n')
    assert code_version(dense, path) != before[1]


def test_uncommitted_edits_are_keyed_by_their_content(tmp_path: Path) -> None:
    path = copy_tree(tmp_path / 'tree')
    first = source_hash(trial_modules(path), path)
    edit(path, 'smarticle_sim.physics', '\n# edit A\n')
    a = source_hash(trial_modules(path), path)
    file = locate('smarticle_sim.physics', path)
    assert file is not None
    file.write_text(file.read_text().replace('# edit A', '# edit B'))
    b = source_hash(trial_modules(path), path)
    assert len({first, a, b}) == 3      # two different edits, two keys (not one 'dirty' key)
    file.write_text(file.read_text().replace('\n# edit B\n', ''))
    assert source_hash(trial_modules(path), path) == first


def test_a_process_keys_the_code_it_imports_from(tmp_path: Path) -> None:
    """Run from a copy (first on PYTHONPATH), outside git, the default code version hashes the copy."""
    path = copy_tree(tmp_path / 'tree')
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(map(str, path))}
    script = ('import smarticle_experiments.trial_code as c, smarticle_experiments.store as s\n'
              'print(c.__file__, s.trial_modules()[0])\nprint(c.source_hash(s.trial_modules()))')

    def run() -> list[str]:
        done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True, env=env,
                              cwd=tmp_path, check=True, timeout=120)
        return done.stdout.split()

    where, _, before = run()
    assert Path(where).is_relative_to(tmp_path)
    assert before == source_hash(trial_modules(path), path)
    edit(path, 'smarticle_experiments.c2_harvest', '\n# edited\n')
    assert run()[2] not in (before, '')


def test_the_walk_follows_relative_late_and_lazily_exported_imports(tmp_path: Path) -> None:
    """A kind's own module outside the stack (``toy_kind.py``) counts, and so does what it reaches: a module
    imported inside a function, one imported relatively, and one a package exports lazily (``_EXPORTS``)."""
    pkg = tmp_path / 'smarticle_toy'
    pkg.mkdir()
    (pkg / '__init__.py').write_text("_EXPORTS: dict[str, str] = {'Thing': 'thing'}\n")
    (pkg / 'thing.py').write_text('from . import helper\n')
    (pkg / 'helper.py').write_text('import math\n')
    (pkg / 'late.py').write_text('')
    (pkg / 'unused.py').write_text('')
    (tmp_path / 'toy_kind.py').write_text('from smarticle_toy import Thing\n\n\ndef run():\n'
                                          '    from smarticle_toy.late import x\n')
    assert sorted(module_files(['toy_kind'], [tmp_path])) == ['smarticle_toy', 'smarticle_toy.helper',
                                                             'smarticle_toy.late', 'smarticle_toy.thing', 'toy_kind']
    before = source_hash(['toy_kind'], [tmp_path])
    (pkg / 'unused.py').write_text('# not run by the kind\n')
    assert source_hash(['toy_kind'], [tmp_path]) == before
    (pkg / 'helper.py').write_text('import math  # run by the kind\n')
    assert source_hash(['toy_kind'], [tmp_path]) != before
