"""The regression rows (fitting/rows.py): each form against an ODE or map whose answer is known."""
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.data.trajectory import Trajectory
from discrepancy.fitting.rows import DerivativeRows, NextSampleRows, WeakRows

T = np.linspace(0.0, 4.0, 401)
X = np.exp(-T)[:, None]          # x' = -x exactly


def setup_of(prior, **params):
    return dc.DiscrepancyModel(prior=prior, **params).make_setup(1, 0)


def test_pointwise_rows_are_the_derivative_minus_the_prior():
    setup = setup_of(lambda x, u: 0 * x, differentiation_method=dc.FiniteDifference())
    assert isinstance(setup.form, DerivativeRows)
    z, y, x_dot = setup.rows(Trajectory(T, X, None, None))
    np.testing.assert_allclose(z, X, rtol=0, atol=0)
    np.testing.assert_allclose(x_dot[1:-1], -X[1:-1], rtol=1e-3)   # second order: (dt^2/6) x'''
    np.testing.assert_array_equal(y, x_dot)                          # the prior is zero


def test_measured_derivatives_are_taken_as_given_and_the_prior_subtracted():
    setup = setup_of(lambda x, u: -0.5 * x, differentiation_method=dc.FiniteDifference())
    z, y, x_dot = setup.rows(Trajectory(T, X, None, -X))
    np.testing.assert_array_equal(x_dot, -X)
    np.testing.assert_allclose(y, -0.5 * X, rtol=1e-15)


def test_weak_rows_of_the_exact_prior_leave_no_residual():
    setup = setup_of(lambda x, u: -x, differentiation_method=dc.WeakForm(window_length=41),
                     feature_library=dc.PolynomialLibrary(degree=1))
    assert isinstance(setup.form, WeakRows) and setup.form.raw_origins
    theta, y, by_parts = setup.rows(Trajectory(T, X, None, None))
    assert theta.shape[1] == setup.n_features          # the rows are Θ already
    assert setup.transform(theta) is theta
    # by parts, ∫φ x' = -∫φ' x; with f_m = -x exact, the residual is quadrature error only
    assert np.max(np.abs(y)) < 1e-6 * np.max(np.abs(by_parts))


def test_next_sample_rows_pair_each_sample_with_its_successor():
    setup = dc.DiscrepancyModel(prior=lambda x, u: 0.9 * x, discrete_time=True).make_setup(1, 0)
    assert isinstance(setup.form, NextSampleRows) and setup.form.pre == 0
    z, y, x_next = setup.rows(Trajectory(np.arange(len(X)), X, None, None))
    np.testing.assert_array_equal(z, X[:-1])
    np.testing.assert_array_equal(x_next, X[1:])
    np.testing.assert_allclose(y, X[1:] - 0.9 * X[:-1], rtol=1e-15)


@pytest.mark.parametrize("window, halo", [(21, 10), (31, 15)])
def test_a_pointwise_forecast_keeps_the_smoothing_halo_before_its_origin(window, halo):
    setup = setup_of(None, differentiation_method=dc.SavitzkyGolay(window_length=window))
    assert setup.form.pre == halo and not setup.form.raw_origins
    assert setup.new_held_out().pre == halo
