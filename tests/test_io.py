"""File loading: the same arrays come back from every format; bad files get clear errors."""
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io

from discrepancy import io
from discrepancy.errors import DataError, UnknownNameError


@pytest.fixture
def arrays(rng):
    t = np.arange(50) * 0.1
    return t, rng.standard_normal((50, 3)), rng.standard_normal((50, 1))


def write_csv(path, header, table):
    np.savetxt(path, table, delimiter=",", header=",".join(header), comments="")


def test_csv_columns_by_name(tmp_path, arrays):
    t, x, u = arrays
    write_csv(tmp_path / "d.csv", ["time", "a", "b", "c", "force"], np.c_[t, x, u])
    d = io.load(tmp_path / "d.csv", inputs=["force"], time="time")
    np.testing.assert_allclose(d.x, x, rtol=1e-15)
    np.testing.assert_allclose(d.u, u, rtol=1e-15)
    np.testing.assert_allclose(d.t, t, rtol=1e-15)
    assert d.state_names == ["a", "b", "c"] and d.input_names == ["force"]


def test_npz_mat_hdf5_give_the_same_arrays(tmp_path, arrays):
    t, x, u = arrays
    np.savez(tmp_path / "d.npz", t=t, x=x, u=u)
    scipy.io.savemat(tmp_path / "d.mat", {"t": t, "x": x.T, "u": u.T})  # MATLAB rows
    with h5py.File(tmp_path / "d.h5", "w") as f:
        f["run/x"], f["run/u"], f["t"] = x, u, t
    loaded = [io.load(tmp_path / "d.npz"), io.load(tmp_path / "d.mat"),
              io.load(tmp_path / "d.h5", states="run/x", inputs="run/u")]
    for d in loaded:
        np.testing.assert_allclose(d.x, x, rtol=1e-15)
        np.testing.assert_allclose(d.u, u, rtol=1e-15)
        np.testing.assert_allclose(d.t, t, rtol=1e-15)


def test_states_from_separate_one_dimensional_variables(tmp_path, arrays):
    t, x, _ = arrays
    np.savez(tmp_path / "d.npz", t=t, p=x[:, 0], q=x[:, 1])
    d = io.load(tmp_path / "d.npz", states=["p", "q"])
    np.testing.assert_allclose(d.x, x[:, :2])
    assert d.state_names == ["p", "q"] and d.u is None


def test_errors_name_what_is_wrong(tmp_path, arrays):
    t, x, _ = arrays
    np.savez(tmp_path / "d.npz", t=t, x=x)
    with pytest.raises(UnknownNameError, match="'states'.*not found|variable 'states'"):
        io.load(tmp_path / "d.npz", states="states")
    with pytest.raises(UnknownNameError, match="suffix"):
        io.load(_touch(tmp_path / "d.xyz"))
    with pytest.raises(FileNotFoundError):
        io.load(tmp_path / "missing.csv")
    write_csv(tmp_path / "bad.csv", ["t", "a"], np.c_[t, x[:, 0]])
    text = (tmp_path / "bad.csv").read_text().replace("\n", "\n", 1).splitlines()
    text[5] = text[5].split(",")[0] + ",oops"
    (tmp_path / "bad.csv").write_text("\n".join(text))
    with pytest.raises(DataError, match="non-numeric"):
        io.load(tmp_path / "bad.csv")
    x_nan = x.copy()
    x_nan[7, 1] = np.nan
    np.savez(tmp_path / "nan.npz", t=t, x=x_nan)
    with pytest.raises(DataError, match=r"row 7, column 1"):
        io.load(tmp_path / "nan.npz")
    np.savez(tmp_path / "back.npz", t=t[::-1], x=x)
    with pytest.raises(DataError, match="increasing"):
        io.load(tmp_path / "back.npz")


def _touch(path):
    path.write_text("1,2\n")
    return path


# ------------------------------------------------------------ CSV as files come

def test_csv_with_bom_quoted_names_and_an_empty_trailing_column(tmp_path):
    path = tmp_path / "d.csv"
    path.write_bytes('\ufeff"t","a","b",\n0,1,2,\n0.5,3,4,\n'.encode())
    d = io.load(path)
    assert d.state_names == ["a", "b"]  # the byte order mark did not hide the time column
    np.testing.assert_array_equal(d.t, [0.0, 0.5])
    np.testing.assert_array_equal(d.x, [[1, 2], [3, 4]])


def test_a_column_filled_in_the_first_row_only_is_read_only_when_asked_for(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text('"u","y","Ts",\n1,2,4,\n3,4,,\n5,6,,\n')
    d = io.load(path, states=["y"], inputs=["u"], time=None)
    np.testing.assert_array_equal(d.x[:, 0], [2, 4, 6])
    np.testing.assert_array_equal(d.u[:, 0], [1, 3, 5])
    with pytest.raises(DataError, match=r"line 3, column 'Ts': an empty cell"):
        io.load(path)


@pytest.mark.parametrize("text, match", [
    ("t,a,a\n0,1,2\n", r"names \['a'\] more than once"),
    ("t,,a\n0,1,2\n", "header column 2 has no name"),
    ("t,a\n0,1\n1,2,3\n", r"line 3: 3 cells, more than the header's 2"),
    ("t,a,b\n0,1,2\n1,2\n", r"line 3: 2 cells; the header has 3"),
    ("t,a\n0,1\n1,x\n", r"line 3, column 'a': non-numeric value 'x'"),
    ("\n\n", "empty"),
    ("t,a\n", "no data rows"),
])
def test_malformed_csv_files_are_refused_with_the_line_and_column(tmp_path, text, match):
    path = tmp_path / "d.csv"
    path.write_text(text)
    with pytest.raises(DataError, match=match):
        io.load(path)


@pytest.mark.parametrize("folder, name, columns", [
    ("cascaded_tanks", "dataBenchmark.csv", ["uEst", "uVal", "yEst", "yVal"]),
    ("silverbox", "SNLS80mV.csv", ["V1", "V2"])])
def test_the_benchmark_files_load_as_they_are(folder, name, columns):
    path = Path(__file__).parents[1] / "paper/src/discrepancy_paper/data" / folder / name
    d = io.load(path, states=columns, time=None)
    truth = np.genfromtxt(path, delimiter=",", skip_header=1, usecols=range(len(columns)))
    np.testing.assert_array_equal(d.x, truth)


class _CountingName(str):
    """A column name that counts its comparisons (to measure the lookup's work)."""

    comparisons = 0

    def __eq__(self, other):
        type(self).comparisons += 1
        return str.__eq__(self, other)

    __hash__ = str.__hash__

    def strip(self, *chars):
        return _CountingName(str.strip(self, *chars))


@pytest.mark.parametrize("width", [500, 4000])
def test_csv_column_lookup_is_linear_in_the_number_of_columns(tmp_path, monkeypatch, width):
    """Loading a wide CSV compares names O(columns) times, not O(columns^2): with 4000
    columns a list lookup per column would make ~8 million comparisons."""
    import csv as csv_module
    import types

    from discrepancy.data import csv_table

    class reader:  # noqa: N801 (stands in for csv.reader)
        def __init__(self, fh):
            self._rows = csv_module.reader(fh)

        def __iter__(self):
            return self

        def __next__(self):
            return [_CountingName(cell) for cell in next(self._rows)]

        @property
        def line_num(self):
            return self._rows.line_num

    monkeypatch.setattr(csv_table, "csv", types.SimpleNamespace(reader=reader,
                                                                Error=csv_module.Error))
    names = [f"c{j}" for j in range(width)]
    path = tmp_path / "wide.csv"
    path.write_text(",".join(["t", *names]) + "\n" + ",".join(["0"] * (width + 1)) + "\n"
                    + ",".join(["1"] * (width + 1)) + "\n")
    _CountingName.comparisons = 0
    data = io.load(path, inputs=names[:width // 2])
    assert data.x.shape == (2, width - width // 2) and data.u.shape == (2, width // 2)
    np.testing.assert_array_equal(data.t, [0.0, 1.0])
    assert _CountingName.comparisons <= 4 * width
