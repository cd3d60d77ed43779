"""Loading measured trajectories from CSV, NPZ, MATLAB ``.mat`` and HDF5 files.

Formats are read with their standard libraries (``csv``/numpy, ``numpy.load`` with
``allow_pickle=False``, ``scipy.io.loadmat``, ``h5py``); nothing is unpickled.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..constraints import InstanceOf, Predicate, validate_params
from ..errors import DataError, UnknownNameError
from ..resources import CHUNKED, check_memory
from .containers import check_file, open_arrays
from .csv_table import CSVTable
from .trajectory import as_2d, as_times

#: a column or variable name, and what ``states=``/``inputs=`` may be
NAME = InstanceOf(str, "a name")
NAMES = [None, NAME, Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) > 0 and all(
    isinstance(n, str) for n in v), "a non-empty list of names")]
#: memory of reading a CSV file whole, per character of it (Python lists of floats)
CSV_BYTES_PER_CHARACTER = 8
#: file suffixes :func:`load` reads, and the format each means
SUFFIXES = {".csv": "csv", ".txt": "csv", ".npz": "npz", ".mat": "mat", ".h5": "hdf5",
            ".hdf5": "hdf5", ".hdf": "hdf5"}


@dataclass(frozen=True)
class LoadedData:
    """Arrays read from a file.

    Attributes:
        x: states ``(m, n)``.
        t: times ``(m,)`` or ``None`` (then give a step to ``fit``).
        u: inputs ``(m, r)`` or ``None``.
        state_names, input_names: column names.
    """

    x: np.ndarray
    t: np.ndarray | None
    u: np.ndarray | None
    state_names: list[str]
    input_names: list[str]


def load(path, *, states=None, inputs=None, time: str | None = "t") -> LoadedData:
    """Read one trajectory from a file.

    Args:
        path: ``.csv``/``.txt`` (header row of column names), ``.npz``, ``.mat`` or
            ``.h5``/``.hdf5``.
        states: for CSV, the state column names (default: every column that is not
            time or an input); for NPZ/MAT/HDF5, either one variable name holding an
            ``(m, n)`` array (default ``"x"``) or a list of names of 1-D variables.
        inputs: like ``states`` (default: CSV none; others ``"u"`` if present).
        time: name of the time column/variable (``None``: no times in the file).

    Raises:
        MissingFileError: (a ``FileNotFoundError``) no such file.
        UnknownNameError: an unknown suffix or variable (the message lists what the file
            has).
        DataError: a folder, a corrupt file, non-numeric or non-finite values, bad times.
        ResourceError: an array too large to read whole (only the arrays asked for are
            read).
    """
    validate_params("io.load", {"states": states, "inputs": inputs, "time": time},
                    {"states": NAMES, "inputs": NAMES, "time": [None, NAME]})
    path = check_file(path)
    kind = SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise UnknownNameError(f"path {path.name!r}: unknown file type {path.suffix!r}; "
                               f"valid suffixes: {', '.join(sorted(SUFFIXES))}")
    if kind == "csv":
        return _from_csv(path, states, inputs, time)
    with open_arrays(path, kind) as arrays:
        return _from_variables(path, arrays, states, inputs, time, matlab=kind == "mat")


def _from_csv(path: Path, states, inputs, time) -> LoadedData:
    check_memory(f"reading {path.name} whole ({path.stat().st_size} bytes of text)",
                 CSV_BYTES_PER_CHARACTER * path.stat().st_size,
                 f"Stream it with CSVFiles instead: {CHUNKED}")
    with CSVTable(path) as table:
        header = table.header
        inputs = [inputs] if isinstance(inputs, str) else list(inputs or [])
        states = [states] if isinstance(states, str) else states
        position = table.position
        has_time = time is not None and time in position
        if states is None:
            taken = set(inputs)
            states = [h for h in header if h not in taken and not (has_time and h == time)]
        states = list(states)
        wanted = [*states, *inputs, *([time] if has_time else [])]
        missing = [n for n in wanted if n not in position]
        if missing:
            raise UnknownNameError(f"{path.name}: columns {missing[:20]} not found; the file "
                                   f"has {header[:50]}{' ...' if len(header) > 50 else ''}")
        data = table.read([position[n] for n in wanted])
    if len(data) == 0:
        raise DataError(f"{path.name}: a CSV file needs a header row and data rows; it has "
                        "no data rows")
    n_x, n_u = len(states), len(inputs)
    x = as_2d(f"{path.name} states", data[:, :n_x])
    u = as_2d(f"{path.name} inputs", data[:, n_x:n_x + n_u]) if inputs else None
    t = as_times(f"{path.name} column {time!r}", data[:, -1], len(x)) if has_time else None
    return LoadedData(x, t, u, states, inputs)


def read_mat(path, *, what: str = "file") -> dict[str, np.ndarray]:
    """Variables of a MATLAB ``.mat`` file (``scipy.io.loadmat``), without its ``__`` headers.

    Raises DataError naming ``what`` when the file is missing or is not a MATLAB file.
    """
    from scipy.io import loadmat

    path = Path(path)
    if not path.is_file():
        raise DataError(f"{what} {str(path)!r} does not exist")
    try:
        contents = loadmat(path)
    except Exception as e:  # scipy raises several types for non-MAT files
        raise DataError(f"{what} {str(path)!r} is not a readable MATLAB file ({e})") from None
    return {k: v for k, v in contents.items() if not k.startswith("__")}


def _stored_as_rows(shape, n_times, matlab: bool) -> bool:
    """Whether a 2-D variable holds samples in columns: decided by the length of the time
    vector when there is one, else (MATLAB files only) by being wider than tall."""
    if n_times is not None:
        return shape[0] != n_times and shape[1] == n_times
    return matlab and shape[0] < shape[1]


def _from_variables(path, arrays, states, inputs, time, *, matlab: bool):
    """The requested arrays of an open file (only those are read)."""
    names = arrays.names
    n_times = None
    if time is not None and time in names:
        n_times = int(np.prod(arrays.shape(time)))

    def get(name):
        if name not in names:
            raise UnknownNameError(f"{path.name}: variable {name!r} not found; the file has "
                                   f"{names}")
        return np.asarray(arrays.read(name))

    def columns(spec, default_stem):
        if isinstance(spec, str):
            a = get(spec)
            a = a[:, None] if a.ndim == 1 else a
            if a.ndim == 2 and _stored_as_rows(a.shape, n_times, matlab):
                a = a.T
            return a, [f"{default_stem}{i + 1}" for i in range(a.shape[1])] if a.ndim == 2 \
                else []
        return np.column_stack([get(n).ravel() for n in spec]), list(spec)

    x, state_names = columns("x" if states is None else states, "x")
    x = as_2d(f"{path.name} states", x)
    u, input_names = None, []
    if inputs is not None or "u" in names:
        u, input_names = columns("u" if inputs is None else inputs, "u")
        u = as_2d(f"{path.name} inputs", u, n_rows=len(x))
    t = None
    if time is not None and time in names:
        t = as_times(f"{path.name} variable {time!r}", get(time).ravel(), len(x))
    return LoadedData(x, t, u, state_names, input_names)
