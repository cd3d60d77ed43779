"""Chunk sources: read trajectories from files piece by piece (for streamed fits).

Every source is a :class:`~discrepancy.streaming.ChunkSource`: ``model.fit(source, t=dt)``
streams it. Files are read ``chunk_size`` rows at a time, so memory stays bounded
however large they are.

* :class:`HDF5Source` (h5py) and :class:`ZarrSource` (zarr): named datasets ``x``
  ``(m, n)`` and optionally ``t`` ``(m,)``, ``u`` ``(m, r)``, ``x_dot`` ``(m, n)``. Each file
  is one trajectory, or ``lengths`` splits its rows into several consecutive ones.
* :class:`NPZFiles` and :class:`CSVFiles`: a folder (or list) of files, each one
  trajectory, or with ``one_trajectory=True`` consecutive pieces of one trajectory
  in sorted name order.
"""
from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._optional import require
from ..constraints import Integral, Interval, Predicate, validate_params
from ..errors import (
    DataError,
    MissingFileError,
    ParameterError,
    ShapeError,
    UnknownNameError,
    describe,
)
from .chunks import Chunk, ChunkSource
from .containers import as_path, open_arrays
from .csv_table import CSVTable
from .io import NAME, NAMES

DEFAULT_CHUNK = 65536
FIELDS = ("x", "t", "u", "x_dot")


def _is_zarr_store(path: Path) -> bool:
    return any((path / marker).exists() for marker in ("zarr.json", ".zgroup", ".zarray"))


def _paths(paths, pattern: str) -> list[Path]:
    if isinstance(paths, (str, Path)) and Path(paths).is_dir() and not _is_zarr_store(Path(paths)):
        found = sorted(Path(paths).glob(pattern))
        if not found:
            raise MissingFileError(f"folder {str(paths)!r} holds no files matching {pattern!r}")
        return found
    if not isinstance(paths, (str, Path, list, tuple)) or not paths:
        raise ParameterError(f"paths must be a file, a folder or a non-empty list of files; "
                             f"got {describe(paths)}")
    out = [as_path(p, "paths") for p in ([paths] if isinstance(paths, (str, Path)) else paths)]
    for p in out:
        if not p.exists():
            raise MissingFileError(f"data file {str(p)!r} does not exist")
    return out


_CHUNK_SIZE = {"chunk_size": [Interval(Integral, 1, None)]}
_LENGTHS = {"lengths": [None, Interval(Integral, 1, None), Predicate(
    lambda v: isinstance(v, (list, tuple)) and len(v) > 0 and all(
        Interval(Integral, 1, None).is_satisfied_by(e) for e in v),
    "a non-empty list of integers >= 1")]}


class _ArrayFiles(ChunkSource):
    """Shared logic of HDF5 and zarr: named array datasets sliced by rows."""

    def __init__(self, paths, *, x: str = "x", t: str | None = None, u: str | None = None,
                 x_dot: str | None = None, chunk_size: int = DEFAULT_CHUNK,
                 lengths: int | Sequence[int] | None = None):
        validate_params(type(self).__name__, {"chunk_size": chunk_size, "lengths": lengths,
                                              "x": x, "t": t, "u": u, "x_dot": x_dot},
                        {**_CHUNK_SIZE, **_LENGTHS, "x": [NAME], "t": [None, NAME],
                         "u": [None, NAME], "x_dot": [None, NAME]})
        self.paths = _paths(paths, self._pattern)
        self.names = {"x": x, "t": t, "u": u, "x_dot": x_dot}
        self.chunk_size = int(chunk_size)
        self.lengths = lengths
        self.n_samples = 0
        for path in self.paths:  # fail early on names and shapes, before any fitting
            with self._open(path) as arrays:
                self.n_samples += self._rows(path, arrays)

    def _rows(self, path: Path, arrays) -> int:
        m = None
        for field, name in self.names.items():
            if name is None:
                continue
            if name not in arrays:
                raise UnknownNameError(f"{path.name}: no dataset {name!r} (for {field}); the file "
                                       f"has: {', '.join(arrays.available()) or 'nothing'}")
            shape = getattr(arrays[name], "shape", None)
            if shape is None:
                raise UnknownNameError(f"{path.name}: {name!r} (for {field}) is a group, not a "
                                       f"dataset; the file has: {', '.join(arrays.available())}")
            if len(shape) == 0:
                raise ShapeError(f"{path.name}: dataset {name!r} ({field}) holds one number; "
                                 "expected an array with one row per sample")
            if m is None:
                m = shape[0]
            if shape[0] != m or len(shape) != (1 if field == "t" else 2):
                raise ShapeError(f"{path.name}: dataset {name!r} ({field}) has shape {shape}; "
                                 f"expected {m} rows{' (1-D)' if field == 't' else ' (2-D)'} like "
                                 f"{self.names['x']!r}")
        return m

    def _splits(self, m: int, path: Path) -> list[tuple[int, int]]:
        if self.lengths is None:
            return [(0, m)]
        if np.ndim(self.lengths) == 0:
            edges = list(range(0, m, int(self.lengths))) + [m]
        else:
            edges = [0, *np.cumsum([int(v) for v in self.lengths]).tolist()]
            if edges[-1] != m:
                raise ShapeError(f"{path.name}: lengths add up to {edges[-1]} rows; the file "
                                 f"has {m}")
        return list(itertools.pairwise(edges))

    def trajectories(self):
        for path in self.paths:
            with self._open(path) as arrays:
                m = arrays[self.names["x"]].shape[0]
                for a, b in self._splits(m, path):
                    yield self._chunks(path, arrays, a, b)

    def _chunks(self, path, arrays, a, b):
        for s in range(a, b, self.chunk_size):
            e = min(s + self.chunk_size, b)
            parts = {f: np.asarray(arrays[name][s:e]) for f, name in self.names.items()
                     if name is not None}
            yield Chunk(**parts, where=f"{path.name} rows {s}..{e - 1}")


class _Opened:
    """Context manager giving name -> array access to an open file."""

    def __init__(self, handle, listing):
        self.handle, self.listing = handle, listing

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        close = getattr(self.handle, "close", None)
        if close:
            close()

    def __contains__(self, name):
        try:
            self.handle[name]
        except KeyError:
            return False
        return True

    def __getitem__(self, name):
        return self.handle[name]

    def available(self):
        return self.listing()


class HDF5Source(_ArrayFiles):
    """Trajectories in HDF5 files (h5py). Args: ``paths`` a file, a list or a folder of
    ``*.h5``; ``x, t, u, x_dot`` dataset names (paths like ``"run1/x"`` allowed);
    ``chunk_size`` rows per read; ``lengths`` trajectory lengths within a file."""

    _pattern = "*.h5"

    def _open(self, path):
        h5py = require("h5py", purpose="HDF5Source")

        try:
            f = h5py.File(path, "r")
        except OSError as e:
            raise DataError(f"{path.name} is not a readable HDF5 file ({e})") from None

        def listing():
            names = []
            f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
            return names
        return _Opened(f, listing)


class ZarrSource(_ArrayFiles):
    """Trajectories in zarr groups (folders). Arguments as :class:`HDF5Source`."""

    _pattern = "*.zarr"

    def _open(self, path):
        zarr = require("zarr", purpose="ZarrSource")

        try:
            g = zarr.open_group(str(path), mode="r")
        except Exception as e:  # zarr raises several types for what is not a group
            raise DataError(f"{path.name} is not a readable zarr group ({type(e).__name__}: "
                            f"{e})") from None
        return _Opened(g, lambda: sorted(k for k, _ in g.arrays()))


class _TableFiles(ChunkSource):
    def __init__(self, paths, *, x, t=None, u=None, x_dot=None, chunk_size=DEFAULT_CHUNK,
                 one_trajectory: bool = False):
        names = self._names
        validate_params(type(self).__name__, {"chunk_size": chunk_size,
                                              "one_trajectory": one_trajectory,
                                              "x": x, "t": t, "u": u, "x_dot": x_dot},
                        {**_CHUNK_SIZE, "one_trajectory": [bool], "x": names[1:],
                         "t": [None, NAME], "u": names, "x_dot": names})
        self.paths = _paths(paths, self._pattern)
        self.names = {"x": x, "t": t, "u": u, "x_dot": x_dot}
        self.chunk_size = int(chunk_size)
        self.one_trajectory = one_trajectory
        self.n_samples = None

    def trajectories(self):
        if self.one_trajectory:
            yield (c for p in self.paths for c in self._file_chunks(p))
        else:
            for p in self.paths:
                yield self._file_chunks(p)

    def _missing(self, path, have):
        for field, name in self.names.items():
            for n in ([] if name is None else [name] if isinstance(name, str) else name):
                if n not in have:
                    raise UnknownNameError(f"{path.name}: no {self._what} {n!r} (for {field}); "
                                           f"it has: {', '.join(have)}")


class NPZFiles(_TableFiles):
    """NPZ files (``numpy.load``, no pickles) with arrays named by ``x, t, u, x_dot``
    (default ``x="x"``). Each file is loaded whole, then cut into chunks."""

    _pattern = "*.npz"
    _what = "array"
    _names = [None, NAME]

    def __init__(self, paths, *, x="x", **kwargs):
        super().__init__(paths, x=x, **kwargs)

    def _file_chunks(self, path):
        with open_arrays(path, "npz") as f:
            self._missing(path, f.names)
            data = {k: f.read(n) for k, n in self.names.items() if n is not None}
        m = data["x"].shape[0]
        for s in range(0, m, self.chunk_size):
            yield Chunk(**{k: v[s:s + self.chunk_size] for k, v in data.items()},
                        where=f"{path.name} rows {s}..{min(s + self.chunk_size, m) - 1}")


class CSVFiles(_TableFiles):
    """CSV files with a header row. ``x`` (and ``u``, ``x_dot``) are lists of column names,
    ``t`` one column name. Read ``chunk_size`` lines at a time."""

    _pattern = "*.csv"
    _what = "column"
    _names = NAMES

    def _file_chunks(self, path):
        with CSVTable(path) as table:
            self._missing(path, table.position)
            cols = {k: [n] if isinstance(n, str) else list(n)
                    for k, n in self.names.items() if n is not None}
            flat = [table.position[c] for names in cols.values() for c in names]
            start = 0
            while True:
                block = table.read(flat, max_rows=self.chunk_size)
                if len(block) == 0:
                    return
                parts, j = {}, 0
                for k, names in cols.items():
                    parts[k] = block[:, j] if k == "t" else block[:, j:j + len(names)]
                    j += len(names)
                yield Chunk(**parts, where=f"{path.name} rows {start}..{start + len(block) - 1}")
                start += len(block)
