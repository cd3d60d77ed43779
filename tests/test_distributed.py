"""Dask: the Gram reduction equals the in-memory fit, on threads and on a real cluster that
loses a worker in the middle of the fit."""
import os
import signal
import threading
import time

import dask
import dask.array as da
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.data.sources import NPZFiles
from discrepancy.distributed import fit_sources
from discrepancy.errors import ParameterError

DT = 1e-3


def lorenz(x):
    return np.c_[10 * (x[:, 1] - x[:, 0]), x[:, 0] * (28 - x[:, 2]) - x[:, 1],
                 x[:, 0] * x[:, 1] - 8 / 3 * x[:, 2]]


def trajectory(m, x0=(-8.0, 7.0, 27.0)):
    """Lorenz by RK4 at step DT (accurate enough that FD derivatives recover the system),
    stepped on one state vector: the same numbers, bit for bit, as :func:`lorenz` on
    ``(1, 3)`` rows, six times faster."""
    def f(s):
        return np.array([10 * (s[1] - s[0]), s[0] * (28 - s[2]) - s[1],
                         s[0] * s[1] - 8 / 3 * s[2]])

    x = np.empty((m, 3))
    x[0] = x0
    for i in range(m - 1):
        s = x[i]
        k1 = f(s)
        k2 = f(s + DT / 2 * k1)
        k3 = f(s + DT / 2 * k2)
        k4 = f(s + DT * k3)
        x[i + 1] = s + DT / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


@pytest.fixture(scope="module")
def x():
    return trajectory(20_000)


def model(diff=None, prior=None, threshold=0.5):
    return dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(degree=2),
                               optimizer=dc.STLSQ(threshold=threshold),
                               differentiation_method=diff)


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize("diff", [dc.FiniteDifference(), dc.SavitzkyGolay(window_length=15)])
def test_dask_array_fit_equals_in_memory(x, diff):
    ref = model(diff).fit(x, t=DT)
    with dask.config.set(scheduler="threads"):
        got = model(diff).fit(da.from_array(x, chunks=(1777, 3)), t=DT)
    assert got.statistics_.count == x.shape[0]
    assert rel(got.statistics_.gram, ref.statistics_.gram) < 1e-12
    assert rel(got.coefficients(), ref.coefficients()) < 1e-10
    assert ref.coefficients()[1, 6] == pytest.approx(-1.0, abs=1e-3)  # the x1 x3 term of Lorenz


@pytest.mark.parametrize("chunk", [500, 7])
def test_dask_blocks_shorter_than_a_window_equal_in_memory(x, chunk):
    """A last block of one row (2501 = 5 * 500 + 1) or every block shorter than the window:
    regrouped so every window is whole, the same statistics as in memory."""
    part = x[:2501]
    diff = dc.SavitzkyGolay(window_length=31)
    ref = model(diff).fit(part, t=DT)
    got = model(diff).fit(da.from_array(part, chunks=(chunk, 3)), t=DT)
    assert got.statistics_.count == part.shape[0]
    assert rel(got.statistics_.gram, ref.statistics_.gram) < 1e-12


def test_dask_list_of_trajectories_with_x_dot_and_inputs(x):
    u = np.sin(np.arange(x.shape[0]) * DT)[:, None]
    xd = lorenz(x) + 0.5 * u
    ref = model(threshold=0.1).fit([x[:9000], x[9000:]], t=DT, u=[u[:9000], u[9000:]],
                                   x_dot=[xd[:9000], xd[9000:]])
    got = model(threshold=0.1).fit([da.from_array(x[:9000], chunks=2000),
                                    da.from_array(x[9000:], chunks=3000)], t=DT,
                                   u=[u[:9000], u[9000:]], x_dot=[xd[:9000], xd[9000:]])
    assert rel(got.coefficients(), ref.coefficients()) < 1e-10
    assert got.get_feature_names() == ref.get_feature_names()


def test_global_method_refused_for_dask(x):
    with pytest.raises(ParameterError, match="global"):
        model(dc.Spline()).fit(da.from_array(x, chunks=5000), t=DT)


def test_one_task_per_file(tmp_path, x):
    for i, (a, b) in enumerate([(0, 7000), (7000, 13_000), (13_000, 20_000)]):
        np.savez(tmp_path / f"run{i}.npz", x=x[a:b])
    diff = dc.FiniteDifference()
    ref = model(diff).fit([x[:7000], x[7000:13_000], x[13_000:]], t=DT)
    with dask.config.set(scheduler="threads"):
        got = fit_sources(model(diff), [NPZFiles(p, chunk_size=999)
                                        for p in sorted(tmp_path.glob("*.npz"))], t=DT)
    assert rel(got.coefficients(), ref.coefficients()) < 1e-10
    assert got.statistics_.count == x.shape[0]


def make_slow_prior():
    """A legitimate but slow prior (no model: zeros), so the fit is still running when a
    worker is killed. A closure, so workers receive it by value."""
    def slow_prior(x, u):
        time.sleep(0.15)
        return np.zeros_like(x)
    return slow_prior


@pytest.mark.slow
def test_local_cluster_survives_a_killed_worker(x):
    distributed = pytest.importorskip("distributed")
    xd = lorenz(x)
    slow_prior = make_slow_prior()
    ref = model(prior=slow_prior).fit(x, t=DT, x_dot=xd)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        plain = model(prior=slow_prior).fit(da.from_array(x, chunks=1000), t=DT, x_dot=xd)
        assert rel(plain.coefficients(), ref.coefficients()) < 1e-10

        result, errors = {}, []

        def run():
            try:
                result["model"] = model(prior=slow_prior).fit(
                    da.from_array(x, chunks=500), t=DT, x_dot=xd)  # 40 blocks, ~3 s
            except Exception as e:  # pragma: no cover - reported below
                errors.append(e)

        worker = threading.Thread(target=run)
        worker.start()
        deadline = time.time() + 30
        while time.time() < deadline and not any(client.processing().values()):
            time.sleep(0.05)
        time.sleep(0.5)  # some blocks done, others running
        victim = sorted(client.scheduler_info()["workers"])[0]
        pids_before = client.run(os.getpid)
        os.kill(pids_before[victim], signal.SIGKILL)
        assert worker.is_alive(), "the fit finished before the worker was killed"
        worker.join(60)
        assert not errors, errors
        pids_after = client.run(os.getpid)
        assert set(pids_after.values()) != set(pids_before.values())  # a worker really died
        got = result["model"]
        assert got.statistics_.count == x.shape[0]  # no block lost or counted twice
        assert rel(got.statistics_.gram, plain.statistics_.gram) < 1e-13
        assert rel(got.coefficients(), ref.coefficients()) < 1e-10


def test_nan_in_a_dask_array_is_named_with_its_rows(x):
    bad = x.copy()
    bad[12_345, 2] = np.nan
    with pytest.raises(dc.errors.DataError,
                       match=r"dask array x\[0\].*: x must be finite; found nan at row "
                             r"\d+ of the chunk \(row 12345 of the trajectory, column 2\)"):
        model().fit(da.from_array(bad, chunks=4000), t=DT)


def test_dask_array_with_no_rows_is_refused():
    with pytest.raises(dc.errors.ShapeError, match="no rows"):
        model().fit(da.zeros((0, 3), chunks=10), t=DT)
