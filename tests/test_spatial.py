"""Spatial derivatives against analytic ones and PySINDy's on identical input."""
import numpy as np
import pysindy as ps
import pytest

import discrepancy as dc
from discrepancy.errors import ParameterError, ShapeError, UnknownNameError

L = 2 * np.pi
X = np.linspace(0, L, 64, endpoint=False)
H = X[1] - X[0]
F = np.exp(np.sin(X))
EXACT = {1: np.cos(X) * F, 2: (np.cos(X) ** 2 - np.sin(X)) * F,
         3: np.cos(X) * (np.cos(X) ** 2 - 3 * np.sin(X) - 1) * F}


@pytest.mark.parametrize("order", [1, 2, 3])
def test_spectral_is_exact_on_a_periodic_band_limited_field(order):
    got = dc.SpatialSpectral().derivative(F[None, :, None], 1, order, H, True)
    assert np.max(np.abs(got[0, :, 0] - EXACT[order])) < 1e-10 * 10 ** order


@pytest.mark.parametrize("accuracy, bound", [(2, 4e-2), (4, 2e-3), (6, 1e-4)])
def test_finite_differences_converge_at_their_order(accuracy, bound):
    fd = dc.SpatialFiniteDifference(accuracy)
    errors = []
    for n in (64, 128):
        x = np.linspace(0, L, n, endpoint=False)
        f = np.exp(np.sin(x))
        got = fd.derivative(f, 0, 2, x[1] - x[0], False)
        errors.append(np.max(np.abs(got - (np.cos(x) ** 2 - np.sin(x)) * f)[6:-6]))
    assert errors[0] < bound
    assert errors[0] / errors[1] == pytest.approx(2 ** accuracy, rel=0.3)  # the interior


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("order, d", [(2, 1), (2, 2), (4, 1), (4, 3), (3, 2), (2, 4)])
def test_finite_differences_equal_pysindy(order, d, periodic):
    u = np.random.default_rng(order * 10 + d).standard_normal((3, 40, 2))
    ours = dc.SpatialFiniteDifference(order).derivative(u, 1, d, 0.1, periodic)
    x = np.arange(40) * 0.1
    theirs = ps.FiniteDifference(order=order, d=d, axis=1, periodic=periodic)._differentiate(u, x)
    known = np.isfinite(theirs)  # PySINDy leaves a NaN at one end for odd orders, periodic
    assert known.mean() > 0.97 and np.all(np.isfinite(ours))
    assert np.max(np.abs(ours - theirs)[known]) < 1e-9 * np.max(np.abs(theirs[known]))


@pytest.mark.parametrize("d", [1, 2, 3, 4])
def test_spectral_equals_pysindy(d):
    u = np.exp(np.sin(X))[:, None] * np.ones((1, 3))
    ours = dc.SpatialSpectral().derivative(u, 0, d, H, True)
    theirs = ps.SpectralDerivative(d=d, axis=0)._differentiate(u, X)
    assert np.max(np.abs(ours - theirs)) < 1e-9 * np.max(np.abs(theirs))


def test_savitzky_golay_smooths_noise_that_differences_amplify():
    rng = np.random.default_rng(0)
    x = np.linspace(0, L, 400, endpoint=False)
    noisy = np.sin(x) + 0.01 * rng.standard_normal(400)
    sg = dc.SpatialSavitzkyGolay(41, 3).derivative(noisy, 0, 1, x[1] - x[0], True)
    fd = dc.SpatialFiniteDifference(2).derivative(noisy, 0, 1, x[1] - x[0], True)
    assert np.std(sg - np.cos(x)) < 0.1 * np.std(fd - np.cos(x))
    assert np.max(np.abs(sg - np.cos(x))) < 0.08


def test_savitzky_golay_ends_are_the_edge_polynomials_derivatives():
    x = np.linspace(0, 1, 30)
    p = 1 + 2 * x - 3 * x ** 2 + x ** 3
    got = dc.SpatialSavitzkyGolay(9, 3).derivative(p, 0, 1, x[1] - x[0], False)
    assert np.max(np.abs(got - (2 - 6 * x + 3 * x ** 2))) < 1e-9


def test_mixed_derivative_is_one_axis_after_the_other():
    from discrepancy.pde.variables import FieldVariables

    g = dc.Grid(X, X, periodic=True)
    a, b = g.mesh()
    u = (np.sin(a) * np.cos(2 * b))[None, ..., None]
    methods = (dc.SpatialSpectral(), dc.SpatialSpectral())
    v = FieldVariables(("u",), ("x", "y"), (), 2)
    jet = v.jet(u, None, g, methods)
    assert np.max(np.abs(jet[..., v.names.index("u_xy")][0]
                         + 2 * np.cos(a) * np.sin(2 * b))) < 1e-10


@pytest.mark.parametrize("make, args, error, words", [
    (lambda: dc.SpatialSpectral(), (F, 0, 1, H, False), ParameterError, "periodic axis"),
    (lambda: dc.SpatialSpectral(cutoff=0), (F, 0, 1, H, True), ParameterError, "cutoff"),
    (lambda: dc.SpatialSavitzkyGolay(9, 2), (F, 0, 3, H, True), ParameterError,
     "polyorder >= 3"),
    (lambda: dc.SpatialSavitzkyGolay(9, 9), (F, 0, 1, H, True), ParameterError, "below"),
    (lambda: dc.SpatialFiniteDifference(4), (F[:4], 0, 2, H, False), ShapeError,
     "at least 6 grid points"),
])
def test_bad_spatial_settings_are_named(make, args, error, words):
    with pytest.raises(error, match=words):
        make().derivative(*args)


def test_spatial_methods_come_from_their_registry():
    from discrepancy.differentiation.spatial import get_spatial_method

    assert isinstance(get_spatial_method("finite_difference(order=4)"),
                      dc.SpatialFiniteDifference)
    with pytest.raises(UnknownNameError, match="spectral"):
        get_spatial_method("fourier")
