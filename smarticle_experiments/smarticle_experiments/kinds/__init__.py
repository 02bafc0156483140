"""The built-in trial kinds, one module each, and what the specs, the engine and the report ask of them.

Importing this package imports every built-in kind's module, which registers its kind in ``kind.KINDS``
(``dense``, ``pair``, ``single``, ``accuracy``, ``p6``, ``c2_harvest``, the Chrono kinds, the physics study's).
It imports them by name (``BUILT_IN_NAMES``), not by import statements, so that the trial code of one kind
(``trial_code``, which follows import statements, and this package's ``__init__`` runs before any kind's module)
is its own module and what that imports, not every other kind's: an edit of one kind re-keys that kind only.
A kind outside the package (a user's, a test's) registers itself the same way when its module is imported;
a spec may also name a plain function as ``module:function`` (untyped parameters, a dict result).

The other smarticle packages (sim, tracking, feedback) are imported by the kinds and the modules they call
(``trials``, ``params``, ``configs``, ``p6``, ``c2_harvest``, ``physics_study``), never by the engine, store,
statistics or report.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any

from ..errors import SpecError
from ..kind import KINDS, KindParams, TrialKind
from ..results import TrialResult

__all__ = ['KINDS', 'CHRONO_KINDS', 'MUJOCO_KINDS', 'BUILT_IN', 'BUILT_IN_NAMES', 'engine_missing', 'kind_modules',
           'read_result', 'report_sections', 'resolve_kind', 'run_kind', 'trial_engine', 'trial_function',
           'trial_params', 'validate_params']

#: The modules of the built-in kinds, in this package (``store.trial_modules`` lists this folder alike).
BUILT_IN_NAMES: tuple[str, ...] = ('dense', 'pair', 'single', 'accuracy', 'p6', 'c2_harvest', 'chrono', 'study')
#: The modules of the built-in kinds, imported.
BUILT_IN: tuple[Any, ...] = tuple(importlib.import_module(f'{__name__}.{name}') for name in BUILT_IN_NAMES)
#: The built-in kinds stepped by MuJoCo (``smarticle_sim.mujoco_engine``) instead of Bullet.
MUJOCO_KINDS: frozenset[str] = KINDS.on('mujoco')
#: The built-in kinds run by the Chrono reference driver (``smarticle_sim.chrono_reference``), where it is built.
CHRONO_KINDS: frozenset[str] = KINDS.on('chrono')

#: A user's ``module:function`` kind: (parameter mapping, seed) -> a JSON-ready dict (or a typed result).
TrialFunction = Callable[[Mapping[str, Any], int], Any]


def resolve_kind(kind: str) -> TrialKind[Any] | None:
    """The registered kind named ``kind``, or None for a user's ``module:function`` kind."""
    if kind in KINDS:
        return KINDS[kind]
    if ':' in kind:
        return None
    raise SpecError(f'kind {kind!r} is unknown; choose one of {", ".join(KINDS)} or give module:function')


def engine_missing(kind: str) -> str | None:
    """Why trials of ``kind`` cannot run on this machine (one line), or None if they can (the Chrono kinds need
    the Chrono driver, tools/chrono_reference/build_chrono.sh)."""
    known = KINDS.get(kind)
    return known.unavailable() if known is not None and known.unavailable is not None else None


def kind_modules(kind: str) -> tuple[str, ...]:
    """The modules whose code a trial of ``kind`` runs (``trial_code`` follows their imports): a registered kind's
    ``modules``, a ``module:function`` kind's module."""
    known = resolve_kind(kind)
    return known.modules if known is not None else (kind.partition(':')[0],)


def trial_engine(kind: str, params: Mapping[str, Any]) -> str:
    """The engine a trial of ``kind`` with the stored parameters ``params`` runs on (a ``module:function`` kind:
    its ``engine`` parameter, else Bullet)."""
    known = KINDS.get(kind)
    return known.engine_of(params) if known is not None else str(params.get('engine') or 'bullet')


def trial_function(kind: str) -> Callable[[Any, int], Any]:
    """The function that runs a trial of ``kind`` (a registered name or an importable ``module:function``)."""
    known = resolve_kind(kind)
    if known is not None:
        return known.run
    module, _, name = kind.partition(':')
    try:
        func = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise SpecError(f'kind {kind!r}: cannot import {name} from {module} ({exc})') from None
    if not callable(func):
        raise SpecError(f'kind {kind!r}: {name} is not callable')
    return func


def trial_params(kind: str, params: Mapping[str, Any] | KindParams) -> Mapping[str, Any] | KindParams:
    """What travels to a worker: a registered kind's typed parameters of a stored mapping (a user's
    ``module:function`` kind: the mapping)."""
    known = KINDS.get(kind)
    if known is None or isinstance(params, KindParams):
        return params
    return known.parse(params)


def validate_params(kind: str, params: Mapping[str, Any]) -> None:
    """Raise SpecError (ValueError) if the merged parameters of a registered kind make no valid trial."""
    trial_params(kind, params)


def run_kind(kind: str, params: Mapping[str, Any] | KindParams, seed: int) -> dict[str, Any]:
    """Run one trial of ``kind`` and return its result in the stored form (a typed result's ``as_dict``)."""
    result = trial_function(kind)(trial_params(kind, params), seed)
    return result.as_dict() if isinstance(result, TrialResult) else dict(result)


def stored_params(params: Mapping[str, Any] | KindParams) -> dict[str, Any]:
    """The stored mapping of a trial's parameters, typed or not."""
    return params.as_dict() if isinstance(params, KindParams) else dict(params)


def read_result(kind: str, data: Mapping[str, Any]) -> TrialResult | dict[str, Any]:
    """A stored result (the JSON record's ``result``) as its kind's typed record; a kind without a type
    (a user's ``module:function``, the Chrono kinds) gives the dict back. Raises ResultError if the stored dict
    does not fit."""
    known = KINDS.get(kind)
    result: TrialResult | dict[str, Any] = dict(data) if known is None else known.read(data)
    return result


def report_sections(kind: str | None = None) -> tuple[str, ...]:
    """The report sections a spec of ``kind`` may name (a ``module:function`` kind, or None: every section some
    kind feeds)."""
    known = KINDS.get(kind) if kind is not None else None
    return known.all_sections() if known is not None else KINDS.sections()
