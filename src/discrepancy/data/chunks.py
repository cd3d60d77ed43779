"""Chunks of one trajectory and sources of them: the data side of streamed fits.

A :class:`Chunk` holds consecutive rows of ONE trajectory in time order; a
:class:`ChunkSource` yields trajectories, each an iterable of chunks. This module
converts what users pass (arrays, mappings, iterators) into chunks and validates
them one by one, naming the chunk and row of any problem, so nothing is silently
dropped however far into a stream it appears. See :mod:`discrepancy.streaming`.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ParameterError, ShapeError, describe
from .validation import check_array, check_times

FIELDS = ("x", "t", "u", "x_dot", "weight")


@dataclass(frozen=True)
class Chunk:
    """Consecutive rows of one trajectory (see the module docstring).

    Attributes:
        x: states ``(k, n)``.
        t: times ``(k,)`` or ``None``.
        u: inputs ``(k, r)`` or ``None``.
        x_dot: measured derivatives ``(k, n)`` or ``None``.
        weight: the rows' weights in the regression ``(k,)`` or ``None``.
        where: description used in error messages (e.g. ``"run3.h5 rows 0..65535"``).
    """

    x: np.ndarray
    t: np.ndarray | None = None
    u: np.ndarray | None = None
    x_dot: np.ndarray | None = None
    weight: np.ndarray | None = None
    where: str | None = None

    @property
    def n_rows(self) -> int:
        """Number of rows ``k``."""
        return self.x.shape[0]

    def rows(self, start: int, stop: int | None = None) -> Chunk:
        """Rows ``start:stop`` of every field, as a new chunk."""
        end = self.n_rows if stop is None else stop
        if not (isinstance(start, (int, np.integer)) and isinstance(end, (int, np.integer))
                and start <= self.n_rows and end <= self.n_rows):
            raise ParameterError(f"start and stop must be row numbers up to {self.n_rows} "
                                 f"(negative: from the end); got {start!r} and {stop!r}")
        cut = slice(start, stop)
        return replace(self, **{f: None if getattr(self, f) is None else getattr(self, f)[cut]
                                for f in FIELDS})


class ChunkSource(ABC):
    """Data as trajectories, each an iterable of :class:`Chunk` in time order."""

    #: total number of rows if known (for the progress bar), else None
    n_samples: int | None = None

    @abstractmethod
    def trajectories(self) -> Iterator[Iterable[Chunk]]:
        """Yield one iterable of chunks per trajectory."""


class IterableSource(ChunkSource):
    """Trajectories given as iterables of chunks (one iterable per trajectory)."""

    def __init__(self, trajectories: list):
        self._trajectories = trajectories

    def trajectories(self):
        yield from self._trajectories


def as_source(x) -> ChunkSource:
    """Chunked data as a :class:`ChunkSource`: a source as it is, an iterator of chunks as one
    trajectory, a list of sources or of iterators as several."""
    if isinstance(x, ChunkSource):
        return x
    if isinstance(x, Iterator):
        return IterableSource([x])
    if isinstance(x, (list, tuple)) and all(isinstance(e, ChunkSource) for e in x):
        return _Joined(list(x))
    if isinstance(x, (list, tuple)) and all(isinstance(e, Iterator) for e in x):
        return IterableSource(list(x))
    raise ParameterError(f"x must be an iterator of chunks, a ChunkSource or a list of either "
                         f"kind (not mixed); got {describe(x)}")


class _Joined(ChunkSource):
    def __init__(self, sources):
        self.sources = sources
        sizes = [s.n_samples for s in sources]
        self.n_samples = None if None in sizes else sum(sizes)

    def trajectories(self):
        for s in self.sources:
            yield from s.trajectories()


def as_chunk(item, where: str) -> Chunk:
    """A :class:`Chunk` from an array (x only), a mapping, or a Chunk."""
    if isinstance(item, Chunk):
        return item if item.where else replace(item, where=where)
    if isinstance(item, Mapping):
        unknown = sorted(set(item) - set(FIELDS))
        if unknown or "x" not in item:
            raise ShapeError(f"{where}: a chunk mapping needs key 'x' and may have {FIELDS}; "
                             f"got keys {sorted(item)}")
        return Chunk(**{k: item[k] for k in FIELDS if k in item}, where=where)
    if isinstance(item, np.ndarray) or hasattr(item, "__array__"):
        return Chunk(x=item, where=where)
    raise ShapeError(f"{where}: a chunk must be an array of x, a mapping with keys {FIELDS} or "
                     f"a Chunk; got {describe(item)}")


# ------------------------------------------------------------------ validation
@dataclass
class _Layout:
    """Columns and optional fields fixed by the first chunk; every later chunk must match."""

    n: int
    r: int
    has: dict


def _check(name, a, chunk, offset, *, rows, cols, ndim=2):
    return check_array(name, a, n_rows=rows, n_cols=cols, ndim=ndim, allow_1d=name == "u",
                       where=chunk.where, row_offset=offset)


def _validate(chunk: Chunk, layout: _Layout, offset: int, step: float, t_last) -> Chunk:
    x = _check("x", chunk.x, chunk, offset, rows=None, cols=layout.n)
    k = x.shape[0]
    for f in ("t", "u", "x_dot", "weight"):
        if (getattr(chunk, f) is None) == layout.has[f]:
            state = "has no" if layout.has[f] else "has"
            raise ShapeError(f"{chunk.where}: chunk {state} {f}, unlike the first chunk; every "
                             "chunk must carry the same fields")
    u = None if chunk.u is None else _check("u", chunk.u, chunk, offset, rows=k, cols=layout.r)
    xd = None if chunk.x_dot is None else _check("x_dot", chunk.x_dot, chunk, offset, rows=k,
                                                 cols=layout.n)
    if chunk.t is None:
        t = check_times("t", step, k, where=chunk.where, row_offset=offset)
    else:
        t = check_times("t", chunk.t, k, where=chunk.where, after=t_last, row_offset=offset)
    from .trajectory import check_weight

    w = None if chunk.weight is None else check_weight("weight", chunk.weight, k,
                                                       where=chunk.where, row_offset=offset)
    return Chunk(x, t, u, xd, w, chunk.where)


def validated_chunks(items: Iterable, traj: int, step: float, layout: _Layout | None):
    """Yield validated chunks of trajectory ``traj`` (creating the layout from the first)."""
    offset, t_last = 0, None
    for i, item in enumerate(items):
        where = f"chunk {i} of trajectory {traj}"
        chunk = as_chunk(item, where)
        if chunk.where != where:
            chunk = replace(chunk, where=f"{where} ({chunk.where})")
        if layout is None or layout.has is None:
            x = np.asarray(chunk.x)
            if layout is not None and x.ndim == 2 and x.shape[1] != layout.n:
                raise ShapeError(f"{where}: x has {x.shape[1]} columns; the model has "
                                 f"{layout.n} states")
            u = None if chunk.u is None else np.asarray(chunk.u)
            if x.ndim != 2:
                raise ShapeError(f"{where}: x must be 2-D (rows, states); got shape {x.shape}")
            layout = _Layout(x.shape[1], 0 if u is None else (1 if u.ndim == 1 else u.shape[1]),
                             {f: getattr(chunk, f) is not None
                              for f in ("t", "u", "x_dot", "weight")})
        chunk = _validate(chunk, layout, offset, step, t_last)
        if chunk.n_rows:
            yield layout, chunk
            offset += chunk.n_rows
            t_last = chunk.t[-1]


def peek_layout(source: ChunkSource) -> tuple[int, int]:
    """``(n_states, n_inputs)`` from the first chunk of ``source``."""
    for k, items in enumerate(source.trajectories()):
        for layout, _ in validated_chunks(items, k, 1.0, None):
            return layout.n, layout.r
    raise ShapeError("x holds no rows")


def is_dask(x) -> bool:
    """True for a dask collection (checked by module name: dask is never imported here)."""
    return type(x).__module__.split(".")[0] == "dask"


def data_kind(x) -> str:
    """How ``fit`` receives ``x``: ``"dask"`` (dask arrays, or a list of them), ``"chunks"``
    (an iterator of chunks, a ChunkSource, or a list of those) or ``"arrays"``."""
    items = list(x) if isinstance(x, (list, tuple)) else [x]
    if any(isinstance(e, Chunk) for e in items):
        raise ParameterError("x is a list of Chunk objects; pass the chunks of one trajectory "
                             "as an iterator, iter([chunk0, chunk1, ...]), or several "
                             "trajectories as a list of such iterators")
    if items and all(is_dask(e) for e in items):
        return "dask"
    if items and all(isinstance(e, (Iterator, ChunkSource)) for e in items):
        return "chunks"
    return "arrays"


def step_of(t) -> float:
    """The time step for chunks without times: ``t`` (a positive number) or 1."""
    if t is None:
        return 1.0
    if np.ndim(t) != 0:
        raise ParameterError("with chunked x, t must be the time step (a number); give "
                             "per-row times inside the chunks (Chunk(x, t=...))")
    times = check_times("t", t, 2)  # checks that the step is a positive finite number
    return float(times[1] - times[0])
