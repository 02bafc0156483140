"""The paper's experiments at scale: specs as data, a Dask engine, a resumable store, statistics, reports."""

from __future__ import annotations

from smarticle_common.exports import lazy_getattr

__version__ = '0.1.0'

#: Public name -> the module that defines it.
_EXPORTS: dict[str, str] = {
    'ExperimentSpec': 'spec', 'load_spec': 'spec', 'spec_from_mapping': 'spec',
    'ResultStore': 'store',
    'KINDS': 'kinds', 'run_kind': 'kinds', 'TrialKind': 'kind', 'KindParams': 'kind',
    'TrialResult': 'results', 'SingleResult': 'results', 'P6Result': 'results', 'C2HarvestResult': 'results',
    'DenseResult': 'results', 'PairResult': 'results', 'InadmissiblePairResult': 'results',
    'GliderRecord': 'results', 'AccuracyResult': 'results', 'read_result': 'kinds',
    'main': 'cli',
    'ExperimentError': 'errors', 'SpecError': 'errors', 'SchedulerError': 'errors', 'StoreError': 'errors',
    'ResultError': 'errors',
}
__all__ = sorted(_EXPORTS)

__getattr__ = lazy_getattr(__name__, _EXPORTS)
