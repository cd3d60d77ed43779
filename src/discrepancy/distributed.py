"""Fitting a model on many files with Dask, as users call it (the machinery, which knows no
model, is :mod:`discrepancy.fitting.distributed`; ``model.fit(dask_array)`` uses it too)."""
from __future__ import annotations

from .fitting.distributed import source_statistics

__all__ = ["fit_sources"]


def fit_sources(model, sources, *, t=None):
    """Fit ``model`` on a list of :class:`~discrepancy.data.chunks.ChunkSource` (e.g. one
    :class:`~discrepancy.data.sources.HDF5Source` per file), one ``dask.delayed`` task
    each, summed as a tree. ``t``: the time step of sources without times. Returns the
    model."""
    setup, stats = source_statistics(model.make_setup, model.differentiation_method, sources,
                                     t=t)
    return model.fit_statistics(stats, setup)
