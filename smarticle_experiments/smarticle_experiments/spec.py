"""Experiments as data: a YAML spec (scene, settings, grid, seeds, periods, analysis, report) and its trials.

A spec file is a mapping with these keys (every other key is refused, naming it)::

    name: p1                      # required; also the default store folder
    description: one line
    tags: [paper]                 # what it is for: paper, benchmark, calibration, diagnostic (``TAGS``)
    status: current               # current or superseded (``list`` shows current specs, ``list --all`` all)
    kind: dense                   # trial kind (kinds.KINDS) or a user's importable module:function
    engine: mujoco                # the engine of its trials, one of the kind's (default: its first, bullet)
    store: p1                     # optional store folder (specs that share trials share a store)
    preset: small                 # robot preset
    periods: 300                  # gait periods per trial (> 0)
    physics: {contact_erp: 0.6}   # PhysicsConfig overrides (default: the project's defaults)
    robot: {}                     # RobotSpec overrides
    noise: paper                  # noise with a cause: 'paper' (the cited figures), 'none' (the default)
                                  # or NoiseConfig fields, e.g. {clock_rate_sd: 0.003} (the others off)
    mujoco: {time_step: 1.0e-4}   # MujocoSettings overrides (engine mujoco only)
    params: {robots: 7}           # the kind's scene / trial parameters (see `smarticle-experiments list -v`)
    analysis: {min_periods: 30}   # the kind's in-trial analysis parameters (same namespace as params)
    grid: {theta_deg: [0, 30]}    # parameter -> list of values; the trials are the product x seeds
                                  # (or a list of such blocks: the union of their products)
    seeds: 151                    # a count (0..n-1), a list, {start: 0, count: 151} or '1000..1150'
    report: [p1, trajectories]    # report sections (the kind's: ``kinds.report_sections``)
    paper: {fraction: 0.64}       # the paper's values the report sections compare with

Grid keys may name an entry of a kind's mapping parameter (its ``GROUPS``: physics, robot, noise, mujoco,
chrono fields) as ``physics.time_step`` / ``robot.arm_mass`` / ``noise.clock_rate_sd``. A spec without noise
leaves ``noise`` out of the trial parameters, so its trial keys are those of a spec written before noise existed;
likewise a trial in its kind's default engine has no ``engine`` parameter (a Bullet trial's key is the one it had
before kinds took an engine) and one in another engine has it (``engine: mujoco``), so the two never share a key.
A kind that cannot run in the spec's engine is refused when the spec loads.
"""

from __future__ import annotations

import difflib
import hashlib
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .configs import noise_mapping
from .errors import SpecError
from .kind import TrialKind
from .kind import ENGINES
from .kinds import KINDS, kind_modules, report_sections, resolve_kind, trial_engine, trial_function, validate_params

SPEC_KEYS: tuple[str, ...] = ('name', 'description', 'tags', 'status', 'kind', 'engine', 'store', 'preset',
                              'periods', 'physics', 'robot', 'noise', 'diagnostics', 'mujoco', 'params', 'analysis',
                              'grid', 'seeds',
                              'report', 'paper')
#: What a spec is for (``tags``): one of the paper's experiments, a speed or accuracy benchmark, a
#: calibration of the sim against the paper, or a diagnostic of one question about the physics.
TAGS: tuple[str, ...] = ('paper', 'benchmark', 'calibration', 'diagnostic')
#: A spec's ``status``: current (``list`` shows it) or superseded by another spec (``list --all``).
STATUSES: tuple[str, ...] = ('current', 'superseded')


@dataclass(frozen=True)
class Trial:
    """One trial: its kind, fully merged parameters, seed and store key."""

    kind: str
    params: Mapping[str, Any]
    seed: int
    key: str
    point: Mapping[str, Any] = field(default_factory=dict)   # the grid values of this trial


@dataclass(frozen=True)
class ExperimentSpec:
    """A validated experiment spec (see the module docstring for the YAML keys)."""

    name: str
    kind: str
    base: Mapping[str, Any]                     # merged parameters before the grid
    grid: tuple[Mapping[str, Sequence[Any]], ...]   # blocks; the points are the union of their products
    seeds: tuple[int, ...]
    description: str = ''
    tags: tuple[str, ...] = ()
    status: str = 'current'
    store: str = ''
    report: tuple[str, ...] = ()
    paper: Mapping[str, Any] = field(default_factory=dict)
    source: str = ''

    @property
    def engine(self) -> str:
        """The engine its trials run on."""
        return trial_engine(self.kind, self.base)

    def code(self) -> dict[str, str]:
        """The code version of its trials (``store.code_version``): the source of the modules its kind runs
        (``kinds.kind_modules``), so an edit of another kind's module leaves its keys as they are."""
        from .store import code_version

        return code_version(kind_modules(self.kind))

    def with_trial_count(self, count: int) -> ExperimentSpec:
        """The same spec with ``count`` trials in all (``--trials``): seeds 0..count/G-1 at each of its G grid
        points; SpecError unless count is a whole multiple >= 1 of G, with the counts that are."""
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise SpecError(f'{self.name}: --trials must be a whole number >= 1, got {count!r}')
        points = len(self.points())
        if count % points:
            raise SpecError(f'{self.name}: --trials counts trials in all; its {points} grid points take a multiple '
                            f'of {points} ({points}, {2 * points}, ...); for K seeds at every grid point give '
                            f'--seeds 0..K-1')
        return _replace(self, seeds=tuple(range(count // points)))

    def with_seeds(self, seeds: Sequence[int]) -> ExperimentSpec:
        """The same spec over ``seeds`` only (``--seeds``), in the same store, under the name
        ``<name>-seeds-<ranges>`` so that its report sits beside the whole spec's; SpecError unless the seeds are
        whole numbers >= 0, at least one, none twice."""
        if not seeds:
            raise SpecError(f'{self.name}: --seeds names no seed')
        if any(isinstance(s, bool) or not isinstance(s, int) or s < 0 for s in seeds):
            raise SpecError(f'{self.name}: --seeds must be whole numbers >= 0, got {list(seeds)!r}')
        if len(set(seeds)) != len(seeds):
            raise SpecError(f'{self.name}: --seeds lists a seed twice')
        label = ','.join(f'{a}-{b}' if b > a else f'{a}' for a, b in seed_runs(sorted(seeds)))
        return _replace(self, seeds=tuple(seeds), name=f'{self.name}-seeds-{label}', store=self.store or self.name)

    def with_periods(self, periods: float) -> ExperimentSpec:
        """The same spec with ``periods`` gait periods per trial; SpecError unless > 0."""
        _check_positive(self.name, 'periods', periods)
        return _replace(self, base={**self.base, 'periods': float(periods)})

    def points(self) -> list[dict[str, Any]]:
        """The grid points (parameter -> value): each block's product in key order, blocks in order; [{}] if none."""
        out: list[dict[str, Any]] = []
        for block in self.grid or ({},):
            names = list(block)
            out += [dict(zip(names, values, strict=True)) for values in itertools.product(*block.values())]
        return out

    def trials(self, code: Mapping[str, str]) -> list[Trial]:
        """Every trial (grid points x seeds), keyed by (kind, parameters, seed, ``code`` version)."""
        out = []
        for point in self.points():
            params = apply_point(self.base, point)
            for seed in self.seeds:
                out.append(Trial(self.kind, params, seed, trial_key(self.kind, params, seed, code), point))
        return out


def _inline_preset_file(name: str, known: Any, base: dict[str, Any]) -> None:
    """A preset file (``smarticle-calibrate``'s) in the trial's own parameters: its base preset, and its physics and
    robot overrides under the spec's own, so a trial's key holds the file's values rather than its path."""
    from smarticle_sim.config_builder import read_preset_file
    from smarticle_sim.errors import ConfigError

    try:
        preset, physics, robot = read_preset_file(str(base['preset']))
    except ConfigError as err:
        raise SpecError(f'{name}: {err}') from None
    base['preset'] = preset
    for group, values in (('physics', physics), ('robot', robot)):
        if values and known is not None and group not in known.params.GROUPS:
            raise SpecError(f'{name}: the preset file sets {group} overrides, not supported by this kind')
        if values:
            base[group] = {**values, **dict(base.get(group) or {})}


def seed_runs(seeds: Sequence[int]) -> list[tuple[int, int]]:
    """Sorted seeds as runs of consecutive ones: [0, 1, 2, 5] -> [(0, 2), (5, 5)]."""
    runs: list[list[int]] = []
    for seed in seeds:
        if runs and seed == runs[-1][1] + 1:
            runs[-1][1] = seed
        else:
            runs.append([seed, seed])
    return [(a, b) for a, b in runs]


def _replace(spec: ExperimentSpec, **changes: Any) -> ExperimentSpec:
    """dataclasses.replace for the frozen spec."""
    from dataclasses import replace

    return replace(spec, **changes)


def coerce(default: Any, value: Any) -> Any:
    """``value`` as a float where the default is a float and the spec wrote a whole number (90 hashes as 90.0)."""
    if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def apply_point(base: Mapping[str, Any], point: Mapping[str, Any]) -> dict[str, Any]:
    """The base parameters with one grid point applied (``physics.X`` / ``robot.X`` / ``noise.X`` /
    ``mujoco.X`` / ``chrono.X`` go into those mappings, copied: the base and the other points keep theirs)."""
    # every mapping copied: a grid point's group.X must not reach the base (or the other points)
    params = {k: dict(v) if isinstance(v, Mapping) else v for k, v in base.items()}
    if 'physics' in base or 'robot' in base:
        params.update(physics=dict(base.get('physics') or {}), robot=dict(base.get('robot') or {}))
    for name, value in point.items():
        group, dot, leaf = name.partition('.')
        if dot:
            params.setdefault(group, {})[leaf] = value
        else:
            params[name] = coerce(base.get(name), value)
    return params


def canonical(value: Any) -> str:
    """Canonical JSON of a value (sorted keys, no spaces) for hashing."""
    return json.dumps(value, sort_keys=True, separators=(',', ':'), default=str)


def trial_key(kind: str, params: Mapping[str, Any], seed: int, code: Mapping[str, str]) -> str:
    """The store key of a trial: a hash of its kind, full parameters, seed and the code's version."""
    text = canonical({'kind': kind, 'params': params, 'seed': seed, 'code': code})
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _check_positive(name: str, field_name: str, value: Any) -> None:
    """SpecError unless ``value`` is a finite number > 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise SpecError(f'{name}: {field_name} must be a number > 0, got {value!r}')


def _mapping(name: str, field_name: str, value: Any) -> dict[str, Any]:
    """A mapping field (None -> {}) or SpecError."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise SpecError(f'{name}: {field_name} must be a mapping, got {type(value).__name__}')
    return dict(value)


def groups_of(known: TrialKind[Any] | None) -> dict[str, frozenset[str]]:
    """The mapping parameters a kind's grid keys ``group.name`` may set, with their names (a user's
    ``module:function`` kind: every registered kind's groups)."""
    if known is not None:
        return dict(known.params.GROUPS)
    out: dict[str, frozenset[str]] = {}
    for kind in KINDS.values():
        for group, names in kind.params.GROUPS.items():
            out[group] = out.get(group, frozenset()) | names
    return out


def _grid_block(name: str, kind: str, known: TrialKind[Any] | None, block: Mapping[str, Any]) -> dict[str, list[Any]]:
    """One grid block (parameter -> non-empty list of values), checked against the kind's parameters."""
    grid: dict[str, list[Any]] = {}
    groups = groups_of(known)
    for key, values in block.items():
        group, dot, leaf = str(key).partition('.')
        if dot:
            if leaf not in groups.get(group, ()):
                raise SpecError(f'{name}: unknown key grid.{key} '
                                f'(not a {", ".join(groups) or "grouped"} setting of kind {kind!r})')
        elif known is not None and (key not in known.defaults or key in ('physics', 'robot')):
            raise SpecError(f'{name}: unknown key grid.{key} for kind {kind!r}')
        if not isinstance(values, list):
            raise SpecError(f'{name}: grid.{key} must be a list of values, got {values!r}')
        if not values:
            raise SpecError(f'{name}: grid.{key} is an empty list: the grid expands to no trials')
        grid[str(key)] = values
    return grid


def _apply_engine(name: str, kind: str, known: TrialKind[Any] | None, data: Mapping[str, Any],
                  base: dict[str, Any]) -> None:
    """A spec's ``engine`` and ``mujoco`` into the base parameters: the engine only if it is not the kind's default
    (so the keys of trials in the default engine stay those of a spec without one); SpecError if the kind does not
    run in it."""
    engine = data.get('engine')
    if engine is not None:
        if not isinstance(engine, str) or engine not in ENGINES:
            raise SpecError(f'{name}: engine must be one of {", ".join(ENGINES)}, got {engine!r}')
        engines = known.engines if known is not None else ('bullet', 'mujoco')
        if engine not in engines:
            raise SpecError(f'{name}: kind {kind!r} runs in {" or ".join(engines)}, not in {engine}')
        if engine != (known.engine if known is not None else 'bullet'):
            base['engine'] = engine
    mujoco = _mapping(name, 'mujoco', data.get('mujoco'))
    if mujoco:
        bad = sorted(set(mujoco) - groups_of(None).get('mujoco', frozenset()))
        if bad:
            raise SpecError(f'{name}: unknown key mujoco.{bad[0]} (not a MujocoSettings field)')
        if known is not None and 'mujoco' not in known.params.GROUPS:
            raise SpecError(f'{name}: mujoco settings are not supported by kind {kind!r}')
        base['mujoco'] = {**dict(base.get('mujoco') or {}), **mujoco}


def spec_seeds(name: str, value: Any) -> tuple[int, ...]:
    """Seeds from a count, a list, {start, count} or the stack's seed syntax as text ('1000..1029',
    ``smarticle_common.cli.parse_seeds``); SpecError for zero, negative or non-integers."""
    def whole(v: Any, what: str, low: int) -> int:
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise SpecError(f'{name}: {what} must be a whole number >= {low}, got {v!r}')
        return v

    if value is None:
        return (0,)
    if isinstance(value, str):
        from smarticle_common.cli import SeedSyntaxError, parse_seeds

        try:
            return tuple(parse_seeds(value))
        except SeedSyntaxError as exc:
            raise SpecError(f'{name}: {exc}') from None
    if isinstance(value, Mapping):
        extra = sorted(set(value) - {'start', 'count'})
        if extra:
            raise SpecError(f'{name}: unknown key seeds.{extra[0]} (known: start, count)')
        start = whole(value.get('start', 0), 'seeds.start', 0)
        return tuple(range(start, start + whole(value.get('count'), 'seeds.count', 1)))
    if isinstance(value, list):
        if not value:
            raise SpecError(f'{name}: seeds is an empty list: no trials to run')
        seeds = tuple(whole(v, 'each seed', 0) for v in value)
        if len(set(seeds)) != len(seeds):
            raise SpecError(f'{name}: seeds lists a seed twice')
        return seeds
    return tuple(range(whole(value, 'seeds', 1)))


def spec_from_mapping(data: Any, source: str = '') -> ExperimentSpec:
    """Validate a parsed YAML mapping into an ExperimentSpec; SpecError names the first bad field."""
    if not isinstance(data, Mapping):
        raise SpecError(f'{source or "spec"}: a spec must be a YAML mapping, got {type(data).__name__}')
    name = data.get('name')
    if not isinstance(name, str) or not name or any(c in name for c in '/\\ '):
        raise SpecError(f'{source or "spec"}: name must be a non-empty word (no spaces or slashes), got {name!r}')
    unknown = [k for k in data if k not in SPEC_KEYS]
    if unknown:
        raise SpecError(f'{name}: unknown key {unknown[0]!r} (known: {", ".join(SPEC_KEYS)})')
    kind = data.get('kind')
    if not isinstance(kind, str):
        raise SpecError(f'{name}: kind is required (one of {", ".join(KINDS)} or module:function)')
    try:
        known = resolve_kind(kind)
    except SpecError as exc:
        raise SpecError(f'{name}: {exc}') from None
    if known is None:
        try:
            trial_function(kind)   # a user's module:function must import here (and on the workers)
        except SpecError as exc:
            raise SpecError(f'{name}: {exc}') from None
    base: dict[str, Any] = dict(known.defaults) if known else {}
    for group in ('params', 'analysis'):
        values = _mapping(name, group, data.get(group))
        if known is not None:
            bad = [k for k in values if k not in known.defaults or k in ('physics', 'robot')]
            if bad:
                raise SpecError(f'{name}: unknown key {group}.{bad[0]} for kind {kind!r} '
                                f'(known: {", ".join(k for k in known.defaults if k not in ("physics", "robot"))})')
        base.update({k: coerce(base.get(k), v) for k, v in values.items()})
    groups = groups_of(None)
    for group in ('physics', 'robot'):
        values = _mapping(name, group, data.get(group))
        bad = sorted(set(values) - groups[group])
        if bad:
            raise SpecError(f'{name}: unknown key {group}.{bad[0]} (not a {group} setting)')
        if values and known is not None and group not in known.params.GROUPS:
            raise SpecError(f'{name}: {group} overrides are not supported by kind {kind!r}')
        if values or known is None or group in base:
            base[group] = values
    diagnostics = _mapping(name, 'diagnostics', data.get('diagnostics'))
    if diagnostics:   # left out of the trial's parameters while empty (the shipped model)
        bad = sorted(set(diagnostics) - groups.get('diagnostics', frozenset()))
        if bad:
            raise SpecError(f'{name}: unknown key diagnostics.{bad[0]} (not a diagnostics setting)')
        if known is not None and 'diagnostics' not in known.params.GROUPS:
            raise SpecError(f'{name}: diagnostics are not supported by kind {kind!r}')
        base['diagnostics'] = diagnostics
    if data.get('noise') is not None:
        try:
            noise = noise_mapping(data['noise'])
        except SpecError as exc:
            raise SpecError(f'{name}: {exc}') from None
        if noise and known is not None and 'noise' not in known.params.GROUPS:
            raise SpecError(f'{name}: noise is not supported by kind {kind!r}')
        if noise:
            base['noise'] = noise
    _apply_engine(name, kind, known, data, base)
    if 'preset' in data:
        if known is not None and 'preset' not in known.defaults:
            raise SpecError(f'{name}: preset is not supported by kind {kind!r}')
        base['preset'] = data['preset']
        from smarticle_sim.config_builder import is_preset_file

        if is_preset_file(data['preset']):
            _inline_preset_file(name, known, base)
    if 'periods' in data:
        _check_positive(name, 'periods', data['periods'])
        base['periods'] = float(data['periods'])
    raw = data.get('grid')
    blocks = raw if isinstance(raw, list) else [raw]
    if isinstance(raw, list) and not raw:
        raise SpecError(f'{name}: grid is an empty list: the grid expands to no trials')
    grid = tuple(_grid_block(name, kind, known, _mapping(name, 'grid', block)) for block in blocks)
    seeds = spec_seeds(name, data.get('seeds'))
    report = data.get('report') or []
    if not isinstance(report, list) or not all(isinstance(r, str) for r in report):
        raise SpecError(f'{name}: report must be a list of section names')
    sections = report_sections(kind)
    bad_sections = [r for r in report if r not in sections]
    if bad_sections:
        raise SpecError(f'{name}: unknown report section {bad_sections[0]!r} for kind {kind!r} '
                        f'(known: {", ".join(sections) or "none"})')
    paper = _mapping(name, 'paper', data.get('paper'))
    store = data.get('store', name)
    if not isinstance(store, str) or not store or any(c in store for c in '/\\ '):
        raise SpecError(f'{name}: store must be a folder name, got {store!r}')
    tags = data.get('tags') or []
    if not isinstance(tags, list) or any(t not in TAGS for t in tags):
        raise SpecError(f'{name}: tags must be a list of {", ".join(TAGS)}, got {tags!r}')
    status = data.get('status', 'current')
    if status not in STATUSES:
        raise SpecError(f'{name}: status must be one of {", ".join(STATUSES)}, got {status!r}')
    spec = ExperimentSpec(name=name, kind=kind, base=base, grid=grid, seeds=seeds,
                          description=str(data.get('description', '')), tags=tuple(tags), status=str(status),
                          store=store, report=tuple(report),
                          paper=paper, source=source)
    if 'periods' in base:
        _check_positive(name, 'periods', base['periods'])
    for point in spec.points():   # every grid point must make a valid config and gait
        try:
            validate_params(kind, apply_point(base, point))
        except SpecError as exc:
            where = f' at grid point {point}' if point else ''
            raise SpecError(f'{name}: {exc}{where}') from None
    return spec


def builtin_dir() -> Path:
    """The folder of the shipped specs (config/experiments of the package, source tree or install share)."""
    here = Path(__file__).resolve().parent.parent / 'config' / 'experiments'
    if here.is_dir():
        return here
    try:
        from ament_index_python.packages import get_package_share_directory

        return Path(get_package_share_directory('smarticle_experiments')) / 'config' / 'experiments'
    except (ImportError, LookupError, ValueError):
        return here


def archive_dir() -> Path | None:
    """The archive of superseded specs in a source tree (``archive/specs`` at the repository root; not
    installed), or None."""
    here = Path(__file__).resolve().parents[2] / 'archive' / 'specs'
    return here if here.is_dir() else None


def archive_names() -> list[str]:
    """Names of the archived specs of a source tree (empty when installed)."""
    folder = archive_dir()
    return sorted(p.stem for p in folder.glob('*.yaml')) if folder else []


def builtin_names() -> list[str]:
    """Names of the shipped specs."""
    return sorted(p.stem for p in builtin_dir().glob('*.yaml'))


def builtin_name(name: str) -> str:
    """The shipped spec called ``name``, whatever its case (``P7`` is ``p7``); SpecError naming the closest
    shipped names when there is none."""
    names = builtin_names()
    if name in names:
        return name
    folded = {n.lower(): n for n in names}
    if name.lower() in folded:
        return folded[name.lower()]
    if name in archive_names():
        raise SpecError(f'experiment {name!r} is archived: archive/README.md names the commit that runs it')
    close = [folded[c] for c in difflib.get_close_matches(name.lower(), list(folded), n=3, cutoff=0.5)]
    hint = f'did you mean {" or ".join(close) if len(close) < 3 else ", ".join(close[:-1]) + " or " + close[-1]}? ' \
        if close else ''
    raise SpecError(f'no experiment {name!r}: not a file and not a shipped spec; {hint}'
                    f'`smarticle-experiments list` shows the {len(names)} shipped specs')


def load_spec(name_or_path: str, engine: str | None = None) -> ExperimentSpec:
    """Load a shipped spec by name (``p1``, any case) or a user's YAML file by path; SpecError if missing or
    invalid. ``engine`` (``--engine``) replaces the spec's engine: in another engine than its own the spec is
    named ``<name>-<engine>`` (its report sits beside the spec's own), in the same store."""
    path = Path(name_or_path)
    if not (path.suffix in ('.yaml', '.yml') or path.exists()):
        path = builtin_dir() / f'{builtin_name(name_or_path)}.yaml'
    if not path.is_file():
        raise SpecError(f'spec file {path} does not exist')
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise SpecError(f'{path}: not valid YAML ({str(exc).splitlines()[0]})') from None
    if engine is not None:
        data = with_engine(data, engine)
    return spec_from_mapping(data, str(path))


def with_engine(data: Any, engine: str) -> Any:
    """A spec mapping in ``engine``: its ``engine`` replaced and, unless that is its own engine already, named
    ``<name>-<engine>`` in the same store (a mapping without a usable name or kind is left to
    ``spec_from_mapping`` to refuse)."""
    if not isinstance(data, Mapping) or not isinstance(data.get('name'), str):
        return data
    kind = data.get('kind')
    known = KINDS.get(kind) if isinstance(kind, str) else None
    own = data.get('engine') or (known.engine if known is not None else 'bullet')
    if engine == own:
        return {**data, 'engine': engine}
    return {**data, 'engine': engine, 'name': f'{data["name"]}-{engine}', 'store': data.get('store', data['name'])}
