"""Named arrays in NPZ, MATLAB and HDF5 files, read one at a time with sizes checked first.

:func:`open_arrays` lists a file's arrays and their shapes without reading them, and
reads only the arrays asked for, each after checking that it fits in memory
(:func:`discrepancy.resources.check_memory`) and, for NPZ, that its header agrees with
the bytes stored (a 4 kB file can declare a 32 GB array). Files that are not what their
suffix says (corrupt, truncated, a folder) raise :class:`~discrepancy.errors.DataError`
naming the file; arrays of Python objects are refused (nothing is ever unpickled).
"""
from __future__ import annotations

import os
import zipfile
from pathlib import Path

import numpy as np

from ..errors import DataError, MissingFileError, ParameterError, describe
from ..resources import CHUNKED, check_memory, n_bytes


def as_path(path, what: str = "path") -> Path:
    """``path`` (text or a path object) as a Path; ParameterError for anything else."""
    if not isinstance(path, (str, os.PathLike)) or isinstance(path, bytes) or path == "":
        raise ParameterError(f"{what} must be a file name (text or a pathlib.Path); got "
                             f"{describe(path)}")
    return Path(path)


def check_file(path, what: str = "data file") -> Path:
    """``path`` as a Path to an existing file; MissingFileError or DataError (a folder)."""
    path = as_path(path, what)
    if not path.exists():
        raise MissingFileError(f"{what} {str(path)!r} does not exist")
    if not path.is_file():
        raise DataError(f"{what} {str(path)!r} is a folder, not a file")
    return path


class _Arrays:
    """A file's arrays by name: ``names``, ``shape(name)``, ``read(name)``; a context
    manager that closes the file."""

    def __init__(self, path: Path, kind: str):
        self.path, self.kind = path, kind

    def __enter__(self) -> _Arrays:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the file (hook)."""

    def type_name(self, name: str) -> str:
        """The stored type of ``name``, for messages."""
        return f"dtype {self.dtype(name)}"

    def read(self, name: str) -> np.ndarray:
        """The array ``name``, after checking its size and type."""
        shape, dtype = self.shape(name), self.dtype(name)
        if dtype.hasobject:
            raise DataError(f"{self.path.name}: array {name!r} is not numeric "
                            f"({self.type_name(name)}); only numeric arrays are read (nothing "
                            "is unpickled)")
        check_memory(f"reading array {name!r} {tuple(shape)} of {self.path.name}",
                     n_bytes(shape, dtype.itemsize), f"Read it in chunks instead: {CHUNKED}")
        try:
            return self._read(name)
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as e:
            raise DataError(f"{self.path.name}: array {name!r} could not be read, the file "
                            f"is corrupt or truncated ({type(e).__name__}: {e})") from None


class _NPZ(_Arrays):
    def __init__(self, path, kind):
        super().__init__(path, kind)
        try:
            self._zip = zipfile.ZipFile(path)
        except (zipfile.BadZipFile, OSError) as e:
            raise DataError(f"{path.name} is not a readable NPZ (zip) file ({e})") from None
        self._members = {n[:-4]: n for n in self._zip.namelist() if n.endswith(".npy")}
        self.names = sorted(self._members)
        self._headers = {}

    def close(self):
        self._zip.close()

    def _header(self, name):
        if name not in self._headers:
            member = self._members[name]
            try:
                with self._zip.open(member) as f:
                    fmt = np.lib.format
                    version = fmt.read_magic(f)
                    read_header = fmt.read_array_header_1_0 if version == (1, 0) else \
                        fmt.read_array_header_2_0
                    shape, _, dtype = read_header(f)
                    offset = f.tell()
            except (ValueError, OSError, zipfile.BadZipFile, EOFError) as e:
                raise DataError(f"{self.path.name}: array {name!r} has no valid .npy header "
                                f"({e})") from None
            stored = self._zip.getinfo(member).file_size - offset
            if not dtype.hasobject and n_bytes(shape, dtype.itemsize) > stored:
                raise DataError(f"{self.path.name}: array {name!r} declares shape {shape} "
                                f"({n_bytes(shape, dtype.itemsize)} bytes) but the file holds "
                                f"{stored} bytes for it; the file is corrupt")
            self._headers[name] = (shape, dtype)
        return self._headers[name]

    def shape(self, name):
        return self._header(name)[0]

    def dtype(self, name):
        return self._header(name)[1]

    def _read(self, name):
        with self._zip.open(self._members[name]) as f:
            return np.lib.format.read_array(f, allow_pickle=False)


class _MAT(_Arrays):
    def __init__(self, path, kind):
        from scipy.io import whosmat

        super().__init__(path, kind)
        try:
            listing = whosmat(path)
        except Exception as e:  # scipy raises several types for non-MAT files
            raise DataError(f"{path.name} is not a readable MATLAB file ({e})") from None
        self._shapes = {n: tuple(s) for n, s, _ in listing}
        self._classes = {n: c for n, _, c in listing}
        self.names = sorted(self._shapes)

    def shape(self, name):
        return self._shapes[name]

    def dtype(self, name):
        numeric = self._classes[name] in ("double", "single", "logical") or \
            self._classes[name].startswith(("int", "uint"))
        return np.dtype(float) if numeric else np.dtype(object)

    def type_name(self, name):
        return f"MATLAB class {self._classes[name]}"

    def _read(self, name):
        from scipy.io import loadmat

        return loadmat(self.path, variable_names=[name])[name]


class _HDF5(_Arrays):
    def __init__(self, path, kind):
        from .._optional import require

        h5py = require("h5py", purpose="reading HDF5 files")
        super().__init__(path, kind)
        try:
            self._file = h5py.File(path, "r")
        except OSError as e:
            raise DataError(f"{path.name} is not a readable HDF5 file ({e})") from None
        names = []
        self._file.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset)
                              else None)
        self.names = sorted(names)

    def close(self):
        self._file.close()

    def shape(self, name):
        return self._file[name].shape or ()

    def dtype(self, name):
        dtype = self._file[name].dtype
        return dtype if dtype.kind in "biufc" else np.dtype(object)

    def _read(self, name):
        return self._file[name][()]


def open_arrays(path: Path, kind: str) -> _Arrays:
    """The arrays of an ``"npz"``, ``"mat"`` or ``"hdf5"`` file (use as a context manager)."""
    return {"npz": _NPZ, "mat": _MAT, "hdf5": _HDF5}[kind](path, kind)
