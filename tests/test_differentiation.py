"""Differentiation methods against analytic derivatives, convergence orders and the registry."""
from __future__ import annotations

import numpy as np
import pytest

import discrepancy as dc
from discrepancy.differentiation import available_methods, get_differentiation_method
from discrepancy.errors import DataError, ParameterError, ShapeError, UnknownNameError


def signals(t):
    """Three test signals and their exact derivatives: sin(3t), t^3 - t, exp(t/2)."""
    x = np.column_stack([np.sin(3 * t), t**3 - t, np.exp(0.5 * t)])
    x_dot = np.column_stack([3 * np.cos(3 * t), 3 * t**2 - 1, 0.5 * np.exp(0.5 * t)])
    return x, x_dot


def uniform(dt, end=2.0):
    return np.arange(int(round(end / dt)) + 1) * dt


# (method, max abs error over all samples, max abs error away from the ends, samples cut per end)
# Signals have derivatives of size ~3; dt = 0.01.
CASES = {
    "finite_difference": (dc.FiniteDifference(), 2e-3, 1e-3, 0),
    "savitzky_golay": (dc.SavitzkyGolay(window_length=11, polyorder=3), 1e-3, 1e-5, 5),
    "spline": (dc.Spline(s=0.0), 1e-4, 1e-5, 10),
    # global smoothers are biased near the ends; judge them in the interior
    "trend_filtered": (dc.TrendFiltered(order=2, alpha=1e-8), None, 2e-2, 10),
    "kalman": (dc.Kalman(alpha=1e-9), 0.1, 1e-5, 10),
    # natural end conditions (zero curvature) bend the ends: judge the interior
    "smoothing_spline": (dc.SmoothingSpline(), None, 2e-3, 10),
}


def test_every_registered_method_is_tested():
    # Dequantised needs quantised data (tests/test_dequantise.py); auto: tests/test_auto.py
    # spectral: tests/test_pysindy_parity.py (periodic data), weak: tests/test_weak.py
    assert set(available_methods()) == set(CASES) | {"dequantised", "auto", "weak", "spectral"}


@pytest.mark.parametrize("name", sorted(CASES))
def test_analytic_derivatives(name):
    method, tol_all, tol_interior, cut = CASES[name]
    t = uniform(0.01)
    x, exact = signals(t)
    x_smooth, x_dot = method.smooth_and_differentiate(x, t)
    assert x_dot.shape == x.shape and x_smooth.shape == x.shape
    assert x_dot.dtype == np.float64
    err = np.abs(x_dot - exact)
    if tol_all is not None:
        assert err.max() < tol_all
    inner = slice(cut, len(t) - cut) if cut else slice(None)
    assert err[inner].max() < tol_interior
    # on noise-free data smoothing must not move x visibly
    assert np.max(np.abs(x_smooth - x)[inner]) < 1e-3


@pytest.mark.parametrize("name", ["finite_difference", "savitzky_golay", "spline"])
def test_registry_name_gives_the_same_answer_as_the_instance(name):
    method = CASES[name][0]
    kwargs = {k: v for k, v in vars(method).items() if not k.startswith("_")}
    by_name = get_differentiation_method(name, **kwargs)
    assert type(by_name) is type(method)
    t = uniform(0.01)
    x, _ = signals(t)
    np.testing.assert_array_equal(by_name(x, t), method(x, t))


def test_columns_are_differentiated_independently():
    t = uniform(0.01)
    x, _ = signals(t)
    method = dc.SavitzkyGolay(window_length=15, polyorder=3)
    together = method(x, t)
    for j in range(x.shape[1]):
        alone = method(x[:, [j]], t)
        np.testing.assert_allclose(together[:, [j]], alone, rtol=1e-12, atol=1e-12)


def _max_error(method, dt, interior=0):
    t = uniform(dt)
    x, exact = signals(t)
    err = np.abs(method(x, t) - exact)
    k = int(round(interior / dt))
    return err[k:len(t) - k].max() if k else err.max()


def _orders(method, dts, interior=0.0):
    errors = [_max_error(method, dt, interior) for dt in dts]
    return np.log2(np.array(errors[:-1]) / np.array(errors[1:]))


def test_finite_difference_converges_at_second_order():
    orders = _orders(dc.FiniteDifference(), [0.02, 0.01, 0.005, 0.0025])
    assert np.all((orders > 1.9) & (orders < 2.1)), orders


def test_finite_difference_is_exact_on_quadratics_and_its_error_on_a_cubic_is_h2():
    t = uniform(0.05)
    x = np.column_stack([1 + 2 * t - 3 * t**2, t**3])
    x_dot = dc.FiniteDifference()(x, t)
    np.testing.assert_allclose(x_dot[:, 0], 2 - 6 * t, atol=1e-11)
    # centred difference of t^3: 3 t^2 + h^2 exactly (interior)
    np.testing.assert_allclose(x_dot[1:-1, 1], 3 * t[1:-1] ** 2 + 0.05**2, atol=1e-11)


@pytest.mark.parametrize("polyorder, expected", [(3, 4.0), (2, 2.0)])
def test_savitzky_golay_interior_order_on_smooth_data(polyorder, expected):
    # a fixed window in samples shrinks with dt: the derivative filter of a centred
    # window of polyorder p (p odd) or p - 1 (p even) has error O(h^(p+1)) resp. O(h^p)
    method = dc.SavitzkyGolay(window_length=11, polyorder=polyorder)
    orders = _orders(method, [0.02, 0.01, 0.005], interior=0.2)
    assert np.all(np.abs(orders - expected) < 0.3), orders


def test_savitzky_golay_exact_for_polynomials_up_to_polyorder():
    t = uniform(0.01, end=1.0)
    x = np.column_stack([t**3 - 2 * t**2 + t - 5, 4 * t])
    x_smooth, x_dot = dc.SavitzkyGolay(window_length=21, polyorder=3).smooth_and_differentiate(x, t)
    np.testing.assert_allclose(x_smooth, x, atol=1e-10)
    np.testing.assert_allclose(x_dot[:, 0], 3 * t**2 - 4 * t + 1, atol=1e-8)
    np.testing.assert_allclose(x_dot[:, 1], 4.0, atol=1e-9)


def test_savitzky_golay_smooths_noise_and_smooth_false_keeps_x(rng):
    t = uniform(0.01, end=5.0)
    clean, exact = signals(t)
    noisy = clean + 0.01 * rng.normal(size=clean.shape)
    sg = dc.SavitzkyGolay(window_length=21, polyorder=3)
    x_smooth, x_dot = sg.smooth_and_differentiate(noisy, t)
    # a 21-point cubic filter removes most of the white noise
    assert np.std(x_smooth - clean) < 0.5 * 0.01
    raw = dc.SavitzkyGolay(window_length=21, polyorder=3, smooth=False)
    x_raw, x_dot_raw = raw.smooth_and_differentiate(noisy, t)
    np.testing.assert_array_equal(x_raw, noisy)
    np.testing.assert_array_equal(x_dot_raw, x_dot)
    # and its derivative beats finite differences on the same noisy data by far
    fd = dc.FiniteDifference()(noisy, t)
    assert np.sqrt(np.mean((x_dot - exact) ** 2)) < 0.2 * np.sqrt(np.mean((fd - exact) ** 2))


def _nonuniform_times(rng, m=401, end=2.0):
    h = end / (m - 1)
    t = np.arange(m) * h
    t[1:-1] += rng.uniform(-0.3, 0.3, m - 2) * h
    return t


def test_finite_difference_accepts_nonuniform_t_with_second_order_accuracy(rng):
    errors = []
    for m in (201, 401, 801):
        t = _nonuniform_times(rng, m)
        x, exact = signals(t)
        errors.append(np.abs(dc.FiniteDifference()(x, t) - exact).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] < 1e-3
    assert np.all(orders > 1.6), orders


def test_spline_accepts_nonuniform_t(rng):
    t = _nonuniform_times(rng)
    x, exact = signals(t)
    x_dot = dc.Spline(s=0.0)(x, t)
    assert np.abs(x_dot - exact)[10:-10].max() < 1e-4


@pytest.mark.parametrize("method", [dc.SavitzkyGolay(window_length=11, polyorder=3),
                                    dc.TrendFiltered(order=1, alpha=1e-4)],
                         ids=["savitzky_golay", "trend_filtered"])
def test_uniform_only_methods_refuse_nonuniform_t(method, rng):
    t = _nonuniform_times(rng)
    x, _ = signals(t)
    with pytest.raises(DataError, match="uniform"):
        method(x, t)


@pytest.mark.parametrize("method, m", [(dc.SavitzkyGolay(window_length=21, polyorder=3), 20),
                                       (dc.SavitzkyGolay(window_length=21, polyorder=3), 5),
                                       (dc.FiniteDifference(), 2),
                                       (dc.Spline(order=3), 4)])
def test_trajectory_shorter_than_window(method, m):
    t = np.arange(m) * 0.01
    with pytest.raises(ShapeError, match=f"{m} samples"):
        method(np.ones((m, 2)), t)


def test_trajectory_exactly_as_long_as_the_window_is_accepted():
    t = uniform(0.01, end=0.2)  # 21 samples
    x = np.column_stack([t**2])
    x_dot = dc.SavitzkyGolay(window_length=21, polyorder=3)(x, t)
    np.testing.assert_allclose(x_dot[:, 0], 2 * t, atol=1e-9)


def test_unknown_method_name_lists_the_valid_names():
    with pytest.raises(UnknownNameError) as info:
        get_differentiation_method("savgol")
    message = str(info.value)
    assert "savgol" in message
    for name in ("finite_difference", "savitzky_golay", "spline", "trend_filtered", "kalman"):
        assert name in message


def test_default_is_chosen_from_the_data():
    assert isinstance(get_differentiation_method(None), dc.AutoSmoothing)


@pytest.mark.parametrize("kwargs", [dict(window_length=10), dict(window_length=1),
                                    dict(window_length=11, polyorder=11),
                                    dict(window_length=11, polyorder=0)])
def test_bad_savitzky_golay_parameters(kwargs):
    t = uniform(0.01)
    with pytest.raises(ParameterError):
        dc.SavitzkyGolay(**kwargs)(signals(t)[0], t)


def test_kalman_refuses_very_long_trajectories():
    t = np.arange(dc.Kalman.max_samples + 1) * 0.01
    with pytest.raises(ParameterError, match="SavitzkyGolay"):
        dc.Kalman()(np.zeros((t.size, 1)), t)


def test_shape_mismatch_between_x_and_t():
    with pytest.raises(ShapeError, match="t"):
        dc.FiniteDifference()(np.zeros((10, 2)), np.arange(9.0))


@pytest.mark.parametrize("method", [dc.FiniteDifference(),
                                    dc.SavitzkyGolay(window_length=11, polyorder=3),
                                    dc.SavitzkyGolay(window_length=21, polyorder=2)],
                         ids=["finite_difference", "sg11", "sg21"])
def test_halo_lets_chunks_reproduce_the_whole_derivative(method, rng):
    """A chunk padded by ``halo`` samples on each side gives the global answer inside it."""
    t = uniform(0.01, end=4.0)
    x = signals(t)[0] + 0.01 * rng.normal(size=(len(t), 3))
    smooth, whole = method.smooth_and_differentiate(x, t)
    h = method.halo
    for a, b in [(h, 60), (100, 137), (250, len(t) - h)]:
        s, d = method.smooth_and_differentiate(x[a - h:b + h], t[a - h:b + h])
        np.testing.assert_allclose(d[h:h + b - a], whole[a:b], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(s[h:h + b - a], smooth[a:b], rtol=1e-10, atol=1e-12)


def test_coarse_sampling_is_warned_about_for_the_method_that_suffers():
    """10 samples per period: central differences are 6 % slow there, so the fit warns and
    names the states; the automatic degree-7 smoother and the spectral derivative are
    accurate at that sampling and are not warned about."""
    import warnings

    from discrepancy.errors import CoarseSamplingWarning

    t = np.arange(2000) * 0.1
    x = np.c_[np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)]
    with pytest.warns(CoarseSamplingWarning, match=r"x2 is sampled at about 10\.0 samples"):
        dc.DiscrepancyModel(differentiation_method=dc.FiniteDifference()).fit(x, t=t)
    for method in (None, dc.Spectral()):
        with warnings.catch_warnings():
            warnings.simplefilter("error", CoarseSamplingWarning)
            dc.DiscrepancyModel(differentiation_method=method).fit(x, t=t)


@pytest.mark.parametrize("window, polyorder", [(9, 3), (31, 5), (101, 5), (201, 7)])
@pytest.mark.parametrize("deriv", [0, 1])
def test_savgol_of_columns_equals_savgol_of_each_column(window, polyorder, deriv):
    """The 2-D path (one set of weights for every column, as the PDE time derivative uses
    for every grid point) gives the 1-D filter's numbers column by column."""
    from discrepancy.differentiation.savgol import savgol

    x = np.random.default_rng(0).normal(size=(500, 7)).cumsum(axis=0)
    together = savgol(x, window, polyorder, deriv=deriv, delta=0.01)
    alone = np.column_stack([savgol(x[:, j], window, polyorder, deriv=deriv, delta=0.01)
                             for j in range(x.shape[1])])
    np.testing.assert_allclose(together, alone, rtol=0, atol=1e-13 * np.abs(alone).max())
