"""Chunk sources: files read piece by piece give the in-memory fit; bad files get clear errors."""
import h5py
import numpy as np
import pytest
import zarr

import discrepancy as dc
from discrepancy.data.sources import CSVFiles, HDF5Source, NPZFiles, ZarrSource
from discrepancy.errors import DataError, ShapeError, UnknownNameError

DT = 0.01
# y = A z² terms: x1' = 0.5 x2², x2' = -x1 x3, x3' = 1 + 0.25 x1  (degree-2 library columns)
TRUE = np.zeros((3, 10))
TRUE[0, 7] = 0.5
TRUE[1, 6] = -1.0
TRUE[2, [0, 1]] = 1.0, 0.25


def rhs(x):
    return np.c_[0.5 * x[:, 1] ** 2, -x[:, 0] * x[:, 2], 1 + 0.25 * x[:, 0]]


def model(diff=None, threshold=0.1):
    return dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=2),
                               optimizer=dc.STLSQ(threshold=threshold),
                               differentiation_method=diff)


@pytest.fixture(scope="module")
def data():
    t = np.arange(30_000) * DT
    x = np.c_[np.sin(0.7 * t), np.cos(0.3 * t) + 0.2 * np.sin(2.1 * t), np.sin(1.3 * t + 1)]
    return x, rhs(x)


@pytest.fixture(scope="module")
def files(tmp_path_factory, data):
    x, xd = data
    d = tmp_path_factory.mktemp("sources")
    with h5py.File(d / "run.h5", "w") as f:
        f["states/x"] = x
        f["states/xd"] = xd
    g = zarr.open_group(str(d / "run.zarr"), mode="w")
    g["x"], g["xd"] = x, xd
    (d / "npz").mkdir()
    (d / "csv").mkdir()
    for i, (a, b) in enumerate([(0, 12_000), (12_000, 30_000)]):
        np.savez(d / "npz" / f"part{i}.npz", x=x[a:b], xd=xd[a:b])
        np.savetxt(d / "csv" / f"part{i}.csv", np.c_[x[a:b], xd[a:b]], delimiter=",",
                   header="p,q,r,dp,dq,dr", comments="")
    return d


def test_hdf5_and_zarr_stream_to_the_in_memory_model(files, data):
    x, xd = data
    ref = model().fit(x, t=DT, x_dot=xd)
    np.testing.assert_allclose(ref.coefficients(), TRUE, atol=1e-9)
    for src in (HDF5Source(files / "run.h5", x="states/x", x_dot="states/xd", chunk_size=7777),
                ZarrSource(files / "run.zarr", x_dot="xd", chunk_size=7777)):
        assert src.n_samples == x.shape[0]
        got = model().fit(src, t=DT)
        np.testing.assert_allclose(got.coefficients(), ref.coefficients(), rtol=1e-10, atol=0)


def test_lengths_split_a_file_into_trajectories(files, data):
    x, _ = data
    diff = dc.SavitzkyGolay(window_length=9, polyorder=3)
    ref = model(diff, 0.0).fit([x[:10_000], x[10_000:]], t=DT)
    got = model(diff, 0.0).fit(ZarrSource(files / "run.zarr", chunk_size=3001,
                                     lengths=[10_000, 20_000]), t=DT)
    np.testing.assert_allclose(got.statistics_.rhs, ref.statistics_.rhs, rtol=1e-12, atol=1e-9)
    assert np.abs(got.coefficients() - ref.coefficients()).max() < \
        1e-10 * np.abs(ref.coefficients()).max()


def test_folders_of_npz_and_csv_as_one_trajectory_or_one_per_file(files, data):
    x, xd = data
    ref = model().fit(x, t=DT, x_dot=xd)
    npz = NPZFiles(files / "npz", x_dot="xd", chunk_size=5000, one_trajectory=True)
    csv = CSVFiles(files / "csv", x=["p", "q", "r"], x_dot=["dp", "dq", "dr"], chunk_size=5000)
    for src in (npz, csv):
        np.testing.assert_allclose(model().fit(src, t=DT).coefficients(), ref.coefficients(),
                                   rtol=1e-10, atol=0)
    # differentiated per file: the join between the files is not differentiated across
    fd = dc.FiniteDifference()
    per_file = model(fd, 0.0).fit(NPZFiles(files / "npz", chunk_size=4000), t=DT)
    in_memory = model(fd, 0.0).fit([x[:12_000], x[12_000:]], t=DT)
    np.testing.assert_allclose(per_file.statistics_.rhs, in_memory.statistics_.rhs, rtol=1e-12)


def test_wrong_dataset_name_lists_what_the_file_has(files):
    with pytest.raises(UnknownNameError, match=r"run.h5: no dataset 'x'.*states/x, states/xd"):
        HDF5Source(files / "run.h5")
    with pytest.raises(UnknownNameError, match=r"no dataset 'xdot'.*x, xd"):
        ZarrSource(files / "run.zarr", x_dot="xdot")
    with pytest.raises(UnknownNameError, match=r"part0.csv: no column 's'.*p, q, r"):
        model().fit(CSVFiles(files / "csv", x=["p", "s"]), t=DT)


def test_mismatched_rows_or_columns(tmp_path):
    with h5py.File(tmp_path / "bad.h5", "w") as f:
        f["x"] = np.zeros((100, 3))
        f["xd"] = np.zeros((90, 3))
    with pytest.raises(ShapeError, match=r"'xd' \(x_dot\) has shape \(90, 3\); expected 100 rows"):
        HDF5Source(tmp_path / "bad.h5", x_dot="xd")
    np.savez(tmp_path / "a.npz", x=np.ones((50, 3)))
    np.savez(tmp_path / "b.npz", x=np.ones((50, 2)))
    with pytest.raises(ShapeError, match=r"chunk 0 of trajectory 1 \(b.npz rows 0..49\)"):
        model().fit(NPZFiles(tmp_path), t=DT)


def test_nan_deep_in_a_file_names_the_rows(tmp_path, data):
    x, xd = data
    x = x.copy()
    x[25_001, 1] = np.nan
    with h5py.File(tmp_path / "nan.h5", "w") as f:
        f["x"], f["xd"] = x, xd
    with pytest.raises(DataError, match=r"nan.h5 rows 24000..27999.*row 1001 of the chunk "
                                        r"\(row 25001 of the trajectory, column 1\)"):
        model().fit(HDF5Source(tmp_path / "nan.h5", x_dot="xd", chunk_size=4000), t=DT)


def test_missing_file_or_empty_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        HDF5Source(tmp_path / "nope.h5")
    with pytest.raises(FileNotFoundError, match=r"no files matching '\*.npz'"):
        NPZFiles(tmp_path)


def test_streamed_csv_reads_files_as_benchmarks_write_them(tmp_path, data):
    """Quoted names, an empty trailing column and a byte order mark: the chunked reader
    gives the fit the same numbers as the in-memory one; a bad cell is named by line."""
    x, xd = data
    x, xd = x[:3000], xd[:3000]
    folder = tmp_path / "csv"
    folder.mkdir()
    lines = ['\ufeff"p","q","r","dp","dq","dr",'] + \
        [",".join(repr(float(v)) for v in row) + "," for row in np.c_[x, xd]]
    (folder / "a.csv").write_bytes("\n".join(lines).encode())
    streamed = model().fit(CSVFiles(folder, x=["p", "q", "r"], x_dot=["dp", "dq", "dr"],
                                    chunk_size=700), t=DT)
    in_memory = model().fit(x, t=DT, x_dot=xd)
    np.testing.assert_allclose(streamed.coefficients(), in_memory.coefficients(), rtol=1e-10)
    lines[1501] = lines[1501].replace(",", ",oops,", 1)
    (folder / "a.csv").write_bytes("\n".join(lines).encode())
    with pytest.raises(DataError, match="a.csv line 1502: 8 cells, more than"):
        model().fit(CSVFiles(folder, x=["p", "q", "r"], x_dot=["dp", "dq", "dr"],
                             chunk_size=700), t=DT)
