"""A trial kind defined outside the package, in one file: its typed parameters, run, result and report section,
registered on import (``test_toy_kind.py`` runs it through the engine, the store and the report)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from smarticle_experiments.kind import KINDS, KindParams
from smarticle_experiments.results import TrialResult


@dataclass(frozen=True)
class ToyParams(KindParams):
    """A number to scale the seed by and a run length."""

    scale: float = 2.0
    periods: float = 1.0

    def check(self) -> None:
        """``scale`` > 0."""
        if not self.scale > 0:
            raise ValueError(f'scale must be > 0, got {self.scale!r}')


@dataclass(frozen=True)
class ToyResult(TrialResult):
    """What a toy trial measured."""

    value: float                    # scale * seed + periods
    trouble: str


def toy_section(ctx: Any) -> list[str]:
    """The toy kind's own report section: the mean value of its trials."""
    rows = ctx.ok_as('toy', ToyResult)
    mean = sum(r.value for _, r in rows) / max(len(rows), 1)
    return [f'{len(rows)} toy trials, mean value {mean:.2f}']


@KINDS.register('toy', ToyParams, 'a toy kind registered from the tests', result=ToyResult,
                writers={'toy': toy_section})
def toy_trial(p: ToyParams, seed: int) -> ToyResult:
    """scale * seed + periods."""
    return ToyResult(value=p.scale * seed + p.periods, trouble='')


#: The registered kind (a test that forgot it registers it again with ``KINDS.add(TOY)``).
TOY = KINDS['toy']
