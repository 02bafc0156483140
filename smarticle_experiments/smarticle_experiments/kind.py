"""What a trial kind is, and the registry the kinds add themselves to (dm_control's ``SUITE.add`` pattern).

A trial kind is one module (``smarticle_experiments.kinds.<name>``, or a user's module) that holds its typed
parameters (a frozen ``KindParams`` dataclass that validates itself on construction and is what travels to the
Dask workers), its run function (typed parameters, seed -> typed result), its result type, the engines it runs
on and the report sections its results feed, and that registers a ``TrialKind`` in ``KINDS`` when it is
imported. This module imports no kind: ``smarticle_experiments.kinds`` imports the built-in ones, and
everything that needs the whole registry reads it from there.

The stored (and hashed) form of a trial's parameters is the mapping ``KindParams.as_dict()``: a spec merges its
values into the kind's defaults (``KindParams.defaults()``) and ``KindParams.from_mapping`` reads them back.
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterator, Mapping
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, ClassVar, Generic, TypeVar

from .errors import ResultError, SpecError

#: The engines a kind may run on: PyBullet (the project's), MuJoCo (cross-engine check), Chrono (the authors').
ENGINES: tuple[str, ...] = ('bullet', 'mujoco', 'chrono')

P = TypeVar('P', bound='KindParams')

#: ``field`` metadata of a parameter left out of the stored mapping while None (added after stored trials
#: existed, so their keys stay the same).
OMIT_NONE: dict[str, bool] = {'omit_none': True}
#: ``field`` metadata of a parameter left out of the stored mapping while it holds its default (added after
#: stored trials existed, e.g. the engine: a Bullet trial's key stays the same).
OMIT_DEFAULT: dict[str, bool] = {'omit_default': True}


def optional(default: Any = None) -> Any:
    """A parameter that is left out of the stored mapping while it is None."""
    return field(default=default, metadata=OMIT_NONE)


def omitted(f: Any) -> bool:
    """Whether the dataclass field ``f`` is left out of the stored mapping when unset (``optional``,
    ``OMIT_DEFAULT``)."""
    return bool(f.metadata.get('omit_none') or f.metadata.get('omit_default'))


def field_default(f: Any) -> Any:
    """The default value of the dataclass field ``f`` (a fresh copy)."""
    factory: Any = f.default_factory
    return factory() if f.default is MISSING else copy.deepcopy(f.default)


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message."""
    return (str(exc) or type(exc).__name__).split('\n')[0]


@dataclass(frozen=True)
class KindParams:
    """Base of a kind's typed parameters: every field has a default; construction validates (``check``).

    ``GROUPS`` names the mapping parameters whose entries a spec may set one by one (grid keys ``group.name``)
    and the names each accepts (``physics``: PhysicsConfig fields, ...).
    """

    GROUPS: ClassVar[Mapping[str, frozenset[str]]] = {}

    def __post_init__(self) -> None:
        try:
            self.check()
        except SpecError:
            raise
        except (ValueError, TypeError, KeyError) as exc:
            raise SpecError(first_line(exc)) from None

    def check(self) -> None:
        """Raise ValueError (SpecError) if the parameters make no valid trial; the base accepts any."""

    def as_dict(self) -> dict[str, Any]:
        """The stored mapping: every field in order (containers copied), optional ones only when set."""
        return {f.name: copy.deepcopy(getattr(self, f.name)) for f in fields(self)
                if not (f.metadata.get('omit_none') and getattr(self, f.name) is None)
                and not (f.metadata.get('omit_default') and getattr(self, f.name) == field_default(f))}

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The parameter names, in order."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def defaults(cls) -> dict[str, Any]:
        """The stored mapping of the default parameters (without those left out while unset)."""
        return {f.name: field_default(f) for f in fields(cls) if not omitted(f)}

    @classmethod
    def checked_before(cls: type[P], data: Mapping[str, Any]) -> P:
        """The typed parameters of a stored mapping checked before (a spec's trial), without checking them again
        (no config is built, no warning repeated)."""
        out = object.__new__(cls)
        for f in fields(cls):
            object.__setattr__(out, f.name, data[f.name] if f.name in data else field_default(f))
        return out

    @classmethod
    def from_mapping(cls: type[P], data: Mapping[str, Any]) -> P:
        """The typed parameters of a stored mapping; SpecError names an unknown parameter or a bad value."""
        unknown = [k for k in data if k not in cls.names()]
        if unknown:
            raise SpecError(f'unknown parameter {unknown[0]!r} (known: {", ".join(cls.names())})')
        try:
            return cls(**dict(data))
        except TypeError as exc:
            raise SpecError(first_line(exc)) from None


#: A kind's run: (typed parameters, seed) -> a typed result (``results.TrialResult``) or a JSON-ready dict.
RunFunction = Callable[[Any, int], Any]
#: A report section a kind draws itself: the report's context -> markdown lines.
SectionWriter = Callable[[Any], list[str]]


@dataclass(frozen=True)
class TrialKind(Generic[P]):
    """A trial kind: its name, typed parameters, run, result type, engines, report sections and code."""

    name: str
    params: type[P]
    run: RunFunction
    description: str
    #: The typed result (``results.TrialResult``) the stored dict reads back as; None: a plain dict.
    result: type | None = None
    #: The result of a start that did not run (robots overlapping), told by ``admissible: false``.
    inadmissible: type | None = None
    #: The engines it runs on (of ``ENGINES``), its default first; a kind of several takes the engine as its
    #: parameter ``engine`` (``params.EngineParams``), which a spec's ``engine`` sets.
    engines: tuple[str, ...] = ('bullet',)
    #: The report sections (``report.SECTIONS``) its results feed.
    sections: tuple[str, ...] = ()
    #: Report sections it draws itself (name -> writer of the report's context), for kinds outside the package.
    writers: Mapping[str, SectionWriter] = field(default_factory=dict)
    #: Why it cannot run on this machine (one line), or None if it can: e.g. the engine is not built.
    unavailable: Callable[[], str | None] | None = None
    #: CPU seconds of one trial of these typed parameters by the cost model (``cost_model``); None: no estimate.
    cost: Callable[[Any], float | None] | None = None
    #: The project modules whose code its run runs (its own module by default; ``trial_code`` follows their
    #: imports).
    modules: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        bad = [e for e in self.engines if e not in ENGINES]
        if not self.engines or bad:
            raise ValueError(f'kind {self.name}: engines must be some of {", ".join(ENGINES)}, got {self.engines}')
        if len(self.engines) > 1 and 'engine' not in self.params.names():
            raise ValueError(f'kind {self.name}: runs on {", ".join(self.engines)}, so its parameters need an '
                             f'engine field')
        if not self.modules:
            object.__setattr__(self, 'modules', (getattr(self.run, '__module__', ''),))

    @property
    def engine(self) -> str:
        """The engine its trials run on unless a spec names another of ``engines``."""
        return self.engines[0]

    def engine_of(self, data: Mapping[str, Any]) -> str:
        """The engine a trial of the stored parameters ``data`` runs on."""
        return str(data.get('engine') or self.engine)

    @property
    def defaults(self) -> dict[str, Any]:
        """Its parameters' stored mapping with their defaults."""
        return self.params.defaults()

    def all_sections(self) -> tuple[str, ...]:
        """The report sections a spec of this kind may name: the report's and its own."""
        return (*self.sections, *(s for s in self.writers if s not in self.sections))

    def cpu_seconds(self, data: Mapping[str, Any]) -> float | None:
        """CPU seconds of one trial of the stored parameters ``data`` by the cost model (None: no estimate)."""
        return None if self.cost is None else self.cost(self.params.checked_before(data))

    def read(self, data: Mapping[str, Any]) -> Any:
        """A stored result as its typed record (a start that did not run: ``inadmissible``), or the dict for a
        kind without a result type; ResultError if the stored dict does not fit."""
        cls: Any = self.inadmissible if self.inadmissible is not None and data.get('admissible') is False \
            else self.result
        if cls is None:
            return dict(data)
        try:
            return cls.from_dict(data)
        except TypeError as exc:
            raise ResultError(f'a stored {self.name} result does not fit {cls.__name__}: {exc}') from None

    def parse(self, data: Mapping[str, Any]) -> P:
        """Typed parameters of a stored mapping (SpecError naming the kind and the fault)."""
        try:
            return self.params.from_mapping(data)
        except SpecError as exc:
            raise SpecError(f'kind {self.name}: {exc}') from None


class Kinds(Mapping[str, TrialKind[Any]]):
    """The registry of trial kinds, filled by the kinds' modules as they are imported."""

    def __init__(self) -> None:
        self._kinds: dict[str, TrialKind[Any]] = {}

    def add(self, kind: TrialKind[Any]) -> TrialKind[Any]:
        """Register ``kind`` (again from the same module: replaced); ValueError if another module took its name."""
        old = self._kinds.get(kind.name)
        if old is not None and old.modules[:1] != kind.modules[:1]:
            raise ValueError(f'trial kind {kind.name!r} is registered by {old.modules[0]} already')
        self._kinds[kind.name] = kind
        return kind

    def register(self, name: str, params: type[KindParams], description: str, **options: Any
                 ) -> Callable[[RunFunction], RunFunction]:
        """Decorator: register the decorated run function as the kind ``name`` (options: ``TrialKind``'s)."""
        def add(run: RunFunction) -> RunFunction:
            self.add(TrialKind(name, params, run, description, **options))
            return run
        return add

    def remove(self, name: str) -> None:
        """Forget the kind ``name`` (a kind registered for a test)."""
        self._kinds.pop(name, None)

    def __getitem__(self, name: str) -> TrialKind[Any]:
        return self._kinds[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._kinds)

    def __len__(self) -> int:
        return len(self._kinds)

    def on(self, engine: str) -> frozenset[str]:
        """The kinds that run on ``engine``."""
        return frozenset(name for name, kind in self._kinds.items() if kind.engine == engine)

    def sections(self) -> tuple[str, ...]:
        """Every report section some kind feeds, in the kinds' order."""
        return tuple(dict.fromkeys(s for kind in self._kinds.values() for s in kind.all_sections()))


#: The registry: each kind's module adds its kind here when imported (``smarticle_experiments.kinds``).
KINDS = Kinds()
