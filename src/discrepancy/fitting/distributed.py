"""Gram statistics as a Dask reduction: the same fit on threads, processes or a cluster.

``model.fit(x)`` with ``x`` a ``dask.array`` (``(m, n)``, or a list of them, one per
trajectory) computes, for every row block, the block's ``ΘᵀΘ``, ``Θᵀy``, ``Σy²``
and row count with ``map_blocks`` (``map_overlap`` with ``halo`` rows each side
when derivatives are estimated, so windows straddling block edges are exact),
and sums them with a tree reduction (``sum(split_every=...)``). Only the p×p
result comes back to the caller, where the usual optimizer solves it. Which
scheduler runs the graph is Dask's choice: the threads of this process by
default, or a ``distributed`` cluster when a ``Client`` is active. A worker lost
mid-fit is handled by Dask recomputing its blocks from their inputs; every block
is a pure function of its rows, so nothing is lost or counted twice.

:func:`source_statistics` does the same for a list of files (one ``dask.delayed``
task per :class:`~discrepancy.data.chunks.ChunkSource`, each streamed on a worker).
Neither knows a model: they take the ``make_setup`` and differentiation method a model passes.
"""
from __future__ import annotations

import numpy as np

from .._optional import require
from ..data.chunks import ChunkSource, step_of
from ..data.trajectory import Trajectory
from ..data.validation import check_array
from ..errors import ParameterError, ShapeError, describe
from ..optimizers.gram import GramStatistics
from .accumulate import BlockAccumulator
from .setup import sample_rows
from .streaming import source_setup, stream_statistics

SPLIT_EVERY = 8


def _block(rows, x, *rest, setup, step, halo, n_total, trajectory, offset):
    """Packed statistics ``(1, L)`` of one row block (``rows``: global row numbers).

    The block's rows are checked first (the same checks as in-memory data), so a NaN is
    reported with its trajectory row and column, not as a non-finite sum afterwards."""
    rows = rows.ravel()
    where = f"dask array x[{trajectory}] rows {int(rows[0])}..{int(rows[-1])}"
    x = check_array("x", x, where=where, row_offset=int(rows[0]))
    u = rest[0] if setup.n_inputs else None
    xd = rest[-1] if len(rest) > (1 if setup.n_inputs else 0) else None
    if u is not None:
        u = check_array("u", u, where=where, row_offset=int(rows[0]))
    if xd is not None:
        xd = check_array("x_dot", xd, where=where, row_offset=int(rows[0]))
    t = rows * step
    lo, hi = 0, len(rows)
    if xd is None:
        lo = 0 if rows[0] == 0 else halo
        hi = len(rows) if rows[-1] == n_total - 1 else len(rows) - halo
    z, y, xd = (a[lo:hi] for a in setup.rows(Trajectory(t, x, u, xd)))
    stats = setup.new_statistics()
    stats.count = offset + int(rows[lo])  # the data row of this block's first row (folds)
    acc = BlockAccumulator(setup.transform, stats, n_threads=1, names=setup.names)
    acc.add(z, y, xd)
    acc.finish_trajectory()
    stats.count -= offset + int(rows[lo])
    return stats.to_vector()[None, :]


def _sample(budget: int, xs, us, xds, step) -> list[Trajectory]:
    """The first ``budget`` rows of the dask trajectories, computed, for choices made from
    the data."""
    out = []
    for x, u, xd in zip(xs, us, xds, strict=True):
        if budget <= 0:
            break
        rows = min(budget, x.shape[0])
        part = [None if a is None else check_array(name, np.asarray(a[:rows]), allow_1d=True,
                                                   where=f"dask array x[{len(out)}]")
                for name, a in (("x", x), ("u", u), ("x_dot", xd))]
        out.append(Trajectory(np.arange(rows) * step, *part))
        budget -= rows
    return out


def _as_dask(name, a, like, cols):
    import dask.array as da

    if a is None:
        return None
    a = a if isinstance(a, da.Array) else da.from_array(np.asarray(a, dtype=float))
    if a.ndim == 1 and name == "u":
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] != like.shape[0] or (cols is not None and a.shape[1] != cols):
        raise ShapeError(f"{name} must be ({like.shape[0]}, {cols or 'r'}) like x; "
                         f"got {describe(a)}")
    return a.astype(float).rechunk((like.chunks[0], -1))


def _trajectory_graph(setup, x, u, xd, step, trajectory, offset):
    """Dask array ``(L,)``: packed statistics of one trajectory."""
    import dask.array as da

    m = x.shape[0]
    if m == 0:
        raise ShapeError(f"x[{trajectory}] has no rows")
    x = x.astype(float).rechunk({1: -1})
    rows = da.arange(m, chunks=(x.chunks[0],))[:, None].astype(float)
    args = [a for a in (x, u, xd) if a is not None]
    out_chunks = (1, setup.new_statistics().to_vector().size)
    common = dict(setup=setup, step=step, n_total=m, trajectory=trajectory, offset=offset,
                  meta=np.empty((0, 0)), dtype=float, chunks=out_chunks)
    if xd is None:
        halo = setup.differentiation.halo
        if setup.differentiation.dropped_rows != (0, 0):
            raise ParameterError(f"{setup.differentiation!r} drops each trajectory's end rows; "
                                 "Dask fits need drop_endpoints=False (or x_dot)")
        if halo is None:
            raise ParameterError(f"{setup.differentiation!r} is a global method; Dask "
                                 "fits need a local one (FiniteDifference, SavitzkyGolay) or x_dot")
        need = max(setup.differentiation.min_samples, 2 * halo + 1)
        if min(x.chunks[0]) < need:
            chunks = _row_chunks(m, max(need, m // max(1, len(x.chunks[0]))), need)
            x = x.rechunk({0: chunks})
            rows = rows.rechunk({0: chunks})
            args = [a.rechunk({0: chunks}) for a in [x, *args[1:]]]
        blocks = da.map_overlap(_block, rows, *args, depth={0: halo, 1: 0}, boundary="none",
                                trim=False, align_arrays=False, halo=halo, **common)
    else:
        blocks = da.map_blocks(_block, rows, *args, halo=0, **common)
    return blocks.sum(axis=0, split_every=SPLIT_EVERY)


def _row_chunks(m: int, size: int, need: int) -> tuple[int, ...]:
    """Row blocks of about ``size`` rows, none shorter than ``need`` (a short remainder joins
    the last block), or one block when ``m < need``."""
    chunks = [size] * (m // size)
    rest = m - size * len(chunks)
    if not chunks or rest >= need:
        chunks.append(rest)
    else:
        chunks[-1] += rest
    return tuple(c for c in chunks if c)


def dask_statistics(make_setup, differentiation_method, x, *, t=None, u=None, x_dot=None):
    """``(setup, stats)`` of dask arrays (``x`` one array or a list, one per trajectory).

    ``make_setup(n_states, n_inputs, sample=...)`` gives the set-up (a model passes its
    own) from the first rows, as many as ``differentiation_method`` chooses from
    (:func:`~discrepancy.fitting.setup.sample_rows`)."""
    require("dask.array", purpose="fitting dask arrays")
    xs = list(x) if isinstance(x, (list, tuple)) else [x]
    us = _per_trajectory("u", u, len(xs))
    xds = _per_trajectory("x_dot", x_dot, len(xs))
    if xs[0].ndim != 2:
        raise ShapeError(f"x must be 2-D (samples, states); got {describe(xs[0])}")
    n = xs[0].shape[1]
    r = 0 if us[0] is None else (1 if np.ndim(us[0]) == 1 else us[0].shape[1])
    step = step_of(t)
    for k, xk in enumerate(xs):
        if xk.shape[0] == 0:
            raise ShapeError(f"x[{k}] has no rows")
    setup = make_setup(n, r, sample=_sample(sample_rows(differentiation_method), xs, us, xds,
                                            step))
    graphs, offset = [], 0
    for k, (xk, uk, xdk) in enumerate(zip(xs, us, xds, strict=True)):
        if xk.ndim != 2 or xk.shape[1] != n:
            raise ShapeError(f"x[{k}] must have shape (m, {n}); got {describe(xk)}")
        graphs.append(_trajectory_graph(setup, xk, _as_dask("u", uk, xk, r or None),
                                        _as_dask("x_dot", xdk, xk, n), step, k, offset))
        offset += xk.shape[0]
    held = setup.new_held_out()
    plan = _window_plan(held, xs, us, step)
    columns = [[xk.astype(float)] + ([_as_dask("u", uk, xk, r)] if r else [])
               for xk, uk in zip(xs, us, strict=True)]
    extremes = [[(a.min(axis=0), a.max(axis=0)) for a in parts] for parts in columns]
    ((total, pieces, extremes),) = _compute((sum(graphs[1:], graphs[0]),
                                             [(x_, u_) for _, x_, u_, _ in plan], extremes))
    stats = setup.new_statistics().from_vector(np.asarray(total))
    for (window, _, _, t), (x_, u_) in zip(plan, pieces, strict=True):
        window.append(t, np.asarray(x_), None if u_ is None else np.asarray(u_))
    for parts in extremes:    # per trajectory: [(x min, x max), (u min, u max)]
        held.extend_range(np.concatenate([lo for lo, _ in parts]),
                          np.concatenate([hi for _, hi in parts]))
    stats.held_out = held
    return setup, stats


def _window_plan(held, xs, us, step):
    """The forecast windows the in-memory fit would keep (same origins, same thinning),
    as ``(window, x slice, u slice, times)`` with the slices still lazy: only the kept
    windows are read. Rows are numbered as the statistics number them."""
    plan, offset = [], 0
    for k, xk in enumerate(xs):
        m = xk.shape[0]
        held.begin(offset)
        for origin in held.origins(m):
            window = held.register(origin)
            lo, hi = origin - window.origin, min(m, origin + held.max_lead + 1)
            plan.append((window, k, lo, hi))
        held.end()
        offset += m
    kept = {id(w) for w in held.windows}
    out = []
    for window, k, lo, hi in plan:
        if id(window) in kept:
            u = None if us[k] is None else _as_dask("u", us[k], xs[k], None)[lo:hi]
            out.append((window, xs[k][lo:hi].astype(float), u, np.arange(lo, hi) * step))
    return out


def _compute(graph):
    """``dask.compute`` with a progress bar on terminals (Dask's own: the local
    scheduler's ``ProgressBar``, or ``distributed.progress`` when a Client is active)."""
    import sys

    import dask

    if not sys.stderr.isatty():
        return dask.compute(graph)
    try:
        from distributed import default_client, progress
        client = default_client()
    except (ImportError, ValueError):
        from dask.diagnostics import ProgressBar
        with ProgressBar():
            return dask.compute(graph)
    future = client.compute(graph)
    progress(future)
    return (future.result(),)


def _per_trajectory(name, value, k):
    if isinstance(value, (list, tuple)):
        if len(value) != k:
            raise ShapeError(f"{name} must be a list of {k} arrays (one per trajectory of x); "
                             f"got {len(value)}")
        return list(value)
    if value is not None and k > 1:
        raise ShapeError(f"{name} must be a list when x is a list of {k} trajectories")
    return [value] * k


def _source_stats(setup, source, step):
    def same_layout(n, r, sample):
        if (n, r) != (setup.n_states, setup.n_inputs):
            raise ShapeError(f"{n} states and {r} inputs; the first source has "
                             f"{setup.n_states} and {setup.n_inputs}")
        return setup

    return stream_statistics(source, step, same_layout, progress=False, n_threads=1)[1]


def source_statistics(make_setup, differentiation_method, sources, *, t=None):
    """``(setup, stats)`` of a list of :class:`~discrepancy.data.chunks.ChunkSource` (e.g.
    one :class:`~discrepancy.data.sources.HDF5Source` per file), one ``dask.delayed`` task
    each, summed as a tree; the set-up is made from the first source's first rows (as many
    as ``differentiation_method`` chooses from)."""
    delayed = require("dask", purpose="fit_sources").delayed

    sources = list(sources)
    if not sources:
        raise ShapeError("sources must hold at least one ChunkSource; got an empty list")
    bad = [i for i, s in enumerate(sources) if not isinstance(s, ChunkSource)]
    if bad:
        raise ParameterError(f"sources[{bad[0]}] must be a ChunkSource (HDF5Source, NPZFiles, "
                             f"...); got {describe(sources[bad[0]])}")
    setup = source_setup(make_setup, differentiation_method, sources[0], step_of(t))
    step = step_of(t)
    parts = [delayed(_source_stats)(setup, s, step) for s in sources]
    while len(parts) > 1:
        parts = [delayed(_merged)(parts[i:i + SPLIT_EVERY]) for i in range(0, len(parts),
                                                                         SPLIT_EVERY)]
    (total,) = _compute(parts[0])
    return setup, total


def _merged(parts: list[GramStatistics]) -> GramStatistics:
    out = parts[0].empty_like()
    for part in parts:
        out += part
    return out
