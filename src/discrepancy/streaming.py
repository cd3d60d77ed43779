"""Chunked fitting: data that arrive in pieces, or do not fit in memory.

What a chunk is
    A :class:`Chunk` holds consecutive rows of ONE trajectory in time order:
    ``x`` ``(k, n)`` and optionally ``t`` ``(k,)`` (the times of these rows),
    ``u`` ``(k, r)`` and ``x_dot`` ``(k, n)``. A plain array is a chunk of ``x``;
    a mapping with keys among ``x, t, u, x_dot`` is converted. Chunks without
    ``t`` are placed on the grid ``t = row * step`` with ``step`` the ``t`` given to
    ``fit`` (default 1), counted from the trajectory's first row, exactly as the
    in-memory fit does.

What a trajectory is
    ``model.fit(iterator_of_chunks)`` is one trajectory; a list of such
    iterators, or a :class:`ChunkSource` (files, see :mod:`discrepancy.data.sources`),
    gives several. Derivatives never straddle the join of two trajectories.

Exactness
    A local differentiation method (``halo`` rows each side, e.g. finite
    differences or Savitzky–Golay) is applied on windows of ``2 halo`` carried
    rows plus the next chunk, keeping only rows whose stencil lies inside the
    window (and the true ends of the trajectory), so every derivative is the one
    the whole trajectory gives. Rows then go through the same fixed block grid
    as the in-memory fit (:mod:`discrepancy.accumulate`), so the Gram statistics,
    and the model, equal the in-memory ones (to rounding in the derivative's
    time step). Global methods (``halo`` None: splines, trend filtering, Kalman)
    are refused: their derivative at one row depends on the whole trajectory;
    differentiate first and stream ``x_dot``.

Memory is bounded by about two chunks plus a 4096-row block of Θ.
"""
from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import replace

import numpy as np

from .accumulate import BLOCK_ROWS, BlockAccumulator
from .data.chunks import (  # noqa: F401  (Chunk, ChunkSource, peek_layout: public here too)
    FIELDS,
    Chunk,
    ChunkSource,
    IterableSource,
    _Layout,
    _validated,
    as_source,
    peek_layout,
)
from .data.trajectory import Trajectory
from .errors import DataError, ParameterError, ShapeError

__all__ = ["Chunk", "ChunkSource", "IterableSource", "fit_streamed", "is_streamed",
           "stream_statistics"]


def _is_dask(x) -> bool:
    return type(x).__module__.split(".")[0] == "dask"


def _is_chunk_stream(x) -> bool:
    return isinstance(x, (Iterator, ChunkSource))


def is_streamed(x) -> bool:
    """True for input that :func:`fit_streamed` handles instead of the in-memory fit:
    a dask array, an iterator of chunks, a ChunkSource, or a non-empty list of those."""
    if isinstance(x, (list, tuple)):
        return bool(x) and all(_is_dask(e) or _is_chunk_stream(e) for e in x)
    return _is_dask(x) or _is_chunk_stream(x)


# ------------------------------------------------------------------ stitching
def _concat(a: Chunk, b: Chunk) -> Chunk:
    return Chunk(**{f: None if getattr(a, f) is None else
                    np.concatenate([getattr(a, f), getattr(b, f)]) for f in FIELDS},
                 where=b.where)


def residual_rows(model, chunks: Iterable[Chunk]) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Yield ``(z, y)`` for consecutive rows of one trajectory, equal to ``model.residual``
    of the whole trajectory (the model must be set up; chunks validated)."""
    for xs, xd, lo, hi in _stitched(chunks, model.differentiation_method_):
        if hi > lo:
            yield model.residual(Trajectory(xs.t[lo:hi], xs.x[lo:hi], None if xs.u is None
                                            else xs.u[lo:hi], xd[lo:hi]))


def _stitched(chunks, method):
    """Yield ``(window, x_dot_or_smoothed, lo, hi)``; rows ``lo:hi`` of the window are exact.

    A window (carried rows plus one chunk) is differentiated once the next chunk shows it
    is not the trajectory's last; chunks with ``x_dot`` pass straight through.
    """
    window, first = None, True
    for chunk in chunks:
        if chunk.x_dot is not None:
            yield chunk, chunk.x_dot, 0, chunk.n_rows
            continue
        h = method.halo
        if h is None:
            raise ParameterError(
                f"{method!r} is a global differentiation method (the derivative at one row "
                "depends on the whole trajectory), so it cannot be applied chunk by chunk; "
                "use FiniteDifference() or SavitzkyGolay(), or compute x_dot first and stream "
                "it with the chunks")
        if window is not None and window.n_rows >= max(method.min_samples, 2 * h + 1):
            xs, xd = method(window.x, window.t)  # not the last window: a chunk follows
            yield replace(window, x=xs), xd, (0 if first else h), window.n_rows - h
            window, first = window.rows(window.n_rows - 2 * h), False
        window = chunk if window is None else _concat(window, chunk)
    if window is not None:
        xs, xd = method(window.x, window.t)
        yield replace(window, x=xs), xd, (0 if first else method.halo), window.n_rows


# ------------------------------------------------------------------ fitting
class _RowFeeder:
    """Passes rows to a BlockAccumulator on the trajectory's block grid: whole blocks go
    through as views, a partial block is kept (copied) until the next rows complete it."""

    def __init__(self, acc: BlockAccumulator):
        self.acc = acc
        self.z, self.y, self.rows = [], [], 0

    def add(self, z, y):
        if self.rows:
            if self.rows + z.shape[0] < BLOCK_ROWS:
                self._keep(z, y)
                return
            need = BLOCK_ROWS - self.rows
            self.acc.add(np.concatenate([*self.z, z[:need]]), np.concatenate([*self.y, y[:need]]))
            self.z, self.y, self.rows = [], [], 0
            z, y = z[need:], y[need:]
        cut = (z.shape[0] // BLOCK_ROWS) * BLOCK_ROWS
        if cut:
            self.acc.add(z[:cut], y[:cut])
        if cut < z.shape[0]:
            self._keep(z[cut:], y[cut:])

    def _keep(self, z, y):
        self.z.append(z.copy())
        self.y.append(y.copy())
        self.rows += z.shape[0]

    def end_trajectory(self):
        if self.rows:
            self.acc.add(np.concatenate(self.z), np.concatenate(self.y))
        self.z, self.y, self.rows = [], [], 0
        self.acc.finish_trajectory()


def step_of(t) -> float:
    """The time step for chunks without times: ``t`` (a positive number) or 1."""
    if t is None:
        return 1.0
    if np.ndim(t) != 0:
        raise ParameterError("with chunked x, t must be the time step (a number); give "
                             "per-row times inside the chunks (Chunk(x, t=...))")
    if not np.isfinite(float(t)) or float(t) <= 0:
        raise DataError(f"t as a time step must be a positive finite number; got {t}")
    return float(t)


def stream_statistics(model, source: ChunkSource, step: float, *, progress: bool | None = None,
                      n_threads: int | None = None, setup: bool = True):
    """Gram statistics of all rows of ``source``. With ``setup`` the model is set up from
    the first chunk; otherwise it must be set up already and the chunks must match it."""
    from tqdm.auto import tqdm

    acc = feeder = layout = None
    if not setup:
        layout = _Layout(model.n_states_, model.n_inputs_, None)
    with tqdm(total=source.n_samples, unit=" samples", unit_scale=True, desc="fit",
              disable=None if progress is None else not progress) as bar:
        for k, items in enumerate(source.trajectories()):
            stream = _validated(items, k, step, layout)
            first = next(stream, None)
            if first is None:
                raise ShapeError(f"trajectory {k} of x has no rows")
            if acc is None:
                layout = first[0]
                if setup:
                    model._setup(layout.n, layout.r)
                elif (layout.n, layout.r) != (model.n_states_, model.n_inputs_):
                    raise ShapeError(f"trajectory {k}: {layout.n} states and {layout.r} inputs; "
                                     f"the model was set up for {model.n_states_} and "
                                     f"{model.n_inputs_}")
                acc = BlockAccumulator(model.feature_library_.transform,
                                       model.feature_library_.n_features_, layout.n,
                                       n_threads=n_threads)
                feeder = _RowFeeder(acc)

            def counted(first=first, stream=stream):
                for _, chunk in _chain(first, stream):
                    yield chunk
                    bar.update(chunk.n_rows)

            for z, y in residual_rows(model, counted()):
                feeder.add(z, y)
            feeder.end_trajectory()
    if acc is None:
        raise ShapeError("x holds no trajectories")
    return acc.total


def _chain(first, rest):
    yield first
    yield from rest


def fit_streamed(model, x, *, t=None, u=None, x_dot=None):
    """``model.fit`` for streamed input (see the module docstring); returns the model."""
    if _is_dask(x) or (isinstance(x, (list, tuple)) and x and all(_is_dask(e) for e in x)):
        from .distributed import fit_dask
        return fit_dask(model, x, t=t, u=u, x_dot=x_dot)
    if u is not None or x_dot is not None:
        raise ParameterError("with chunked x, give u and x_dot inside the chunks "
                             "(Chunk(x, u=..., x_dot=...)), not as separate arguments")
    stats = stream_statistics(model, as_source(x), step_of(t))
    return model._fit_statistics(stats)
