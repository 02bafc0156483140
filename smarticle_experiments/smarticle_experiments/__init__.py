"""The paper's experiments at scale: specs as data, a Dask engine, a resumable store, statistics, reports."""

__version__ = '0.1.0'
