"""The code a trial runs: the project modules reachable from a kind's modules by their imports, and one hash of
their source, the part of a trial's key that changes when that code changes.

The walk is static (``ast``): every ``import`` and ``from ... import`` statement of a module counts, at its top
or inside a function, so a module a trial imports late (``p6.py`` from ``trials.py``) is found; imports of the
standard library and of third-party packages are not followed (their versions are in the key apart, see
``store.code_version``). A package's ``__init__`` runs when one of its modules is imported, so it counts too,
and a name a package exports lazily (its ``_EXPORTS`` mapping) leads to the module that defines it. The set errs
on the side of re-running: a module imported by a function no trial calls (a table of ``physics_study``
importing ``stats``) counts as well. Code that is only reached by a computed name (``importlib.import_module``
of a variable) is not found: give such modules as entries.

The hash is over module names and source bytes, not paths or commits: a copy of the tree elsewhere, a tree
outside git and an uncommitted edit are keyed by what the files hold.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
from collections.abc import Iterable, Sequence
from functools import lru_cache
from pathlib import Path

from .errors import StoreError

#: Top-level packages whose names start so are the project's (the stack's packages and their examples);
#: the top-level package of each entry module counts too (a kind defined outside the stack).
PROJECT_PREFIX = 'smarticle_'


def _top_dirs(top: str, path: Sequence[Path] | None) -> list[Path]:
    """The folders a top-level name is found in: its package folders, or the folder of a one-file module
    (as ``[file]``); searched in ``path`` if given, else where Python would import it from."""
    if path is not None:
        for folder in path:
            if (folder / top / '__init__.py').is_file():
                return [folder / top]
            if (folder / f'{top}.py').is_file():
                return [folder / f'{top}.py']
        return []
    try:
        spec = importlib.util.find_spec(top)
    except (ImportError, ValueError):
        return []
    if spec is None:
        return []
    if spec.submodule_search_locations:
        return [Path(p) for p in spec.submodule_search_locations]
    return [Path(spec.origin)] if spec.origin and spec.origin.endswith('.py') else []


def locate(name: str, path: Sequence[Path] | None = None) -> Path | None:
    """The source file of module ``name`` (a package's ``__init__.py``), or None if it is not a module."""
    top, *rest = name.split('.')
    for base in _top_dirs(top, path):
        if base.suffix == '.py':
            if not rest:
                return base
            continue
        folder = base.joinpath(*rest)
        if (folder / '__init__.py').is_file():
            return folder / '__init__.py'
        if rest and folder.with_suffix('.py').is_file():
            return folder.with_suffix('.py')
    return None


def _lazy_exports(init: Path) -> dict[str, str]:
    """A package's lazily exported names -> their module (its ``_EXPORTS`` literal), or nothing."""
    try:
        tree = ast.parse(init.read_bytes(), filename=str(init))
    except (OSError, SyntaxError, ValueError):
        return {}
    for node in tree.body:
        target: ast.expr
        if isinstance(node, ast.AnnAssign) and node.value is not None:
            target, value = node.target, node.value
        elif isinstance(node, ast.Assign) and len(node.targets) == 1:
            target, value = node.targets[0], node.value
        else:
            continue
        if isinstance(target, ast.Name) and target.id == '_EXPORTS':
            try:
                mapping = ast.literal_eval(value)
            except ValueError:
                return {}
            return {str(k): str(v) for k, v in mapping.items()} if isinstance(mapping, dict) else {}
    return {}


def exported_module(package: str, name: str, path: Sequence[Path] | None = None) -> str:
    """The module ``package`` lazily exports ``name`` from (its ``_EXPORTS``); StoreError if it exports no such
    name."""
    init = locate(package, path)
    module = _lazy_exports(init).get(name) if init is not None and init.name == '__init__.py' else None
    if not module:
        raise StoreError(f'{package} exports no {name!r}, so the trial code cannot be found')
    return f'{package}.{module}'


def imported_names(source: bytes, module: str, is_package: bool) -> set[str]:
    """Absolute names every import statement of a module's ``source`` names: modules, and ``module.name`` for
    each name of a ``from module import name`` (which may be a module or not)."""
    tree = ast.parse(source, filename=module)
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
            found.update(f'{target}.{alias.name}' for alias in node.names if alias.name != '*')
    return found


def module_files(entries: Iterable[str], path: Sequence[Path] | None = None) -> dict[str, Path]:
    """Every project module the modules ``entries`` run (themselves, their packages' ``__init__`` and what they
    import, transitively) -> its source file; ``path``: the folders to find top-level packages in (default:
    where Python imports them from). StoreError if an entry has no source file."""
    entries = list(entries)
    tops = {e.split('.')[0] for e in entries}
    found: dict[str, Path] = {}
    todo: list[str] = []
    for entry in entries:
        if locate(entry, path) is None:
            raise StoreError(f'cannot find the source of module {entry!r}, whose code a trial runs')
        todo.append(entry)
    while todo:
        name = todo.pop()
        if name in found or not (name.startswith(PROJECT_PREFIX) or name.split('.')[0] in tops):
            continue
        file = locate(name, path)
        if file is None:
            parent, _, attr = name.rpartition('.')
            init = locate(parent, path) if parent else None
            if init is not None and init.name == '__init__.py':
                lazy = _lazy_exports(init).get(attr)
                if lazy:
                    todo.append(f'{parent}.{lazy}')
            continue
        found[name] = file
        parts = name.split('.')
        todo.extend('.'.join(parts[:k]) for k in range(1, len(parts)))
        try:
            source = file.read_bytes()
            todo.extend(imported_names(source, name, file.name == '__init__.py'))
        except (OSError, SyntaxError, ValueError) as exc:
            raise StoreError(f'cannot read the trial code {file}: {exc}') from None
    return found


def source_hash(entries: Iterable[str], path: Sequence[Path] | None = None) -> str:
    """A hash (16 hex digits of a SHA-256) of the names and source bytes of every project module the modules
    ``entries`` run (``module_files``). Cached per process (the default ``path``)."""
    entries = tuple(sorted(set(entries)))
    if path is None:
        return _cached_hash(entries)
    return _hash(module_files(entries, path))


@lru_cache(maxsize=32)
def _cached_hash(entries: tuple[str, ...]) -> str:
    """``source_hash`` of the modules where Python imports them from, once per process."""
    return _hash(module_files(entries))


def _hash(files: dict[str, Path]) -> str:
    """The hash of some modules' names and source bytes, in name order."""
    digest = hashlib.sha256()
    for name in sorted(files):
        data = files[name].read_bytes()
        digest.update(f'{name}\0{len(data)}\0'.encode())
        digest.update(data)
    return digest.hexdigest()[:16]
