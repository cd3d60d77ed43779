"""Fields on Dask: one task per time block, the p×p sums reduced as a tree.

``model.fit(u, t=dt, grid=grid)`` with ``u`` a ``dask.array`` ``(m, *grid.shape[, n])``
chunked along time (the grid axes are made whole), or a list of them (runs), maps every
block, with ``halo`` snapshots of its neighbours (``map_overlap``), to the packed Gram
statistics of its own snapshots and sums them (``sum(split_every=...)``), so only p×p
numbers come back. Which scheduler runs it is Dask's choice: threads, or a
``distributed`` cluster when a ``Client`` is active; zarr arrays opened with
``dask.array.from_zarr`` are read by the workers themselves. The statistics, and the
model, equal the in-memory fit's (to rounding).
"""
from __future__ import annotations

import numpy as np

from .._optional import require
from ..data.fields import FieldRun, field_array
from ..data.validation import check_times
from ..errors import ParameterError, ShapeError, describe
from .resolve import SAMPLE_SNAPSHOTS

SPLIT_EVERY = 8


def _block(rows, u, *, setup, step, halo, n_total, offset):
    """Packed statistics ``(1, L)`` of one time block (``rows``: its snapshot numbers)."""
    rows = rows.ravel().astype(int)
    where = f"dask array snapshots {rows[0]}..{rows[-1]}"
    u = field_array("u", u, setup.grid, n_fields=setup.n_fields, where=where,
                    row_offset=int(rows[0]))
    lo = 0 if rows[0] == 0 else halo
    hi = len(rows) if rows[-1] == n_total - 1 else len(rows) - halo
    stats = setup.new_statistics()
    stats.count = offset + int(rows[lo]) * setup.rows_per_snapshot  # fold position
    setup.statistics(FieldRun(rows * step, u, None, setup.grid), into=stats,
                     keep=slice(lo, hi))
    stats.count -= offset + int(rows[lo]) * setup.rows_per_snapshot
    return stats.to_vector()[None, :]


def dask_statistics(model, u, *, t, grid, progress=None):
    """``(setup, stats)`` of a dask array of fields, or a list of them (one per run; see
    the module docstring)."""
    da = require("dask.array", purpose="fitting dask arrays")
    runs = list(u) if isinstance(u, (list, tuple)) else [u]
    if np.ndim(t) != 0 and t is not None:
        raise ParameterError("with dask arrays of fields, t must be the time step")
    step = float(check_times("t", 1.0 if t is None else t, 2)[1])
    runs = [_checked(k, a, grid, da) for k, a in enumerate(runs)]
    if len({a.shape[-1] for a in runs}) != 1:
        raise ShapeError("every run must hold the same number of fields")
    sample, budget = [], SAMPLE_SNAPSHOTS
    for a in runs:
        if budget <= 0:
            break
        part = np.asarray(a[:min(a.shape[0], budget)], dtype=float)
        sample.append(FieldRun(np.arange(len(part)) * step, field_array("u", part, grid),
                               None, grid))
        budget -= len(part)
    setup = model.make_setup(runs[0].shape[-1], 0, grid, sample=sample,
                             lengths=[a.shape[0] for a in runs])
    if setup.halo is None:
        raise ParameterError("Dask fits need a local time method (the weak form, "
                             "SavitzkyGolay, FiniteDifference)")
    graphs, offset = [], 0
    for a in runs:
        graphs.append(_run_graph(setup, a, step, offset, da))
        offset += a.shape[0] * setup.rows_per_snapshot
    total = _compute(sum(graphs[1:], graphs[0]), progress)
    return setup, setup.new_statistics().from_vector(np.asarray(total))


def _checked(k, a, grid, da):
    if not isinstance(a, da.Array):
        raise ParameterError(f"u[{k}] must be a dask array; got {describe(a)}")
    if a.ndim == grid.ndim + 1:
        a = a[..., None]
    if a.ndim != grid.ndim + 2 or tuple(a.shape[1:-1]) != grid.shape or a.shape[0] == 0:
        raise ShapeError(f"u[{k}] must be (time, {', '.join(map(str, grid.shape))}[, fields]); "
                         f"got {describe(a)}")
    return a


def _run_graph(setup, u, step, offset, da):
    """Dask array ``(L,)``: the packed statistics of one run, from rows ``offset`` on."""
    m, halo = u.shape[0], setup.halo
    need = max(setup.min_samples, 2 * halo + 1)
    if m < setup.min_samples:
        raise ShapeError(f"a run of {m} snapshots is shorter than the {setup.min_samples} the "
                         "time method needs")
    u = u.astype(float).rechunk({i: -1 for i in range(1, u.ndim)})
    if min(u.chunks[0]) < need:
        u = u.rechunk({0: _row_chunks(m, max(need, m // max(1, len(u.chunks[0]))), need)})
    rows = da.arange(m, chunks=(u.chunks[0],)).astype(float)
    rows = rows.reshape((m,) + (1,) * (u.ndim - 1)).rechunk((u.chunks[0],) + (1,) * (u.ndim - 1))
    size = setup.new_statistics().to_vector().size
    blocks = da.map_overlap(_block, rows, u, depth={0: halo}, boundary="none", trim=False,
                            align_arrays=False, setup=setup, step=step, halo=halo, n_total=m,
                            offset=offset, meta=np.empty((0, 0)), dtype=float,
                            chunks=(1, size), drop_axis=list(range(2, u.ndim)))
    return blocks.sum(axis=0, split_every=SPLIT_EVERY)


def _row_chunks(m: int, size: int, need: int) -> tuple[int, ...]:
    chunks = [size] * (m // size)
    rest = m - size * len(chunks)
    if not chunks or rest >= need:
        chunks.append(rest)
    else:
        chunks[-1] += rest
    return tuple(c for c in chunks if c)


def _compute(graph, progress):
    import sys

    import dask

    show = sys.stderr.isatty() if progress is None else progress
    if not show:
        return dask.compute(graph)[0]
    from dask.diagnostics import ProgressBar
    with ProgressBar():
        return dask.compute(graph)[0]
