"""Fields streamed from disk (zarr, HDF5) in time chunks and fitted on Dask give the
in-memory statistics and model; a smaller version of benchmarks/bench_pde.py."""
import dask
import dask.array as da
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import MissingFileError, ParameterError, ShapeError, UnknownNameError
from discrepancy.symbolic import symbol

u, ux, uxx = (symbol(n) for n in ("u", "u_x", "u_xx"))
DT = 0.05


@pytest.fixture(scope="module")
def ks():
    """Burgers (nu = 0.1) on 64 points, 481 samples: several chunks of a long run."""
    x = np.linspace(-8, 8, 64, endpoint=False)
    grid = dc.Grid(x, periodic=True)
    truth = dc.PDEDiscrepancyModel.prior_only([-u * ux + 0.1 * uxx], grid)
    U = truth.simulate(np.exp(-(x + 2) ** 2) + 0.5 * np.exp(-(x - 3) ** 2),
                       np.arange(0, 24.0001, DT), rtol=1e-9)[..., 0]
    noisy = U + 0.02 * U.std() * np.random.default_rng(0).standard_normal(U.shape)
    return {"clean": U, "noisy": noisy}, grid


def model():
    return dc.PDEDiscrepancyModel(prior=[-u * ux + 0.05 * uxx])


@pytest.fixture(scope="module")
def in_memory(ks):
    """The in-memory fit of each field, the reference the streamed fits must equal (fitted
    once for the module; the tests only read it)."""
    data, grid = ks
    return {kind: model().fit(U, t=DT, grid=grid) for kind, U in data.items()}


def rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


def same(got, ref):
    assert got.statistics_.count == ref.statistics_.count
    assert rel(got.statistics_.gram, ref.statistics_.gram) < 1e-12
    for a, b in zip(got.statistics_.folds, ref.statistics_.folds, strict=True):
        assert rel(a.rhs, b.rhs) < 1e-10
    assert np.array_equal(got.coef_ != 0, ref.coef_ != 0)
    assert rel(got.coef_, ref.coef_) < 1e-10


@pytest.mark.parametrize("kind", ["clean", "noisy"])
def test_zarr_and_hdf5_in_time_chunks_equal_in_memory(ks, in_memory, kind, tmp_path):
    import h5py
    import zarr

    data, grid = ks
    U, ref = data[kind], in_memory[kind]
    assert ref.differentiation_choice_["form"] == ("pointwise" if kind == "clean" else "weak")
    names = ref.get_feature_names()
    assert {names[j] for j in np.flatnonzero(ref.coef_[0])} == {"u_xx"}
    store = zarr.open(str(tmp_path / "u.zarr"), mode="w", shape=U.shape, chunks=(50, 64),
                      dtype="f8")
    store[:] = U
    with h5py.File(tmp_path / "u.h5", "w") as f:
        f["fields/u"] = U
    for item in [(tmp_path / "u.zarr", ""), (tmp_path / "u.h5", "fields/u")]:
        if item[1] == "":
            item = (item[0], None)
        source = dc.FieldSource(item if item[1] else U, grid=grid, dt=DT, chunk_size=37)
        same(model().fit(source, grid=grid), ref)


def test_zarr_store_by_path(ks, in_memory, tmp_path):
    import zarr

    data, grid = ks
    U = data["noisy"]
    root = zarr.open_group(str(tmp_path / "g.zarr"), mode="w")
    root.create_array("u", shape=U.shape, chunks=(40, 64), dtype="f8")[:] = U
    got = model().fit(dc.FieldSource((tmp_path / "g.zarr", "u"), grid=grid, dt=DT,
                                     chunk_size=50), grid=grid)
    same(got, in_memory["noisy"])


def test_dask_threads_equal_in_memory(ks, in_memory):
    data, grid = ks
    for kind, U in data.items():
        ref = in_memory[kind]
        with dask.config.set(scheduler="threads"):
            got = model().fit(da.from_array(U, chunks=(61, 64)), t=DT, grid=grid)
        same(got, ref)
    runs = [data["noisy"][:200], data["noisy"][200:]]
    with dask.config.set(scheduler="threads"):
        got = model().fit([da.from_array(r, chunks=(45, 64)) for r in runs], t=DT, grid=grid)
    same(got, model().fit(runs, t=DT, grid=grid))


@pytest.mark.slow
def test_dask_local_cluster_equals_in_memory(ks, in_memory):
    distributed = pytest.importorskip("distributed")
    data, grid = ks
    U, ref = data["noisy"], in_memory["noisy"]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster):
        got = model().fit(da.from_array(U, chunks=(100, 64)), t=DT, grid=grid)
    same(got, ref)


def test_bad_sources_are_named(ks, tmp_path):
    import h5py

    data, grid = ks
    U = data["clean"]
    with pytest.raises(ShapeError, match="must be \\(time, 64"):
        dc.FieldSource(U[:, :60], grid=grid, dt=DT)
    with pytest.raises(MissingFileError, match="does not exist"):
        dc.FieldSource((tmp_path / "none.h5", "u"), grid=grid, dt=DT)
    with h5py.File(tmp_path / "a.h5", "w") as f:
        f["v"] = U
    with pytest.raises(UnknownNameError, match="no dataset 'u'"):
        dc.FieldSource((tmp_path / "a.h5", "u"), grid=grid, dt=DT)
    with pytest.raises(ShapeError, match="2 fields like the first"):
        dc.FieldSource([np.stack([U, U], -1), U], grid=grid, dt=DT)
    with pytest.raises(ParameterError, match="global method"):
        dc.PDEDiscrepancyModel(differentiation_method=dc.SmoothingSpline()).fit(
            dc.FieldSource(U, grid=grid, dt=DT), grid=grid)
    bad = np.concatenate([U, U])    # past the 512 snapshots the choices read first
    bad[781, 5] = np.nan
    with pytest.raises(dc.errors.DataError, match="run 0 snapshots 773..817.*time row 781"):
        model().fit(dc.FieldSource(bad, grid=grid, dt=DT, chunk_size=37), grid=grid)


CHILD = """
import sys, numpy as np, zarr
import discrepancy as dc
from discrepancy.symbolic import symbol
def rss(key):
    return next(int(l.split()[1]) for l in open('/proc/self/status') if l.startswith(key)) / 1024
x = np.linspace(0, 2 * np.pi, 512, endpoint=False)
grid = dc.Grid(x, periodic=True)
names = sorted(zarr.open_group(sys.argv[1], mode='r').array_keys())
source = dc.FieldSource([(sys.argv[1], n) for n in names], grid=grid, dt=0.005, chunk_size=100)
model = dc.PDEDiscrepancyModel(prior=[-symbol('u') * symbol('u_x')])
model.make_setup(1, 0, grid, sample=[source.read(0, 0, 400)])   # imports and plans, warmed
before = rss('VmRSS')
model.fit(source, grid=grid, progress=False)
print(rss('VmHWM') - before, model.equations(4)[0])
"""


@pytest.mark.slow
def test_streamed_fit_holds_a_fraction_of_the_field_in_memory(tmp_path):
    """160 MB of fields on disk; the streamed fit's peak memory grows by a fraction of it."""
    import subprocess
    import sys

    import zarr

    x = np.linspace(0, 2 * np.pi, 512, endpoint=False)
    t = np.arange(1000) * 0.005
    group = zarr.open_group(str(tmp_path / "f.zarr"), mode="w")
    rng = np.random.default_rng(0)
    for r in range(40):                  # exact viscous Burgers (Cole-Hopf), nu = 0.05
        k = np.arange(1, 6)
        b = rng.uniform(-1, 1, 5)
        b *= 0.8 / np.abs(b).sum()
        decay = np.exp(-0.05 * k ** 2 * t[:, None]) * b
        angle = k * x[:, None] + rng.uniform(0, 6, 5)
        u = 0.1 * (decay * k) @ np.sin(angle).T / (1 + decay @ np.cos(angle).T)
        group.create_array(f"run{r:02d}", shape=u.shape, dtype="f8")[:] = u
    out = subprocess.run([sys.executable, "-c", CHILD, str(tmp_path / "f.zarr")],
                         capture_output=True, text=True, check=True).stdout.split(maxsplit=1)
    grown, equation = float(out[0]), out[1].strip()
    assert equation == "prior + 0.0500 u_xx"
    assert grown < 0.25 * 40 * 1000 * 512 * 8 / 2 ** 20, grown
