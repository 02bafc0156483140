"""Reports: Markdown and PNG figures from the stored trials of a spec, with the paper against the sim.

Every number carries its 95 % interval (``stats``); each paper-against-sim row says whether the paper's
value lies inside the sim's interval. Trials that ended in SimTrouble are excluded from the statistics
(their runs stop early) but counted and listed; failed trials (the trial raised, or the engine lost it)
are counted and listed with the last line of their traceback.

Words, as the glider analysis defines them (``smarticle_tracking.gliders``, docs/gliders.md): a stored
``GliderRecord`` is a **bound pair** (bound >= K = ``min_periods`` periods in a row); it is a **glider** only
if its stored net travel is at least ``TRAVEL_MIN_W_PER_100`` W per 100 periods of its run (``pair_kind``);
C1 / C2 are the bands of its mean phi. Every section that counts bound pairs counts the gliders among them
too; the P6 kind stores a pair's travel only with ``details``, and without it the section says so. Sections
(the spec's ``report`` list):

* ``p1`` fraction of trials with a pair bound >= ``positive_periods`` (and its isolated variant, and the
  isolated variant that is a glider), and the distance those pairs travel (W);
* ``trajectories`` body-centre paths of one trial (Fig. 1c);
* ``configurations`` r and phi histograms of the bound pairs, C1 / C2 shares, of the gliders too (Fig. 3c, P2);
* ``lifetimes`` lifetime against phi, semi-log lifetime histogram, Kaplan-Meier per class (P3);
* ``basin`` bound-at-end map over (theta, phi) for each phase of robot 2 (Fig. 4a, P4);
* ``alpha_sweep`` ensemble MSD, beta, V_com and r against alpha_max (Fig. 6, P5);
* ``p6`` C2 pairs' bound runs open loop against feedback, Kaplan-Meier (Fig. 5d);
* ``drift`` single-robot drift per cycle (P7);
* ``accuracy`` run time against error of the physics settings.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from smarticle_common.facts import R_BIND_BL
from smarticle_sim.mujoco_engine import MujocoSettings
from smarticle_sim.settings import BULLET_SOLVER_RESIDUAL_THRESHOLD
from smarticle_tracking.gliders import MIN_PERIODS, GliderConfig, PairKind, pair_kind, rule_text, travel_rate

from .errors import ResultError
from .kinds import KINDS, read_result, trial_engine
from .results import (AccuracyResult, DenseResult, GliderRecord, InadmissiblePairResult, P6Result,
                      PairResult, SingleResult, TrialResult)
from .quantities import antiparallel_band, theta_quadrants
from .spec import ExperimentSpec, Trial, canonical, seed_runs
from .stats import Estimate, bootstrap_mean, fisher_p, kaplan_meier, logrank, wilson
from .store import ResultStore, json_ready, write_atomic
from .trials import config_of, ensemble_msd, msd_beta


T = TypeVar('T')


@dataclass
class Comparison:
    """One paper-against-sim row."""

    quantity: str
    paper: str
    sim: Estimate | None
    sim_text: str
    inside: bool | None
    note: str = ''


def seed_ranges(seeds: Sequence[int]) -> str:
    """Sorted seeds compactly: ``1000, 1001, 1003..1021, 1023`` (a run of three or more as ``a..b``; '-' if none)."""
    if not seeds:
        return '-'
    return ', '.join(f'{a}..{b}' if b - a >= 2 else ', '.join(map(str, range(a, b + 1)))
                     for a, b in seed_runs(seeds))


@dataclass
class Context:
    """What a report section sees: the spec, its trials, their stored records, the output folder."""

    spec: ExperimentSpec
    trials: list[Trial]
    records: dict[str, dict[str, Any]]
    folder: Path
    figures: list[Path] = field(default_factory=list)
    comparisons: list[Comparison] = field(default_factory=list)

    @cached_property
    def rule(self) -> GliderConfig:
        """The glider analysis's definitions with the spec's K and bind distance (``glider_rule``)."""
        return glider_rule(self.spec)

    def ok(self) -> list[tuple[Trial, TrialResult | dict[str, Any]]]:
        """Finished trials that did not end in trouble, with their typed results (``results.read_result``)."""
        out = []
        for t in self.trials:
            rec = self.records.get(t.key)
            if rec and rec.get('status') == 'ok' and not (rec.get('result') or {}).get('trouble'):
                out.append((t, read_result(t.kind, rec['result'])))
        return out

    def _ok_of(self, section: str, types: tuple[type, ...]) -> list[tuple[Trial, Any]]:
        """``ok()`` for a section that reads results of ``types``; ResultError names a trial of another kind."""
        out = []
        for t, r in self.ok():
            if not isinstance(r, types):
                raise ResultError(f'report section {section!r} reads {" or ".join(c.__name__ for c in types)} '
                                  f'results; trial {t.key} (kind {t.kind}) gives {type(r).__name__}')
            out.append((t, r))
        return out

    def ok_as(self, section: str, cls: type[T]) -> list[tuple[Trial, T]]:
        """``ok()`` for a section that reads results of one type ``cls``."""
        return self._ok_of(section, (cls,))

    def ok_gliders(self, section: str) -> list[tuple[Trial, DenseResult | InadmissiblePairResult]]:
        """``ok()`` for a section that reads gliders: dense and pair trials, inadmissible pair starts included."""
        return self._ok_of(section, (DenseResult, InadmissiblePairResult))

    def ok_pairs(self, section: str) -> list[tuple[Trial, PairResult | InadmissiblePairResult]]:
        """``ok()`` for a section that reads pair trials, inadmissible starts included."""
        return self._ok_of(section, (PairResult, InadmissiblePairResult))

    def seeds_text(self, pairs: Sequence[tuple[Trial, Any]]) -> str:
        """The seeds of some trials, compactly."""
        return seed_ranges(sorted({t.seed for t, _ in pairs}))

    def save(self, fig: Any, name: str) -> Path:
        """Write a figure as ``<name>.png`` in the report folder."""
        path = self.folder / f'{name}.png'
        fig.tight_layout()
        fig.savefig(path)
        self.figures.append(path)
        return path


def figure(width: float = 7.0, height: float = 5.0) -> Any:
    """A matplotlib Figure on the Agg backend."""
    import matplotlib

    matplotlib.use('Agg')
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), dpi=100)


def legend(ax: Any, size: int = 7) -> None:
    """A legend, if anything on ``ax`` has a label."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=size)


def _paper(ctx: Context, name: str, default: Any = None) -> Any:
    """A paper value from the spec's ``paper`` mapping."""
    return ctx.spec.paper.get(name, default)


def _bound_pairs(pairs: Sequence[tuple[Trial, DenseResult]]) -> list[GliderRecord]:
    """Every bound pair (stored glider record) of the given trials."""
    return [g for _, res in pairs for g in res.gliders]


def _num(value: float | None) -> float:
    """A stored number, NaN for None (JSON's NaN)."""
    return math.nan if value is None else float(value)


def _longest(res: DenseResult | InadmissiblePairResult) -> GliderRecord | None:
    """A trial's longest bound pair (the first of equal lifetimes), or None."""
    return max(res.gliders, key=lambda g: g.lifetime_periods, default=None)


def glider_rule(spec: ExperimentSpec) -> GliderConfig:
    """The glider analysis's definitions (``smarticle_tracking.gliders``) with the spec's K (``min_periods``)
    and bind distance, in the stored records' unit: lengths in W, so body length and width are 1."""
    return GliderConfig(min_periods=int(spec.base.get('min_periods', MIN_PERIODS)),
                        r_bind=float(spec.base.get('r_bind_bl', R_BIND_BL)), body_length=1.0, width=1.0,
                        isolation_distance=float(spec.base.get('isolation_w', 2.0)))


def travel_per_100(g: GliderRecord) -> float:
    """A stored bound pair's net travel in W per 100 periods of its run (NaN when not stored)."""
    return travel_rate(_num(g.distance_w), g.lifetime_periods, 1.0)


def is_glider(g: GliderRecord, rule: GliderConfig) -> bool:
    """True when a stored bound pair is a glider: its net travel meets the glider rule (``pair_kind``)."""
    return pair_kind(g.lifetime_periods, _num(g.distance_w), rule) is PairKind.GLIDER


def gliders_among(pairs: Sequence[GliderRecord], rule: GliderConfig) -> int:
    """How many of some stored bound pairs are gliders."""
    return sum(is_glider(g, rule) for g in pairs)


def words_line(rule: GliderConfig) -> str:
    """The definitions a report's glider counts use, once at its top."""
    return (f'Words (the glider analysis, docs/gliders.md): {rule_text(rule)}. A count of bound pairs includes the '
            'gliders among them.')


def pairs_count(pairs: Sequence[GliderRecord], rule: GliderConfig) -> str:
    """'663 bound pairs (>= 30 periods), 12 of them gliders (>= 1 W per 100 periods)': both numbers."""
    n, moving = len(pairs), gliders_among(pairs, rule)
    return (f'{n} bound pair{"" if n == 1 else "s"} (>= {rule.min_periods} periods), {moving} of them '
            f'glider{"" if moving == 1 else "s"} (>= {rule.travel_min_w_per_100:g} W per 100 periods)')


# ------------------------------------------------------------------ sections


def section_p1(ctx: Context) -> list[str]:
    """P1: trials with a pair bound >= positive_periods, the isolated variant, the isolated variant that is a
    glider (the paper's claim), and the travel of those pairs."""
    pairs = ctx.ok_as('p1', DenseResult)
    rule = ctx.rule
    n = len(pairs)
    positive = sum(bool(r.positive) for _, r in pairs)
    isolated = sum(bool(r.positive_isolated) for _, r in pairs)
    limit = ctx.spec.base.get('positive_periods', 100)
    iso_w = ctx.spec.base.get('isolation_w', 2.0)
    gliding = sum(any(g.lifetime_periods >= limit and g.isolated and is_glider(g, rule) for g in r.gliders)
                  for _, r in pairs)
    frac, frac_iso, frac_glide = wilson(positive, n), wilson(isolated, n), wilson(gliding, n)
    distances = [max((g for g in r.gliders if g.lifetime_periods >= limit),
                     key=lambda g: g.lifetime_periods).distance_w for _, r in pairs if r.positive]
    dist = bootstrap_mean([_num(d) for d in distances])
    p_frac, p_dist = _paper(ctx, 'fraction_bound', 0.64), _paper(ctx, 'distance_w', 2.9)
    rate = rule.travel_min_w_per_100
    ctx.comparisons += [
        Comparison(f'P1 trials with an isolated pair bound >= {limit} periods (no third robot within {iso_w:g} W '
                   'in >= 90 % of its periods)', f'{p_frac:.0%} (97/151)', frac_iso,
                   f'{frac_iso.text(".1%", 1)} ({isolated}/{n})', frac_iso.contains(p_frac),
                   'bound pairs, travel not checked'),
        Comparison(f'P1 trials with an isolated glider bound >= {limit} periods (the pair also travels >= {rate:g} W '
                   'per 100 periods)', f'{p_frac:.0%} (97/151)', frac_glide,
                   f'{frac_glide.text(".1%", 1)} ({gliding}/{n})', frac_glide.contains(p_frac),
                   'the glider rule'),
        Comparison('P1 same, any bound pair (clusters and trains included)', f'{p_frac:.0%}', frac,
                   f'{frac.text(".1%", 1)} ({positive}/{n})', frac.contains(p_frac)),
        Comparison(f'P1 distance travelled by the longest pair bound >= {limit} periods (W)',
                   f'{p_dist} +- 0.2 (its gliders)', dist, dist.text('.2f'), dist.contains(p_dist),
                   'the longest bound pair >= the limit in each positive trial, glider or not'),
    ]
    fig = figure(6, 4)
    ax = fig.add_subplot(1, 1, 1)
    ax.scatter([r.longest_periods for _, r in pairs], [r.longest_distance_w or 0.0 for _, r in pairs], s=12)
    ax.axvline(limit, color='k', ls=':', lw=0.8)
    reach = max([limit, *(r.longest_periods for _, r in pairs)])
    ax.plot([0, reach], [0.0, rate * reach / 100.0], color='tab:red', ls='--', lw=0.8,
            label=f'glider rule ({rate:g} W per 100 periods): gliders above')
    ax.set_xlabel('longest bound pair\'s lifetime (periods)')
    ax.set_ylabel('its distance travelled (W)')
    ax.set_title(f'P1: {positive}/{n} trials with a pair bound >= {limit} periods, {gliding} with an isolated glider',
                 fontsize=9)
    legend(ax, 7)
    ctx.save(fig, 'p1_longest')
    return [f'Positive trial: a pair bound for >= {limit} periods (a bound pair of the glider analysis, K = '
            f'{rule.min_periods} periods, bound = r under {rule.r_bind:g} BL in any frame of a period), glider or '
            f'not; the glider row asks the pair to travel >= {rate:g} W per 100 periods of its run too. Isolated: in '
            f'>= 90 % of its periods no third robot\'s centre within {iso_w:g} W of either robot. '
            f'{pairs_count(_bound_pairs(pairs), rule)} in {n} trials.', '', '![P1](p1_longest.png)', '',
            *long_pairs_table(pairs, limit, rule), *end_groups_table(pairs, iso_w)]


#: A descriptive cut of the long pairs' table: net displacement of at least this many W per 100 periods (the
#: paper's gliders: 2.9 W in >= 100 periods; P5's free pair at 90 deg about 3-4 W per 100 periods). Not the glider
#: rule (``smarticle_tracking.gliders.TRAVEL_MIN_W_PER_100``, 1 W per 100 periods): a faster share of the pairs.
FAST_W_PER_100 = 2.0


def long_pairs_table(pairs: Sequence[tuple[Trial, DenseResult]], limit: int, rule: GliderConfig) -> list[str]:
    """What the pairs bound >= ``limit`` periods are: by class and by isolation, how many are gliders, their mean
    r and their net travel per 100 periods (median and quartiles), and how many travel >= ``FAST_W_PER_100``."""
    long = [g for _, r in pairs for g in r.gliders if g.lifetime_periods >= limit]
    if not long:
        return []
    groups = [('all', long)] + [(c, [g for g in long if g.glider_class == c]) for c in ('C1', 'C2', 'unclassified')]
    groups += [('isolated', [g for g in long if g.isolated]),
               ('in a group', [g for g in long if not g.isolated])]

    def quartiles(values: list[float]) -> str:
        q1, q2, q3 = np.percentile(values, [25, 50, 75])
        return f'{q2:.2f} [{q1:.2f}, {q3:.2f}]'

    lines = [f'Pairs bound >= {limit} periods, what they are (gliders: those travelling >= '
             f'{rule.travel_min_w_per_100:g} W per 100 periods of their run; r: the pair\'s mean centre distance; '
             'travel: its net displacement per 100 periods of its run; median [quartiles]):', '',
             f'| bound pairs | n | gliders | r (BL) | travel (W per 100 periods) | faster than {FAST_W_PER_100:g} W '
             'per 100 periods |', '| --- | ---: | ---: | --- | --- | ---: |']
    for name, gs in groups:
        if not gs:
            continue
        travel = [travel_per_100(g) for g in gs]
        fast = sum(t >= FAST_W_PER_100 for t in travel)
        lines.append(f'| {name} | {len(gs)} | {gliders_among(gs, rule)} | '
                     f'{quartiles([_num(g.r_bl) for g in gs])} | {quartiles(travel)} | {fast} |')
    return [*lines, '']


def end_groups(xy: np.ndarray, reach: float) -> tuple[int, ...]:
    """Sizes (largest first) of the groups of robots at positions ``xy`` (N, 2): robots whose centres are
    closer than ``reach`` are in one group, and so are their neighbours' neighbours (single linkage)."""
    from scipy.sparse.csgraph import connected_components

    ok = np.isfinite(xy).all(axis=1)
    pts = xy[ok]
    close = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2) < reach
    _, labels = connected_components(close, directed=False)
    return tuple(sorted(np.bincount(labels).tolist(), reverse=True))


def end_groups_table(pairs: Sequence[tuple[Trial, DenseResult]], reach_w: float) -> list[str]:
    """How the collective ends: the groups of robots within ``reach_w`` W (= BL) of each other in the last
    recorded frame of every trial that ran to its end, e.g. 6+1 or 4+2+1."""
    counts: dict[tuple[int, ...], int] = defaultdict(int)
    largest, whole = [], 0
    for t, r in pairs:
        traj = r.trajectory_bl
        if not traj or float(r.periods_run) < float(t.params.get('periods', 0.0)):
            continue
        last = np.array([[math.nan if v is None else v for v in p] for p in traj[-1]], dtype=float)
        sizes = end_groups(last, reach_w)
        counts[sizes] += 1
        largest.append(sizes[0])
        whole += len(sizes) == 1
    if not counts:
        return []
    n = sum(counts.values())
    lines = [f'Groups at the end of the run (robots closer than {reach_w:g} W, single linkage; {n} trials that ran to '
             f'the end; largest group: median {np.median(largest):g} robots, all robots in one group in '
             f'{whole} trials):', '',
             '| groups | trials | share [95 %] |', '| --- | ---: | --- |']
    for sizes, k in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])):
        lines.append(f'| {"+".join(map(str, sizes))} | {k} | {wilson(k, n).text(".0%")} |')
    return lines


def section_trajectories(ctx: Context) -> list[str]:
    """Fig. 1c: body-centre trajectories of one trial (the first positive one, else the first)."""
    pairs = [(t, r) for t, r in ctx.ok_as('trajectories', DenseResult) if r.trajectory_bl]
    if not pairs:
        return ['No trajectory recorded.']
    trial, res = next(((t, r) for t, r in pairs if r.positive), pairs[0])
    xy = np.array([[[math.nan if v is None else v for v in p] for p in row] for row in res.trajectory_bl])
    fig = figure(6, 6)
    ax = fig.add_subplot(1, 1, 1)
    longest = _longest(res)
    for k in range(xy.shape[1]):
        bold = longest is not None and k in (longest.i, longest.j)
        line, = ax.plot(xy[:, k, 0], xy[:, k, 1], lw=1.6 if bold else 0.7, label=f'{k}')
        ax.plot(xy[0, k, 0], xy[0, k, 1], 'o', color=line.get_color(), ms=4)
    ax.set_aspect('equal')
    ax.set_xlabel('x (BL)')
    ax.set_ylabel('y (BL)')
    ax.set_title(f'seed {trial.seed}: one sample per period (o start; bold: the longest bound pair)', fontsize=9)
    legend(ax, 7)
    ctx.save(fig, 'trajectories')
    return [f'Trajectories of seed {trial.seed} (Fig. 1c):', '', '![trajectories](trajectories.png)']


def section_configurations(ctx: Context) -> list[str]:
    """Fig. 3c / P2: r and phi histograms of the bound pairs; C1 and C2 shares of the bound pairs and of the
    gliders among them."""
    pairs = ctx.ok_as('configurations', DenseResult)
    rule = ctx.rule
    gl = [g for g in _bound_pairs(pairs) if g.r_bl is not None and g.phi_deg is not None]
    moving = [g for g in gl if is_glider(g, rule)]
    n = len(gl)
    c1, c2 = sum(g.glider_class == 'C1' for g in gl), sum(g.glider_class == 'C2' for g in gl)
    e1, e2 = wilson(c1, n), wilson(c2, n)
    both = n > 0 and e1.low > 0 and e2.low > 0
    m1, m2 = sum(g.glider_class == 'C1' for g in moving), sum(g.glider_class == 'C2' for g in moving)
    g1, g2 = wilson(m1, len(moving)), wilson(m2, len(moving))
    both_moving = bool(moving) and g1.low > 0 and g2.low > 0
    tol = math.degrees(rule.class_tolerance)
    band1, band2 = f'mean phi {180 - tol:.0f}-{180 + tol:.0f} deg', f'mean phi {360 - tol:.0f}-{tol:.0f} deg'
    ctx.comparisons += [
        Comparison(f'P2 share of bound pairs in C1 ({band1})', 'one of two modes', e1,
                   f'{e1.text(".1%", 1)} ({c1}/{n})', None, 'qualitative; bound pairs, travel not checked'),
        Comparison(f'P2 share of bound pairs in C2 ({band2})', 'one of two modes', e2,
                   f'{e2.text(".1%", 1)} ({c2}/{n})', None, 'qualitative; bound pairs, travel not checked'),
        Comparison('P2 both modes present among the bound pairs', 'yes', None, 'yes' if both else 'no', both,
                   'inside = both Wilson lower bounds > 0'),
        Comparison(f'P2 both modes present among the gliders (bound pairs travelling >= '
                   f'{rule.travel_min_w_per_100:g} W per 100 periods)', 'yes', None,
                   f'{g1.text(".1%", 1)} C1 ({m1}), {g2.text(".1%", 1)} C2 ({m2}) of {len(moving)} '
                   f'glider{"" if len(moving) == 1 else "s"}'
                   if moving else 'no glider among them',
                   both_moving, 'inside = both Wilson lower bounds > 0'),
    ]
    fig = figure(10, 4)
    ax1, ax2 = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for cls, colour in (('C1', 'tab:red'), ('C2', 'tab:blue'), ('unclassified', 'tab:gray')):
        sel = [g for g in gl if g.glider_class == cls]
        ax1.hist([g.r_bl for g in sel], bins=np.linspace(0.8, 2.0, 25), alpha=0.6, color=colour, label=cls)
        ax2.hist([g.phi_deg for g in sel], bins=np.linspace(0, 360, 37), alpha=0.6, color=colour, label=cls)
    ax1.set_xlabel('r (BL)')
    ax2.set_xlabel('phi (deg)')
    for ax in (ax1, ax2):
        ax.set_ylabel('bound pairs')
        legend(ax, 7)
    fig.suptitle(f'{n} bound pairs ({len(moving)} of them gliders) from {len(pairs)} trials (mean r, circular mean '
                 'phi per pair)', fontsize=9)
    ctx.save(fig, 'configurations')
    return [f'{pairs_count(gl, rule)} in {len(pairs)} trials; C1: {band1}, C2: {band2}.', '',
            '![r and phi histograms](configurations.png)']


def section_lifetimes(ctx: Context) -> list[str]:
    """P3: the bound pairs' lifetime against phi, semi-log lifetime histogram, Kaplan-Meier per class."""
    pairs = ctx.ok_as('lifetimes', DenseResult)
    rule = ctx.rule
    gl = _bound_pairs(pairs)
    periods = float(ctx.spec.base.get('periods', 300))
    lines = ['| class | bound pairs | of them gliders | still bound at the end | KM median lifetime (periods) [95 %] |',
             '| --- | ---: | ---: | ---: | --- |']
    fig = figure(12, 4)
    ax1, ax2, ax3 = (fig.add_subplot(1, 3, k) for k in (1, 2, 3))
    for cls, colour in (('C1', 'tab:red'), ('C2', 'tab:blue'), ('unclassified', 'tab:gray')):
        sel = [g for g in gl if g.glider_class == cls]
        if not sel:
            lines.append(f'| {cls} | 0 | 0 | - | - |')
            continue
        life = [g.lifetime_periods for g in sel]
        cens = [bool(g.ongoing) for g in sel]
        km = kaplan_meier(life, cens)
        end = wilson(sum(cens), len(sel))
        lines.append(f'| {cls} | {len(sel)} | {gliders_among(sel, rule)} | {end.text(".0%", 1)} | '
                     f'{km.median.text(".0f")} |')
        ax1.scatter([g.phi_deg for g in sel], life, s=10, color=colour, label=cls)
        ax2.hist(life, bins=np.linspace(0, periods, 31), alpha=0.6, color=colour, label=cls)
        ax3.step(np.r_[0, km.times], np.r_[1, km.survival], where='post', color=colour, label=cls)
        ax3.fill_between(np.r_[0, km.times], np.r_[1, km.low], np.r_[1, km.high], step='post', color=colour,
                         alpha=0.15)
        if cls == 'C2':
            lo, hi = _paper(ctx, 'c2_lifetime_range', [60, 100])
            overlap = km.median.low <= hi and km.median.high >= lo
            ctx.comparisons.append(Comparison('P3 C2 bound pairs\' median lifetime (periods, Kaplan-Meier)',
                                              f'~{lo}-{hi}', km.median, km.median.text('.0f'), bool(overlap),
                                              'inside = paper range overlaps the interval; bound pairs, travel not '
                                              'checked'))
        if cls == 'C1':
            ctx.comparisons.append(Comparison('P3 C1 bound pairs still bound at the end of the trial', 'many', end,
                                              f'{end.text(".0%", 1)} ({sum(cens)}/{len(sel)})',
                                              bool(end.low > 0), 'inside = Wilson lower bound > 0'))
    ax1.set_xlabel('phi (deg)')
    ax1.set_ylabel('lifetime (periods)')
    ax2.set_yscale('log')
    ax2.set_xlabel('lifetime (periods)')
    ax2.set_ylabel('bound pairs (log)')
    ax3.set_xlabel('lifetime (periods)')
    ax3.set_ylabel('survival (Kaplan-Meier, 95 % band)')
    for ax in (ax1, ax2, ax3):
        legend(ax, 7)
    ctx.save(fig, 'lifetimes')
    return [f'Lifetimes of the bound pairs, gliders or not ({pairs_count(gl, rule)}); those still bound at the end '
            'of a trial are right-censored (Kaplan-Meier).', '',
            *lines, '', '![lifetimes](lifetimes.png)']


#: Outcome of a P4 start -> its colour in the basin maps (pink bound, blue repelled, as in the paper's Fig. 4a).
BASIN_COLOURS = {'bound': 'tab:pink', 'repelled': 'tab:blue', 'neither': 'lightgrey', 'inadmissible': 'k'}

#: How the basin section words the quadrant rule of ``theta_quadrants``.
QUADRANT_RULE = ('theta 0 counts in quadrants 1, 4 and theta 180 in 2, 3 (each lies between two quadrants of its '
                 'pair); theta 90 and 270, the line between the pairs, count in neither')


#: The classes of P4 starts the basin table, its Fisher tests and its paper-against-sim rows count (quadrants:
#: ``theta_quadrants``; "antiparallel" / "parallel" exactly phi = 180 / 0, the bands 90 <= phi <= 270 against the
#: rest).
BASIN_CLASSES: tuple[tuple[str, Callable[[float, float], bool]], ...] = (
    ('all admissible', lambda theta, phi: True),
    ('theta in quadrants 1, 4', lambda theta, phi: theta_quadrants(theta) == '1, 4'),
    ('theta in quadrants 2, 3', lambda theta, phi: theta_quadrants(theta) == '2, 3'),
    ('antiparallel normals (phi 180)', lambda theta, phi: phi == 180.0),
    ('parallel normals (phi 0)', lambda theta, phi: phi == 0.0),
    ('antiparallel band (90 <= phi <= 270)', lambda theta, phi: antiparallel_band(phi)),
    ('parallel band (phi < 90 or > 270)', lambda theta, phi: not antiparallel_band(phi)),
)


def basin_outcome(r: PairResult | InadmissiblePairResult) -> str:
    """A P4 start's outcome by the issue's rule: 'bound' if the pair is in contact in each of the last
    ``bound_tail`` periods (it keeps colliding to the end), 'repelled' if its centres end farther apart than
    twice the robot's reach (no shape can touch), 'neither' otherwise, or 'inadmissible'."""
    if isinstance(r, InadmissiblePairResult) or not r.admissible:
        return 'inadmissible'
    if r.colliding_at_end:
        return 'bound'
    return 'repelled' if r.out_of_reach_at_end else 'neither'


def section_basin(ctx: Context) -> list[str]:
    """Fig. 4a / P4: each start's outcome (bound, repelled, neither) over the (theta, phi) grid per phase of
    robot 2, and the bound share of each class of starts."""
    rows = ctx.ok_pairs('basin')
    adm = [(t, r) for t, r in rows if isinstance(r, PairResult) and r.admissible]
    phases = sorted({float(t.params['phase2']) for t, _ in rows})
    tail = ctx.spec.base.get('bound_tail')
    legend_text = 'pink bound, blue repelled, grey neither, black inadmissible'
    fig = figure(5.5 * max(1, len(phases)), 5)
    for k, phase in enumerate(phases):
        ax = fig.add_subplot(1, max(1, len(phases)), k + 1)
        for t, r in (x for x in rows if float(x[0].params['phase2']) == phase):
            ax.scatter(float(t.params['theta_deg']), float(t.params['phi_deg']), c=BASIN_COLOURS[basin_outcome(r)],
                       s=30, marker='s')
        ax.set_xlabel('theta (deg)')
        ax.set_ylabel('phi (deg)')
        ax.set_title(f'phase {phase:g}: {legend_text}', fontsize=8)
    ctx.save(fig, 'basin')
    polar = figure(5.5 * max(1, len(phases)), 5.5)
    for k, phase in enumerate(phases):   # Fig. 4a: robot 2 around robot 1 at angle theta, rings = phi
        ax = polar.add_subplot(1, max(1, len(phases)), k + 1, projection='polar')
        sel = [x for x in rows if float(x[0].params['phase2']) == phase]
        ax.scatter([math.radians(float(t.params['theta_deg'])) for t, _ in sel],
                   [float(t.params['phi_deg']) % 360.0 + 30.0 for t, _ in sel],
                   c=[BASIN_COLOURS[basin_outcome(r)] for _, r in sel], s=40, marker='s')
        ax.set_rlim(0.0, 400.0)
        ax.set_rticks([30.0, 120.0, 210.0, 300.0], labels=['phi 0', '90', '180', '270'], fontsize=6)
        ax.set_title(f'phase {phase:g}: angle = theta, ring = phi', fontsize=8)
    ctx.save(polar, 'basin_polar')
    judged = [(t, basin_outcome(r)) for t, r in adm]
    bound = [(t, r) for (t, r), (_, outcome) in zip(adm, judged, strict=True) if outcome == 'bound']
    counts = {name: sum(outcome == name for _, outcome in judged) for name in ('bound', 'repelled', 'neither')}
    earlier = sum(bool(r.bound_at_end) for _, r in adm)

    def angles(t: Trial) -> tuple[float, float]:
        return float(t.params['theta_deg']) % 360.0, float(t.params['phi_deg']) % 360.0

    classes = dict(BASIN_CLASSES)
    in_front = sum(classes['theta in quadrants 1, 4'](*angles(t)) for t, _ in bound)
    share = wilson(in_front, len(bound))
    anti = wilson(sum(classes['antiparallel band (90 <= phi <= 270)'](*angles(t)) for t, _ in bound), len(bound))
    ctx.comparisons += [
        Comparison('P4 bound starts with theta in quadrants 1 and 4', 'mostly (> 50 %)', share,
                   f'{share.text(".0%", 1)} ({in_front}/{len(bound)})',
                   bool(share.n and share.low > 0.5), 'inside = Wilson lower bound > 50 %'),
        Comparison('P4 bound starts with antiparallel normals (90 <= phi <= 270 deg)', 'mostly (> 50 %)', anti,
                   f'{anti.text(".0%", 1)}', bool(anti.n and anti.low > 0.5), 'inside = Wilson lower bound > 50 %'),
    ]

    def outcomes(name: str, of_phase: float | None = None) -> list[str]:
        """The outcomes of the admissible starts of class ``name`` (of one phase, or of all)."""
        return [outcome for t, outcome in judged if classes[name](*angles(t))
                and (of_phase is None or float(t.params['phase2']) == of_phase)]

    def bound_of(name: str, of_phase: float | None) -> tuple[int, int]:
        starts = outcomes(name, of_phase)
        return starts.count('bound'), len(starts)

    def cell(k: int, n: int) -> str:
        est = wilson(k, n)
        return f'{k}/{n} ({est.low:.2f}-{est.high:.2f})' if est.n else '-'

    columns = [*(f'phase {p:g}' for p in phases), 'all phases']
    table = ['| starts | ' + ' | '.join(f'{c}: bound' for c in columns) + ' | all phases: repelled | all phases: '
             'neither |', '| --- |' + ' --- |' * (len(columns) + 2)]
    for name, _ in BASIN_CLASSES:
        starts = outcomes(name)
        cells = [cell(*bound_of(name, of_phase)) for of_phase in [*phases, None]]
        cells += [cell(starts.count(kind), len(starts)) for kind in ('repelled', 'neither')]
        table.append(f'| {name} | ' + ' | '.join(cells) + ' |')
    tests = []
    for of_phase in [*phases, None]:
        quadrants = fisher_p(bound_of('theta in quadrants 1, 4', of_phase),
                             bound_of('theta in quadrants 2, 3', of_phase))
        normals = fisher_p(bound_of('antiparallel band (90 <= phi <= 270)', of_phase),
                           bound_of('parallel band (phi < 90 or > 270)', of_phase))
        tests.append(f'{"all phases" if of_phase is None else f"phase {of_phase:g}"}: quadrants p = {quadrants:.2g}, '
                     f'normals p = {normals:.2g}')
    return [f'{len(rows)} starts, {len(adm)} admissible: {counts["bound"]} bound (in contact in each of the last '
            f'{tail} periods: the pair keeps colliding to the end), {counts["repelled"]} repelled (centres farther '
            f'apart at the end than twice the robot\'s reach: no shape can touch), {counts["neither"]} neither '
            f'(within reach, not colliding every period). By the earlier rule (r < r_bind or contact in each of '
            f'the last {tail} periods) {earlier} were bound.', '',
            'Bound, repelled and neither starts of each class out of its admissible ones (95 % Wilson interval); '
            f'{QUADRANT_RULE}:', '', *table, '',
            'Bound shares compared by Fisher\'s exact test (two-sided), quadrants 1, 4 against 2, 3 and the '
            'antiparallel band against the parallel band: ' + '; '.join(tests) + '.', '', '![basin](basin.png)', '',
            '![basin, polar](basin_polar.png)']


def section_alpha_sweep(ctx: Context) -> list[str]:
    """Fig. 6 / P5: ensemble MSD, beta, V_com and r of bound pairs against alpha_max."""
    by_alpha: dict[float, list[GliderRecord]] = defaultdict(list)
    pairs = ctx.ok_gliders('alpha_sweep')
    for t, r in pairs:
        longest = _longest(r)
        if longest is not None:
            by_alpha[float(t.params['alpha_max_deg'])].append(longest)
    alphas = sorted({float(t.params['alpha_max_deg']) for t, _ in pairs})
    rule = ctx.rule
    lines = ['| alpha_max (deg) | trials with a bound pair | of them gliders | beta (ensemble) | '
             'beta per pair, mean [95 %] | V_com (W/period) [95 %] | r (BL) [95 %] | C2 share [95 %] |',
             '| ---: | ---: | ---: | ---: | --- | --- | --- | --- |']
    fig = figure(13, 4)
    axm, axb, axv, axr = (fig.add_subplot(1, 4, k) for k in (1, 2, 3, 4))
    table: dict[str, list[tuple[float, Estimate]]] = defaultdict(list)
    total_trials: dict[float, int] = defaultdict(int)
    for t, _ in pairs:
        total_trials[float(t.params['alpha_max_deg'])] += 1
    for alpha in alphas:
        gl = by_alpha.get(alpha, [])
        lags, values = ensemble_msd([g.com_path_w for g in gl])
        beta_ens = msd_beta(lags, values)
        if lags.size:
            axm.loglog(lags, values, 'o-', ms=3, label=f'{alpha:g} deg')
        beta = bootstrap_mean([g.beta for g in gl if g.beta is not None])
        v = bootstrap_mean([g.v_com_w_per_period for g in gl if g.v_com_w_per_period is not None])
        r_est = bootstrap_mean([g.r_bl for g in gl if g.r_bl is not None])
        c2 = wilson(sum(g.glider_class == 'C2' for g in gl), len(gl))
        for name, est in (('beta', beta), ('v', v), ('r', r_est)):
            table[name].append((alpha, est))
        lines.append(f'| {alpha:g} | {len(gl)}/{total_trials[alpha]} | {gliders_among(gl, rule)} | {beta_ens:.2f} | '
                     f'{beta.text(".2f")} | '
                     f'{v.text(".3f")} | {r_est.text(".3f")} | {c2.text(".0%", 1)} |')
        target = _paper(ctx, 'beta', 1.8)
        if alpha in (90.0, 10.0):
            ctx.comparisons.append(Comparison(f'P5 beta at {alpha:g} deg', f'~{target}', beta, beta.text('.2f'),
                                              beta.contains(target), 'bootstrap over pairs'))
        if alpha < 70.0:
            ctx.comparisons.append(Comparison(f'P5 share of C2 bound pairs at {alpha:g} deg',
                                              '0 (no C2 glider below 70 deg)', c2, c2.text('.0%', 1),
                                              c2.contains(0.0) if c2.n else None,
                                              'bound pairs, travel not checked (stricter than gliders)'))
    for ax, name, label in ((axb, 'beta', 'beta'), (axv, 'v', 'V_com (W / period)'), (axr, 'r', 'r (BL)')):
        pts = table[name]
        x = [a for a, _ in pts]
        y = np.array([e.value for _, e in pts])
        err = np.array([[e.value - e.low if math.isfinite(e.low) else 0.0 for _, e in pts],
                        [e.high - e.value if math.isfinite(e.high) else 0.0 for _, e in pts]])
        ax.errorbar(x, y, yerr=err, fmt='o-', capsize=3)
        ax.set_xlabel('alpha_max (deg)')
        ax.set_ylabel(label)
    axm.set_xlabel('lag (periods)')
    axm.set_ylabel('ensemble MSD (W^2)')
    legend(axm, 6)
    ctx.save(fig, 'alpha_sweep')
    return ['Per trial: its longest bound pair (bound >= K periods, glider or not; gliders: those of them travelling '
            f'>= {rule.travel_min_w_per_100:g} W per 100 periods). beta per pair = fit of its own path (NaN when too '
            'short); ensemble beta = fit of the ensemble MSD <x^2> - <x>^2 over all pairs at that amplitude.', '',
            *lines, '', '![alpha sweep](alpha_sweep.png)']


def other_grid_values(point: Mapping[str, Any], swept: Sequence[str]) -> tuple[tuple[str, Any], ...]:
    """A trial's grid values other than the ones a section sweeps itself (``swept``), sorted by key: the
    setting a section keeps apart in its own rows."""
    return tuple(sorted((k, v) for k, v in point.items() if k not in swept))


def setting_cells(setting: tuple[tuple[str, Any], ...], keys: Sequence[str]) -> str:
    """The table cells of ``setting`` under the columns ``keys`` (empty where it has no value)."""
    values = dict(setting)
    return ''.join(f'{values.get(k, "")} | ' for k in keys)


#: ``step_convergence``: a figure counts as converged at a step if it is within this fraction of its value at
#: the finest step of the spec, or within the two values' combined 95 % half-widths.
CONVERGED_WITHIN = 0.10


def section_step_convergence(ctx: Context) -> list[str]:
    """A bound pair's mean r and travel per 100 periods against the time step, the solver iterations and the
    solver's residual threshold; the reference is the finest step with the most iterations
    and the strictest threshold.

    A grid over more than the solver (e.g. ``physics.restitution``) gives one block of rows per setting, each
    against its own finest step, and one curve per setting and solver in ``step_convergence.png``.
    """
    # a setting = (time step, solver iterations, residual threshold); sorted coarse to loose, fine to strict,
    # so the last is the reference; a variant = the trial's other grid values
    Setting = tuple[float, int, float]
    Variant = tuple[tuple[str, Any], ...]
    # MuJoCo's trials (``trial_engine``) have their own step and no Bullet solver: iterations and threshold 0
    solver_keys = ('physics.time_step', 'physics.solver_iterations', 'physics.solver_residual_threshold',
                   'mujoco.time_step')
    by_setting: dict[tuple[Variant, Setting], list[GliderRecord]] = defaultdict(list)
    trials_at: dict[tuple[Variant, Setting], int] = defaultdict(int)
    for t, r in ctx.ok_gliders('step_convergence'):
        if trial_engine(t.kind, t.params) == 'mujoco':
            setting: Setting = (MujocoSettings(**dict(t.params.get('mujoco') or {})).time_step, 0, 0.0)
        else:
            ph = config_of(t.params).physics
            threshold = ph.solver_residual_threshold
            if threshold is None:
                threshold = BULLET_SOLVER_RESIDUAL_THRESHOLD
            setting = (ph.time_step, ph.solver_iterations, threshold)
        variant = other_grid_values(t.point, solver_keys)
        key = (variant, setting)
        trials_at[key] += 1
        longest = _longest(r)
        if longest is not None:
            by_setting[key].append(longest)
    if not trials_at:
        return ['No trials yet.']
    variants = sorted({v for v, _ in trials_at}, key=str)
    columns = sorted({k for v in variants for k, _ in v})
    figures: dict[str, dict[tuple[Variant, Setting], Estimate]] = {'r': {}, 'travel': {}}
    for key in trials_at:
        gl = by_setting.get(key, [])
        figures['r'][key] = bootstrap_mean([g.r_bl for g in gl if g.r_bl is not None])
        figures['travel'][key] = bootstrap_mean([100.0 * g.v_com_w_per_period for g in gl
                                                 if g.v_com_w_per_period is not None])

    def off(name: str, key: tuple[Variant, Setting], finest: tuple[Variant, Setting]) -> tuple[str, bool | None]:
        est, ref = figures[name][key], figures[name][finest]
        if not (math.isfinite(est.value) and math.isfinite(ref.value)) or ref.value == 0.0:
            return 'n/a', None
        rel = (est.value - ref.value) / abs(ref.value)
        half = sum((e.high - e.low) / 2.0 for e in (est, ref) if math.isfinite(e.low) and math.isfinite(e.high))
        return f'{rel:+.1%}', abs(rel) <= CONVERGED_WITHIN or abs(est.value - ref.value) <= half

    lines = ['| ' + ''.join(f'{k} | ' for k in columns) + 'time step | solver iterations | residual threshold | '
             'trials with a bound pair | of them gliders | bound pair\'s mean r (BL) [95 %] | off the finest | travel '
             'per 100 periods (W) [95 %] | off the finest | converged |',
             '| ' + '---: | ' * len(columns) + '--- | ---: | ---: | ---: | ---: | --- | ---: | --- | ---: | --- |']
    fig = figure(9, 4)
    axes = [fig.add_subplot(1, 2, panel + 1) for panel in range(2)]
    for variant in variants:
        settings = sorted((s for v, s in trials_at if v == variant), key=lambda s: (-s[0], s[1], -s[2]))
        finest = (variant, settings[-1])
        for setting in settings:
            key = (variant, setting)
            r_off, r_ok = off('r', key, finest)
            v_off, v_ok = off('travel', key, finest)
            both = None if r_ok is None or v_ok is None else (r_ok and v_ok)
            lines.append('| ' + setting_cells(variant, columns)
                         + f'1/{1.0 / setting[0]:.0f} s | {setting[1] or "- (MuJoCo)"} | '
                         f'{f"{setting[2]:.0e}" if setting[1] else "-"} | '
                         f'{len(by_setting.get(key, []))}/{trials_at[key]} | '
                         f'{gliders_among(by_setting.get(key, []), ctx.rule)} | {figures["r"][key].text(".3f")} | '
                         f'{r_off} | {figures["travel"][key].text(".2f")} | {v_off} | '
                         f'{_yes_no(both) if key != finest else "(reference)"} |')
        prefix = ', '.join(f'{k} {v}' for k, v in variant)
        for ax, name in zip(axes, ('r', 'travel'), strict=True):
            for solver in sorted({s[1:] for s in settings}, key=lambda v: (v[0], -v[1])):
                same = [s for s in settings if s[1:] == solver]
                ests = [figures[name][(variant, s)] for s in same]
                err = np.array([[e.value - e.low if math.isfinite(e.low) else 0.0 for e in ests],
                                [e.high - e.value if math.isfinite(e.high) else 0.0 for e in ests]])
                residual = '' if solver[1] in (BULLET_SOLVER_RESIDUAL_THRESHOLD, 0.0) else f', residual {solver[1]:.0e}'
                label = f'{solver[0]} solver iterations{residual}' if solver[0] else 'MuJoCo'
                ax.errorbar([1.0 / s[0] for s in same], [e.value for e in ests], yerr=err, fmt='o-', capsize=3,
                            label=f'{prefix}: {label}' if prefix else label)
    for ax, label in zip(axes, ('bound pair\'s mean r (BL)', 'travel per 100 periods (W)'), strict=True):
        legend(ax, 7)
        ax.set_xscale('log', base=2)
        ax.set_xlabel('physics rate (1 / time step, Hz)')
        ax.set_ylabel(label)
    ctx.save(fig, 'step_convergence')
    return [f'Per trial: its longest bound pair (bound >= K periods, glider or not; mean r over its periods; travel '
            f'= its V_com x 100 periods; gliders: those travelling >= {ctx.rule.travel_min_w_per_100:g} W net per 100 '
            'periods of their run). The '
            f'reference is the finest step (with the most solver iterations and the strictest residual threshold '
            f'there){" of each setting" if columns else ""}; converged = within {CONVERGED_WITHIN:.0%} of it or '
            f'within the two values\' combined 95 % half-widths, for both figures. Residual threshold: Bullet\'s '
            f'solverResidualThreshold ({BULLET_SOLVER_RESIDUAL_THRESHOLD:.0e} is its own default).', '', *lines, '',
            '![step convergence](step_convergence.png)']


def section_p6(ctx: Context) -> list[str]:
    """Fig. 5d / P6: C2 pairs' lifetimes open loop against feedback (Kaplan-Meier, censored at the trial's end).

    A lifetime is the pair's bound run from period 0 (K = 1), a bound pair or a glider or neither; with the kind's
    ``details`` the pair's travel is stored and the gliders are counted (``p6_details_lines``), else it says so.
    A grid over more than amplitude and feedback (e.g. ``noise.clock_rate_sd``) gives one row per setting and
    condition; open loop and feedback are compared (log-rank) within a setting.
    """
    Key = tuple[tuple[tuple[str, Any], ...], float, bool]
    groups: dict[Key, list[P6Result]] = defaultdict(list)
    for t, r in ctx.ok_as('p6', P6Result):
        setting = other_grid_values(t.point, ('alpha_max_deg', 'feedback'))
        groups[(setting, float(t.params['alpha_max_deg']), bool(t.params['feedback']))].append(r)
    keys = sorted({k for setting, _, _ in groups for k, _ in setting})
    lines = ['| ' + ''.join(f'{k} | ' for k in keys) + 'condition | trials | reached the end | KM median lifetime '
             '(periods) [95 %] | mean lifetime +- SE | mean halts |',
             '| ' + '---: | ' * len(keys) + '--- | ---: | ---: | --- | ---: | ---: |']
    fig = figure(11, 4.5)
    ax1, ax2 = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    medians: dict[Key, Estimate] = {}
    order = sorted(groups.items(), key=lambda kv: (str(kv[0][0]), kv[0][1], kv[0][2]))
    labels = []
    for x, (cond, rows) in enumerate(order):
        setting, alpha, feedback = cond
        label = f'{"feedback" if feedback else "open loop"} {alpha:g} deg'
        short = f'{"fb" if feedback else "ol"} {alpha:g}' + ''.join(f' {v:g}' if isinstance(v, float) else f' {v}'
                                                                     for _, v in setting)
        labels.append(short)
        km = kaplan_meier([r.lifetime_periods for r in rows], [r.censored for r in rows])
        medians[cond] = km.median
        life = np.array([r.lifetime_periods for r in rows], dtype=float)
        se = life.std(ddof=1) / np.sqrt(life.size) if life.size > 1 else float('nan')
        lines.append('| ' + setting_cells(setting, keys)
                     + f'{label} | {len(rows)} | {km.censored} | {km.median.text(".0f")} | {life.mean():.1f} +- '
                     f'{se:.1f} | {np.mean([r.halts for r in rows]):.1f} |')
        ax1.scatter(x + np.linspace(-0.15, 0.15, life.size), life, s=12)
        ax2.step(np.r_[0, km.times], np.r_[1, km.survival], where='post', label=short if setting else label)
    lines += p6_details_lines(order, float(ctx.spec.base.get('periods', 0.0)))
    ax1.set_xticks(range(len(order)), labels, fontsize=7, rotation=20)
    ax1.set_ylabel('C2 pair\'s bound run (periods)')
    ax2.set_xlabel('lifetime (periods)')
    ax2.set_ylabel('survival (Kaplan-Meier)')
    legend(ax2, 7)
    ctx.save(fig, 'p6_lifetimes')
    for (setting, alpha, feedback), rows in order:
        plain = groups.get((setting, alpha, False))
        if feedback and plain:
            where = ''.join(f', {k} {v}' for k, v in setting)
            if all(r.censored for r in (*plain, *rows)):
                lines.append(f'\nOpen loop against feedback at {alpha:g} deg{where}: every pair reached the end, no '
                             'test.')
                continue
            stat, p = logrank(*(([r.lifetime_periods for r in g], [r.censored for r in g]) for g in (plain, rows)))
            ratio = (np.mean([r.lifetime_periods for r in rows])
                     / max(float(np.mean([r.lifetime_periods for r in plain])), 1e-9))
            lines.append(f'\nLog-rank (censored lifetimes), open loop against feedback at {alpha:g} deg{where}: '
                         f'statistic {stat:.3f}, p = {p:.3g}; mean lifetime ratio feedback / open loop {ratio:.2f}.')
    fb = [m for (_, _, f), m in medians.items() if f]
    ol = [m for (_, _, f), m in medians.items() if not f]
    if fb and ol:
        best_ol = max(ol, key=lambda m: m.high)
        longer = all(m.low > best_ol.high for m in fb)
        ctx.comparisons.append(Comparison('P6 feedback C2 pairs stay bound longer than open loop',
                                          'much longer (C2 gliders)', None,
                                          f'feedback median(s) {", ".join(m.text(".0f") for m in fb)} vs best '
                                          f'open loop {best_ol.text(".0f")}', longer,
                                          'inside = every feedback median interval above the open-loop ones; bound '
                                          'runs from the start, glider or not'))
    rows = [r for _, rs in order for r in rs]
    words = ('Lifetime: the C2 pair\'s bound run from period 0 (bound = r under the bind distance in a period, K = 1), '
             'glider or not.')
    if rows and any(r.travel_w is None for r in rows):
        words += (' Travel is not stored for these trials (run without `details`), so the gliders among the pairs '
                  'are not counted.')
    return [words, '', *lines, '', '![P6 lifetimes](p6_lifetimes.png)']


def _mean_se(values: Sequence[float]) -> str:
    """``mean +- SE`` of some values (SE nan below two)."""
    v = np.asarray(values, dtype=float)
    se = v.std(ddof=1) / math.sqrt(v.size) if v.size > 1 else math.nan
    return f'{v.mean():.2f} +- {se:.2f}'


def p6_details_lines(order: Sequence[tuple[Any, list[P6Result]]], periods: float) -> list[str]:
    """With the p6 kind's ``details``: each condition's travel while bound (W), the gliders among its pairs (bound
    >= K periods and travelling the glider rate, ``smarticle_tracking.gliders.pair_kind``) and its periods with
    contact."""
    rows = list(order)
    if not rows or any(r.travel_w is None or r.contact_periods is None for _, rs in rows for r in rs):
        return []
    rule = GliderConfig(body_length=1.0, width=1.0)      # travel_w is stored in W
    out = ['', f'| condition | setting | travel while bound (W), mean +- SE | gliders (bound >= {rule.min_periods} '
           f'periods, >= {rule.travel_min_w_per_100:g} W per 100 periods) | periods with contact, mean +- SE | '
           'in the second half | final r (BL), median |', '| --- | --- | ---: | ---: | ---: | ---: | ---: |']
    for (setting, alpha, feedback), rs in rows:
        moving = sum(pair_kind(r.lifetime_periods, _num(r.travel_w), rule) is PairKind.GLIDER for r in rs)
        out.append(f'| {"feedback" if feedback else "open loop"} {alpha:g} deg | {dict(setting) or "-"} | '
                   f'{_mean_se([r.travel_w or 0.0 for r in rs])} | {moving} of {len(rs)} | '
                   f'{_mean_se([len(r.contact_periods or []) for r in rs])} | '
                   f'{_mean_se([sum(q >= periods / 2 for q in r.contact_periods or []) for r in rs])} | '
                   f'{np.median([r.final_r_bl if r.final_r_bl is not None else math.nan for r in rs]):.2f} |')
    return out


def section_drift(ctx: Context) -> list[str]:
    """P7: single-robot drift per cycle (um), bootstrap over seeds, per amplitude and per other grid setting.

    A grid over more than the amplitude (e.g. ``physics.tilt_inertia_scale``) gives one row per setting and
    amplitude and one curve per setting in ``drift.png`` (drift against amplitude, 95 % bars).
    """
    groups: dict[tuple[tuple[str, Any], ...], dict[float, list[float]]] = defaultdict(lambda: defaultdict(list))
    for t, r in ctx.ok_as('drift', SingleResult):
        setting = other_grid_values(t.point, ('alpha_max_deg',))
        groups[setting][float(t.params['alpha_max_deg'])].append(r.drift_um_per_cycle)
    target = _paper(ctx, 'drift_um', 75.0)
    keys = sorted({k for setting in groups for k, _ in setting})
    lines = ['| ' + ''.join(f'{k} | ' for k in keys) + 'alpha_max (deg) | robots | drift (um / cycle) [95 %] |',
             '| ' + '---: | ' * len(keys) + '---: | ---: | --- |']
    curves = []
    for setting, by_alpha in sorted(groups.items(), key=lambda kv: str(kv[0])):
        label = ', '.join(f'{k} {v}' for k, v in setting) or 'drift'
        curve = []
        for alpha, values in sorted(by_alpha.items()):
            est = bootstrap_mean(values)
            curve.append((alpha, est))
            lines.append('| ' + setting_cells(setting, keys)
                         + f'{alpha:g} | {len(values)} | {est.text(".1f")} |')
            if alpha == 90.0:
                name = 'P7 drift per cycle at 90 deg (um)' + (f' ({label})' if setting else '')
                ctx.comparisons.append(Comparison(name, f'~{target:g}', est, est.text('.1f'), est.contains(target),
                                                  'bootstrap over seeds'))
        curves.append((label, curve))
    if any(len(curve) > 1 for _, curve in curves):
        fig = figure(6, 4)
        ax = fig.add_subplot(1, 1, 1)
        for label, curve in curves:
            alphas = [a for a, _ in curve]
            means = np.array([e.value for _, e in curve])
            lo = means - np.array([e.low for _, e in curve])
            hi = np.array([e.high for _, e in curve]) - means
            ax.errorbar(alphas, means, yerr=[lo, hi], fmt='o-', capsize=3, label=label)
        ax.axhline(target, color='grey', ls=':', lw=1, label=f'paper ~{target:g} um at 90 deg')
        ax.set_xlabel('alpha_max (deg)')
        ax.set_ylabel('drift per cycle (um), 95 % interval')
        legend(ax)
        ctx.save(fig, 'drift')
    return lines


def section_accuracy(ctx: Context) -> list[str]:
    """Run time against error: each setting against the sweep's finest (highest rate, most iterations)."""
    rows = ctx.ok_as('accuracy', AccuracyResult)
    if not rows:
        return ['No finished settings.']
    ref_t, ref = max(rows, key=lambda x: (float(x[0].params['rate_hz']), int(x[0].params['solver_iterations'])))
    out = ['| rate (Hz) | iterations | seed | wall s / sim s | pos err 10 T (BL) | r err (BL) | drift err |',
           '| ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
    pts = []
    for t, r in rows:
        pos = math.nan
        if r.xy10_bl and ref.xy10_bl and t.seed == ref_t.seed:
            pos = float(np.linalg.norm(np.array(r.xy10_bl) - np.array(ref.xy10_bl), axis=1).mean())
        r_err = abs(r.r_mean_bl - ref.r_mean_bl)
        d_err = abs(r.drift_um_per_cycle - ref.drift_um_per_cycle) / ref.drift_um_per_cycle \
            if ref.drift_um_per_cycle else math.nan
        out.append(f'| {t.params["rate_hz"]:g} | {t.params["solver_iterations"]} | {t.seed} | '
                   f'{r.wall_per_sim_s:.4f} | {pos:.4f} | {r_err:.4f} | {d_err:.1%} |')
        pts.append((int(t.params['solver_iterations']), r.wall_per_sim_s, pos))
    fig = figure(6, 4)
    ax = fig.add_subplot(1, 1, 1)
    for it in sorted({p[0] for p in pts}):
        sel = sorted((w, e) for i, w, e in pts if i == it and math.isfinite(e) and e > 0)
        if sel:
            ax.loglog([w for w, _ in sel], [e for _, e in sel], 'o-', label=f'{it} iterations')
    ax.set_xlabel('wall s per simulated s')
    ax.set_ylabel('position error after 10 periods (BL)')
    legend(ax)
    ctx.save(fig, 'accuracy')
    return [f'Reference: {ref_t.params["rate_hz"]:g} Hz, {ref_t.params["solver_iterations"]} iterations.', '',
            *out, '', '![accuracy](accuracy.png)']


#: A bound pair "touches" if its robots touched in at least this share of its bound periods (fixed before the
#: first run that watched contacts, the spec p1_contacts).
TOUCHING_SHARE = 0.5


def section_contacts(ctx: Context) -> list[str]:
    """How often bound pairs touch (dense trials with ``contacts: true``): per class, and P1 with touching pairs."""
    pairs = ctx.ok_as('contacts', DenseResult)
    rule = ctx.rule
    gl = [g for g in _bound_pairs(pairs) if g.contact_fraction is not None]
    if not gl:
        return ['No bound pair carries a contact share: run the spec with `params: {contacts: true}`.']
    limit = ctx.spec.base.get('positive_periods', 100)
    lines = [f'A bound pair touches if its two robots touched (any physics step) in >= {TOUCHING_SHARE:.0%} of its '
             f'bound periods; {pairs_count(gl, rule)}.', '',
             '| bound pairs | n | of them gliders | touching [95 %] | median share of periods with contact | '
             'share 0 (never touched) |',
             '| --- | ---: | ---: | --- | ---: | ---: |']
    fig = figure(6, 4)
    ax = fig.add_subplot(1, 1, 1)
    for cls, colour in (('all', None), ('C1', 'tab:red'), ('C2', 'tab:blue'), ('unclassified', 'tab:gray')):
        sel = gl if cls == 'all' else [g for g in gl if g.glider_class == cls]
        if not sel:
            continue
        share = np.array([g.contact_fraction for g in sel])
        touching = wilson(int((share >= TOUCHING_SHARE).sum()), len(sel))
        lines.append(f'| {cls} | {len(sel)} | {gliders_among(sel, rule)} | {touching.text(".0%", 1)} | '
                     f'{np.median(share):.2f} | {(share == 0).mean():.0%} |')
        if colour is not None:
            ax.hist(share, bins=np.linspace(0, 1, 21), alpha=0.6, color=colour, label=cls)
    ax.set_xlabel('share of the pair\'s bound periods with contact')
    ax.set_ylabel('bound pairs')
    legend(ax, 7)
    ctx.save(fig, 'contacts')
    n = len(pairs)
    positive = sum(any(g.lifetime_periods >= limit for g in r.gliders) for _, r in pairs)
    touching_pos = sum(any(g.lifetime_periods >= limit and (g.contact_fraction or 0.0) >= TOUCHING_SHARE
                           for g in r.gliders) for _, r in pairs)
    iso_touching = sum(any(g.lifetime_periods >= limit and g.isolated
                           and (g.contact_fraction or 0.0) >= TOUCHING_SHARE for g in r.gliders)
                       for _, r in pairs)
    lines += ['', f'| trials ({n}) with a pair bound >= {limit} periods | count [95 %] |', '| --- | --- |',
              f'| any | {wilson(positive, n).text(".1%", 1)} ({positive}) |',
              f'| touching | {wilson(touching_pos, n).text(".1%", 1)} ({touching_pos}) |',
              f'| touching and isolated | {wilson(iso_touching, n).text(".1%", 1)} ({iso_touching}) |',
              '', '![contacts](contacts.png)']
    return lines


def section_pair_paths(ctx: Context) -> list[str]:
    """The path of each pair's centre (one sample per period), one panel per grid setting, and a table of
    how far the pairs went and how they ended: does a setting make pairs glide, and which way?"""
    by_setting: dict[tuple[tuple[str, Any], ...], list[tuple[Trial, DenseResult]]] = defaultdict(list)
    for t, r in ctx.ok_gliders('pair_paths'):
        if isinstance(r, DenseResult) and r.trajectory_bl:
            by_setting[other_grid_values(t.point, ())].append((t, r))
    if not by_setting:
        return ['No trajectory recorded (the spec needs `trajectory: true`).']
    settings = sorted(by_setting, key=str)
    keys = sorted({k for setting in settings for k, _ in setting})
    cols = min(4, len(settings))
    rows = math.ceil(len(settings) / cols)
    fig = figure(3.0 * cols, 3.3 * rows)
    axes = []
    lines = ['Each pair\'s centre (the mean of its two robots\' centres), one sample per period; net travel over the '
             'run and the pair at its end (r, phi).', '',
             '| ' + ' | '.join(keys) + ' | pairs | net travel of the centre (W): mean [95 %] | per pair | '
             'r at the end (BL) | phi at the end (deg) |',
             '| ' + ' | '.join('---:' for _ in keys) + ' | ---: | --- | --- | --- | --- |']
    for n, setting in enumerate(settings):
        ax = fig.add_subplot(rows, cols, n + 1)
        travels = []
        trials = sorted(by_setting[setting], key=lambda tr: tr[0].seed)
        for t, r in trials:
            xy = np.array([[[math.nan if v is None else v for v in q] for q in row] for row in r.trajectory_bl])
            centre = np.nanmean(xy[:, :2, :], axis=1) - np.nanmean(xy[0, :2, :], axis=0)
            travels.append(float(np.hypot(*centre[-1])) if len(centre) else math.nan)
            ax.plot(centre[:, 0], centre[:, 1], lw=0.9, label=f'seed {t.seed}')
            ax.plot(centre[-1, 0], centre[-1, 1], 'o', ms=3, color=ax.lines[-1].get_color())
        axes.append(ax)
        title = [f'{k.rsplit(".", 1)[-1]} {format(v, ".4g") if isinstance(v, float) else v}' for k, v in setting]
        ax.set_title(', '.join(title) or 'all trials', fontsize=6)
        ax.set_xlabel('x (BL)', fontsize=7)
        ax.set_ylabel('y (BL)', fontsize=7)
        ax.tick_params(labelsize=6)
        est = bootstrap_mean(travels)
        ends = [r for _, r in trials]
        r_end = ', '.join(f'{e.r_end_bl:.2f}' for e in ends if isinstance(e, PairResult))
        phi_end = ', '.join(f'{e.phi_end_deg:.1f}' for e in ends if isinstance(e, PairResult))
        lines.append(f'| {setting_cells(setting, keys)}{len(travels)} | {est.text(".2f")} | '
                     f'{", ".join(f"{v:.2f}" for v in travels)} | {r_end} | {phi_end} |')
    reach = max(max(abs(v) for ax in axes for line in ax.lines for v in (*line.get_xdata(), *line.get_ydata())
                        if math.isfinite(v)), 0.05) * 1.1
    for ax in axes:   # one scale for every panel: a still pair is a dot beside a glider's path
        ax.set_xlim(-reach, reach)
        ax.set_ylim(-reach, reach)
        ax.set_aspect('equal')
    fig.tight_layout()
    ctx.save(fig, 'pair_paths')
    return [*lines, '', '![pair paths](pair_paths.png)']


SECTIONS: dict[str, Callable[[Context], list[str]]] = {
    'p1': section_p1, 'trajectories': section_trajectories, 'configurations': section_configurations,
    'lifetimes': section_lifetimes, 'basin': section_basin, 'alpha_sweep': section_alpha_sweep,
    'p6': section_p6, 'drift': section_drift, 'accuracy': section_accuracy, 'contacts': section_contacts,
    'step_convergence': section_step_convergence, 'pair_paths': section_pair_paths,
}


#: The sections that count the bound pairs of the glider analysis (the report states the words once at its top).
PAIR_SECTIONS = frozenset({'p1', 'trajectories', 'configurations', 'lifetimes', 'alpha_sweep', 'contacts',
                           'step_convergence'})


def section_writer(kind: str, name: str) -> Callable[[Context], list[str]]:
    """The writer of the report section ``name``: the report's own (``SECTIONS``), else the one the kind draws."""
    if name in SECTIONS:
        return SECTIONS[name]
    return KINDS[kind].writers[name]


def _yes_no(value: bool | None) -> str:
    """The 'inside' cell."""
    return 'n/a' if value is None else ('yes' if value else 'no')


def trouble_lines(ctx: Context) -> list[str]:
    """Counts and lists of trials that are missing, failed or ended in trouble."""
    missing = [t for t in ctx.trials if t.key not in ctx.records]
    failed = [(t, ctx.records[t.key]) for t in ctx.trials
              if t.key in ctx.records and ctx.records[t.key].get('status') != 'ok']
    trouble = [(t, ctx.records[t.key]) for t in ctx.trials if t.key in ctx.records
               and ctx.records[t.key].get('status') == 'ok' and (ctx.records[t.key].get('result') or {}).get('trouble')]
    lines = ['## Trials not in the statistics', '',
             f'{len(ctx.trials)} trials in the spec: {len(ctx.ok())} used, {len(trouble)} ended in sim trouble, '
             f'{len(failed)} failed, {len(missing)} not run yet.', '', *margin_lines(ctx)]
    if trouble or failed:
        lines += ['| key | seed | grid point | what |', '| --- | ---: | --- | --- |']
        for t, rec in trouble:
            lines.append(f'| {t.key} | {t.seed} | {dict(t.point)} | trouble: {rec["result"]["trouble"][:160]} |')
        for t, rec in failed:
            lines.append(f'| {t.key} | {t.seed} | {dict(t.point)} | failed ({rec.get("error_kind")}): '
                         f'{str(rec.get("error", ""))[:160]} |')
    return lines


def margin_lines(ctx: Context) -> list[str]:
    """How close the trials that ran came to the trouble limits: the largest body tilt and the deepest contact
    overlap seen at their trouble checks (trial results that carry them), or nothing."""
    results = [(t, r) for t in ctx.trials if t.key in ctx.records and ctx.records[t.key].get('status') == 'ok'
               for r in [read_result(t.kind, ctx.records[t.key].get('result') or {})] if isinstance(r, DenseResult)]
    tilts = [(r.peak_tilt_deg, t.seed) for t, r in results if r.peak_tilt_deg is not None]
    overlaps = [(r.peak_overlap_mm, t.seed) for t, r in results if r.peak_overlap_mm is not None]
    if not tilts or not overlaps:
        return []
    ph = config_of(results[0][0].params).physics
    tilt, tilt_seed = max(tilts)
    overlap, overlap_seed = max(overlaps)
    median_tilt = float(np.median([v for v, _ in tilts]))
    return [f'Trouble margins over {len(tilts)} trials that ran (at their trouble checks): largest body tilt '
            f'{tilt:.1f} deg (seed {tilt_seed}; median of the trials\' largest {median_tilt:.1f} deg; the limit '
            f'is {math.degrees(ph.max_tilt):g} deg), deepest contact overlap {overlap:.2f} mm (seed {overlap_seed}; '
            f'trouble is {ph.max_penetration * 1000:g} mm at {ph.penetration_checks} checks in a row).', '']


def code_line(code: Mapping[str, str]) -> str:
    """The report's line on code: the source tree now (HEAD) and, apart, the code version of its trials (the
    hash of the trial code's source, which is in their keys, and the library versions)."""
    from .store import head_commit

    libraries = ', '.join(f'{name} {version}' for name, version in code.items() if name != 'source')
    return (f'Code: the source tree now is at HEAD {head_commit()}; the trials\' code version (in their store keys) is '
            f'the trial code\'s source hash {code.get("source", "unknown")}, {libraries}.')


def write_report(spec: ExperimentSpec, trials: list[Trial], store: ResultStore, code: Mapping[str, str]) -> Path:
    """Write ``report.md`` and the PNG figures of ``spec`` into ``<store>/report-<name>/``; return the .md path."""
    folder = store.folder / f'report-{spec.name}'
    folder.mkdir(parents=True, exist_ok=True)
    records = {r['key']: r for r in store.records(t.key for t in trials)}
    ctx = Context(spec, trials, records, folder)
    body: list[str] = []
    for name in spec.report:
        body += [f'## {name}', '', *section_writer(spec.kind, name)(ctx), '']
    ok = ctx.ok()
    words = [words_line(ctx.rule), ''] if set(spec.report) & PAIR_SECTIONS else []
    head = [f'# {spec.name}: {spec.description}', '',
            f'Spec `{spec.source or spec.name}`, kind `{spec.kind}`, {len(trials)} trials '
            f'({len(spec.points())} grid points x {len(spec.seeds)} seeds), {spec.base.get("periods", "?")} periods.',
            '', code_line(code), '', *words,
            '## Paper against sim', '',
            '| quantity | paper | sim [95 % interval] | interval | n trials / values | seeds | paper inside | note |',
            '| --- | --- | --- | --- | ---: | --- | --- | --- |']
    for c in ctx.comparisons:
        method = c.sim.method if c.sim is not None else '-'
        n_values = f' / {c.sim.n}' if c.sim is not None else ''
        head.append(f'| {c.quantity} | {c.paper} | {c.sim_text} | {method} | {len(ok)}{n_values} | '
                    f'{ctx.seeds_text(ok)} | '
                    f'{_yes_no(c.inside)} | {c.note} |')
    text = '\n'.join([*head, '', *body, *trouble_lines(ctx), ''])
    path = folder / 'report.md'
    write_atomic(path, text)
    return path


def _identity(kind: str, params: Mapping[str, Any], seed: int) -> str:
    """A trial's identity without the code version: kind, parameters (as the store writes them) and seed."""
    return canonical({'kind': kind, 'params': json_ready(params), 'seed': int(seed)})


def stored_records(spec: ExperimentSpec, trials: Sequence[Trial], store: ResultStore) -> dict[str, dict[str, Any]]:
    """The newest stored record of each of ``trials`` under the trial's key, whatever code version ran it
    (the status of a claim is the last run of its spec)."""
    newest: dict[str, dict[str, Any]] = {}
    for record in store.records():
        ident = _identity(str(record.get('kind')), record.get('params') or {}, int(record.get('seed', -1)))
        if ident not in newest or float(record.get('end_unix') or 0) >= float(newest[ident].get('end_unix') or 0):
            newest[ident] = record
    out = {}
    for t in trials:
        found = newest.get(_identity(t.kind, t.params, t.seed))
        if found is not None:
            out[t.key] = found
    return out


def status_table(root: Path) -> str:
    """The status of the paper's claims as Markdown, one line per claim: every current spec tagged ``paper``,
    its sections' paper-against-sim rows computed from the newest stored trials under ``root``, and the
    spec's report. A spec with no stored trial gets one 'not run' line."""
    import tempfile
    import warnings

    from smarticle_sim.settings import NotConvergedWarning

    from .spec import builtin_names, load_spec

    lines = ['| experiment | claim | paper | sim [95 % interval] | paper inside | trials used | report |',
             '| --- | --- | --- | --- | --- | ---: | --- |']
    for name in builtin_names():
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', NotConvergedWarning)
            spec = load_spec(name)
        if spec.status != 'current' or 'paper' not in spec.tags:
            continue
        store = ResultStore(root / spec.store)
        trials = spec.trials(spec.code())
        records = stored_records(spec, trials, store)
        link = f'[report-{spec.name}]({store.folder / f"report-{spec.name}" / "report.md"})'
        if not records:
            lines.append(f'| {spec.name} | {spec.description} | - | not run | n/a | 0 | `smarticle-experiments run '
                         f'{spec.name}` |')
            continue
        with tempfile.TemporaryDirectory() as tmp:
            ctx = Context(spec, trials, records, Path(tmp))
            for section in spec.report:
                SECTIONS[section](ctx)
        used = len(ctx.ok())
        if not ctx.comparisons:
            lines.append(f'| {spec.name} | {spec.description} | - | see report | n/a | {used} of {len(trials)} | '
                         f'{link} |')
        for c in ctx.comparisons:
            lines.append(f'| {spec.name} | {c.quantity} | {c.paper} | {c.sim_text} | {_yes_no(c.inside)} | '
                         f'{used} of {len(trials)} | {link} |')
    return '\n'.join(lines)
