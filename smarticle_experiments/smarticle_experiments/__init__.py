"""The paper's experiments at scale: specs as data, a Dask engine, a resumable store, statistics, reports."""

from __future__ import annotations

__version__ = '0.1.0'

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'ExperimentSpec': 'spec', 'load_spec': 'spec', 'spec_from_mapping': 'spec',
    'ResultStore': 'store',
    'KINDS': 'trials', 'run_kind': 'trials',
    'TrialResult': 'results', 'SingleResult': 'results', 'P6Result': 'results', 'C2HarvestResult': 'results',
    'DenseResult': 'results', 'PairResult': 'results', 'InadmissiblePairResult': 'results',
    'main': 'cli',
    'ExperimentError': 'errors', 'SpecError': 'errors', 'SchedulerError': 'errors', 'StoreError': 'errors',
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    """A public name of ``__all__``, imported from its module on first use (importing the package stays cheap)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    import importlib

    return getattr(importlib.import_module(f'.{module}', __name__), name)
