"""Chunked fitting: equal to the in-memory fit, exact halos, bounded memory, clear errors."""
import tracemalloc

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import discrepancy as dc
from discrepancy.errors import DataError, ParameterError, ShapeError
from discrepancy.fitting.accumulate import BLOCK_ROWS, accumulate
from discrepancy.streaming import Chunk

DT = 1e-3
LORENZ = np.zeros((3, 10))  # degree-2 library columns: 1 x y z x² xy xz y² yz z²
LORENZ[0, [1, 2]] = -10, 10
LORENZ[1, [1, 2, 6]] = 28, -1, -1
LORENZ[2, [3, 5]] = -8 / 3, 1


def lorenz(x):
    return np.c_[10 * (x[:, 1] - x[:, 0]), x[:, 0] * (28 - x[:, 2]) - x[:, 1],
                 x[:, 0] * x[:, 1] - 8 / 3 * x[:, 2]]


@pytest.fixture(scope="module")
def lorenz_data():
    m = 100_000
    sol = solve_ivp(lambda t, x: lorenz(x[None])[0], (0, DT * (m - 1)), [-8, 7, 27],
                    t_eval=np.arange(m) * DT, rtol=1e-10, atol=1e-10)
    return sol.y.T


def model(diff=None, threshold=0.5):
    return dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=2),
                               optimizer=dc.STLSQ(threshold=threshold),
                               differentiation_method=diff)


def chunks(a, size=7777, *, ragged_start=False, seed=0, **extra):
    """Cut rows into chunks of ``size`` (and 1..40-row chunks near the start if ragged)."""
    rng = np.random.default_rng(seed)
    s = 0
    while s < a.shape[0]:
        k = int(rng.integers(1, 40)) if ragged_start and s < 400 else size
        parts = {name: v[s:s + k] for name, v in extra.items()}
        yield Chunk(a[s:s + k], **parts) if parts else a[s:s + k]
        s += k


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def test_blocked_accumulation_is_the_plain_sum_and_independent_of_threads():
    rng = np.random.default_rng(3)
    rows = 20 * BLOCK_ROWS + 123  # enough blocks for two threads
    z, y = rng.standard_normal((rows, 3)), rng.standard_normal((rows, 2))
    lib = dc.PolynomialLibrary(degree=3).fit(["a", "b", "c"])
    theta = lib.transform(z)
    one = accumulate(dc.GramStatistics(20, 2), lib.transform, z, y, n_threads=1)
    two = accumulate(dc.GramStatistics(20, 2), lib.transform, z, y, n_threads=2)
    assert np.array_equal(one.gram, two.gram) and np.array_equal(one.rhs, two.rhs)
    assert rel(one.gram, theta.T @ theta) < 1e-13
    assert rel(one.rhs, theta.T @ y) < 1e-13
    np.testing.assert_allclose(one.yy, (y ** 2).sum(axis=0), rtol=1e-13)
    assert one.count == z.shape[0]


def test_chunked_fit_with_x_dot_recovers_lorenz_and_equals_in_memory(lorenz_data):
    x = lorenz_data
    xd = lorenz(x)
    ref = model().fit(x, t=DT, x_dot=xd)
    got = model().fit(chunks(x, x_dot=xd), t=DT)
    np.testing.assert_allclose(ref.coefficients(), LORENZ, atol=1e-8)
    assert rel(got.coefficients(), ref.coefficients()) < 1e-10
    assert got.statistics_.count == x.shape[0]


@pytest.mark.parametrize("diff", [dc.FiniteDifference(),
                                  dc.SavitzkyGolay(window_length=21, polyorder=3)])
def test_derivatives_straddling_chunk_joins_are_exact(lorenz_data, diff):
    x = lorenz_data
    ref = model(diff).fit(x, t=DT)
    got = model(diff).fit(chunks(x, ragged_start=True), t=DT)
    # statistics built from exactly the same rows and derivatives as the whole trajectory
    assert rel(got.statistics_.gram, ref.statistics_.gram) < 1e-13
    assert rel(got.statistics_.rhs, ref.statistics_.rhs) < 1e-12
    assert rel(got.coefficients(), ref.coefficients()) < 1e-10
    np.testing.assert_allclose(got.coefficients(), LORENZ, atol=0.05)


def test_one_row_chunks_give_the_whole_trajectory_derivative(lorenz_data):
    x = lorenz_data[:300]
    diff = dc.SavitzkyGolay(window_length=11, polyorder=3)
    ref = model(diff, threshold=0.0).fit(x, t=DT)
    got = model(diff, threshold=0.0).fit(chunks(x, size=1), t=DT)
    assert rel(got.statistics_.rhs, ref.statistics_.rhs) < 1e-12


def test_several_trajectories_never_differentiated_across_joins(lorenz_data):
    a, b = lorenz_data[:40_000], lorenz_data[60_000:]
    ref = model(dc.FiniteDifference()).fit([a, b], t=DT)
    got = model(dc.FiniteDifference()).fit([chunks(a), chunks(b, size=5000)], t=DT)
    assert rel(got.statistics_.rhs, ref.statistics_.rhs) < 1e-12
    joined = model(dc.FiniteDifference()).fit(chunks(np.vstack([a, b])), t=DT)
    assert rel(joined.statistics_.rhs, ref.statistics_.rhs) > 1e-6  # the join would matter


def test_per_chunk_nonuniform_times_and_inputs():
    rng = np.random.default_rng(5)
    t = np.cumsum(rng.uniform(0.5e-3, 1.5e-3, 20_000))
    u = np.sin(3 * t)[:, None]
    x = np.c_[np.sin(t), np.cos(2 * t)] + 0.1 * u
    def m():
        return dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=2),
                                   optimizer=dc.STLSQ(threshold=0.0),
                                   differentiation_method=dc.FiniteDifference())
    ref = m().fit(x, t=t, u=u)
    got = m().fit(chunks(x, size=999, t=t, u=u))
    assert got.n_inputs_ == 1
    assert rel(got.statistics_.rhs, ref.statistics_.rhs) < 1e-12


def test_memory_is_bounded_by_the_chunk_not_the_data():
    def stream(rows, size=10_000):
        rng = np.random.default_rng(0)
        for _ in range(rows // size):
            x = rng.standard_normal((size, 3))
            yield Chunk(x, x_dot=x[:, ::-1].copy())

    def peak(rows):
        tracemalloc.start()
        model(threshold=0.0).fit(stream(rows))
        out = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        return out

    peak(20_000)  # imports and first-call caches are not the stream's memory
    small, large = peak(200_000), peak(1_600_000)  # x alone: 4.8 MB and 38.4 MB
    assert large < 1.25 * small, f"peak grew from {small / 1e6:.1f} to {large / 1e6:.1f} MB"
    assert large < 20e6


def test_global_differentiation_method_is_refused(lorenz_data):
    with pytest.raises(ParameterError, match="global"):
        model(dc.Spline()).fit(chunks(lorenz_data[:5000]), t=DT)


def test_chunk_with_other_column_count_names_the_chunk(lorenz_data):
    def stream():
        yield from chunks(lorenz_data[:20_000], size=5000)
        yield np.zeros((10, 4))

    with pytest.raises(ShapeError, match=r"chunk 4 of trajectory 0.*3 columns.*\(10, 4\)"):
        model().fit(stream(), t=DT)


def test_nan_far_into_the_stream_names_chunk_and_row(lorenz_data):
    x = lorenz_data.copy()
    x[93_330, 2] = np.nan  # chunk 12 (rows 93324..101100), row 6 of it
    with pytest.raises(DataError, match=r"chunk 12 of trajectory 0.*row 6 of the chunk "
                                        r"\(row 93330 of the trajectory, column 2\)"):
        model().fit(chunks(x), t=DT)


def test_times_must_keep_increasing_across_chunks():
    x = np.random.default_rng(0).standard_normal((100, 2))
    t = np.r_[np.arange(50), np.arange(50)] * 0.1
    with pytest.raises(DataError, match="strictly increasing \\(also across chunks\\)"):
        model().fit(chunks(x, size=50, t=t))


def test_u_and_x_dot_belong_in_the_chunks(lorenz_data):
    with pytest.raises(ParameterError, match="inside the chunks"):
        model().fit(chunks(lorenz_data), t=DT, x_dot=lorenz(lorenz_data))


def test_transform_into_a_buffer_equals_transform():
    rng = np.random.default_rng(2)
    z = rng.standard_normal((500, 2))
    poly = dc.PolynomialLibrary(degree=4).fit(["a", "b"])
    both = (dc.PolynomialLibrary(degree=2) + dc.FourierLibrary(n_frequencies=2)).fit(["a", "b"])
    for lib in (poly, both):
        buffer = np.empty((lib.n_features_, 500)).T  # Fortran order, as the accumulator uses
        assert np.array_equal(lib.transform(z, out=buffer), lib.transform(z))
        c_order = np.empty((500, lib.n_features_))
        assert np.array_equal(lib.transform(z, out=c_order), lib.transform(z))
    with pytest.raises(ShapeError, match="out must be float64 of shape"):
        poly.transform(z, out=np.empty((500, 3)))


def test_in_memory_fit_with_a_composite_library_matches_plain_least_squares():
    rng = np.random.default_rng(4)
    x = rng.uniform(-2, 2, (9000, 2))
    y = np.c_[0.7 * np.sin(x[:, 0]) - 0.3 * x[:, 1] ** 2, 1.5 * np.cos(2 * x[:, 1])]
    lib = dc.PolynomialLibrary(degree=2) + dc.FourierLibrary(n_frequencies=2)
    m = dc.DiscrepancyModel(feature_library=lib, optimizer=dc.STLSQ(threshold=0.0)).fit(
        x, x_dot=y)
    theta = m.feature_library_.transform(x)
    lstsq = np.linalg.lstsq(theta, y, rcond=None)[0].T
    np.testing.assert_allclose(m.coefficients(), lstsq, atol=1e-8)
    names = m.get_feature_names()
    assert abs(m.coefficients()[0, names.index("sin(x1)")] - 0.7) < 1e-8
