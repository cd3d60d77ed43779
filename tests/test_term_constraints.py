"""Masks and linear constraints on coefficients, against constrained least squares solved
independently (scipy's bounded least squares on the explicit design matrix)."""
import numpy as np
import pytest
from scipy.optimize import lsq_linear

import discrepancy as dc
from discrepancy.errors import ConvergenceError, ParameterError, UnknownNameError
from discrepancy.optimizers.linear_constraints import LinearConstraints


@pytest.fixture(scope="module")
def data(vdp_data, helpers):
    x = vdp_data.x + 0.01 * np.random.default_rng(0).standard_normal(vdp_data.x.shape)
    return x, helpers.vdp_rhs(0.1)


def constrained(prior, constraints, **kw):
    return dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(3),
                               differentiation_method=dc.SavitzkyGolay(31, 3),
                               optimizer=dc.STLSQ(threshold=0.0, **kw), constraints=constraints)


def test_masked_kinematics_and_an_inequality_equal_bounded_least_squares(data):
    """x1' = x2 is exact (no correction), and the x2 coefficient of x2' may not exceed 0.3
    (the truth is 0.4, so the bound is active)."""
    x, prior = data
    rule = dc.Constraints(exact_equations=["x1"], at_most=[({("x2", "x2"): 1.0}, 0.3)])
    model = constrained(prior, rule).fit(x, t=0.01)
    names = model.get_feature_names()
    z, y = model.residual(dc.data.Trajectory(np.arange(len(x)) * 0.01, x))
    theta = model.feature_library_.transform(z)
    upper = np.full(theta.shape[1], np.inf)
    upper[names.index("x2")] = 0.3
    reference = lsq_linear(theta, y[:, 1], bounds=(-np.inf, upper), method="bvls",
                           tol=1e-14).x
    assert not model.coef_[0].any()
    np.testing.assert_allclose(model.coef_[1], reference, atol=1e-8)
    assert model.coef_[1, names.index("x2")] == pytest.approx(0.3, abs=1e-10)
    # through the chunked path too
    chunks = iter([x[i:i + 400] for i in range(0, len(x), 400)])
    streamed = constrained(prior, rule).fit(chunks, t=0.01)
    np.testing.assert_allclose(streamed.coef_, model.coef_, atol=1e-8)


def test_a_term_confined_to_one_equation_and_a_coupling_equality(data):
    x, prior = data
    rule = dc.Constraints(only={"x1^2 x2": ["x2"]},
                          equal=[({("x2", "x2"): 1.0, ("x2", "x1^2 x2"): 1.0}, 0.0)])
    model = constrained(prior, rule).fit(x, t=0.01)
    names = model.get_feature_names()
    a, b = names.index("x2"), names.index("x1^2 x2")
    assert model.coef_[0, b] == 0
    assert model.coef_[1, a] + model.coef_[1, b] == pytest.approx(0, abs=1e-10)
    assert model.coef_[1, a] == pytest.approx(0.4, rel=0.02)  # the truth satisfies it


def test_thresholding_never_drops_a_term_of_an_equality(data):
    x, prior = data
    rule = dc.Constraints(equal=[({("x2", "x1"): 1.0}, 0.0)])  # a term the truth lacks
    model = dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(3),
                                optimizer=dc.STLSQ(threshold=0.05), constraints=rule).fit(
        x, t=0.01)
    names = model.get_feature_names()
    assert abs(model.coef_[1, names.index("x1")]) < 1e-12  # held at 0 by the constraint
    assert set(np.flatnonzero(model.coef_[1])) == {names.index("x2"), names.index("x1^2 x2")}


def test_bad_constraints_are_named(data):
    x, prior = data
    with pytest.raises(UnknownNameError, match="'x9'"):
        constrained(prior, dc.Constraints(exact_equations=["x9"])).fit(x, t=0.01)
    with pytest.raises(UnknownNameError, match="term in at_most"):
        constrained(prior, dc.Constraints(at_most=[({("x2", "x7^9"): 1}, 0)])).fit(x, t=0.01)
    with pytest.raises(ParameterError, match="masks exclude"):
        constrained(prior, dc.Constraints(exact_equations=["x1"],
                                          equal=[({("x1", "x2"): 1}, 0)])).fit(x, t=0.01)
    with pytest.raises(ParameterError, match="optimizer that takes them"):
        dc.DiscrepancyModel(prior=prior, optimizer=dc.Lasso(),
                            constraints=dc.Constraints(exact_equations=["x1"])).fit(x, t=0.01)
    infeasible = dc.Constraints(at_most=[({("x2", "x2"): 1}, 0.1)],
                                at_least=[({("x2", "x2"): 1}, 0.2)])
    with pytest.raises(ConvergenceError, match="feasible"):
        constrained(prior, infeasible).fit(x, t=0.01)


def test_standalone_optimizer_takes_index_form_constraints():
    rng = np.random.default_rng(1)
    theta, xi = rng.standard_normal((500, 4)), np.array([1.0, -2.0, 0.0, 0.5])
    y = theta @ xi + 0.01 * rng.standard_normal(500)
    rule = LinearConstraints(1, 4, ub_lhs=np.array([[0.0, -1.0, 0.0, 0.0]]),
                             ub_rhs=np.array([1.5]))          # -ξ1 <= 1.5, i.e. ξ1 >= -1.5
    coef = dc.STLSQ(threshold=0.0, constraints=rule).fit(theta, y).coef_[0]
    reference = lsq_linear(theta, y, bounds=([-np.inf, -1.5, -np.inf, -np.inf], np.inf),
                           method="bvls", tol=1e-14).x
    np.testing.assert_allclose(coef, reference, atol=1e-9)


def test_a_coupled_inequality_equals_the_kkt_solution_in_memory_chunked_and_on_dask(data):
    """x2' may use x2 and x1^2 x2 with coef(x2) - coef(x1^2 x2) <= 0.7 (the truth has
    0.4 + 0.4 = 0.8, so the constraint is active): the answer is the equality-constrained
    least squares of the explicit design matrix (its KKT system solved with numpy), with a
    non-negative multiplier; the same through chunks and a dask array."""
    da = pytest.importorskip("dask.array")
    x, prior = data
    rule = dc.Constraints(exact_equations=["x1"],
                          at_most=[({("x2", "x2"): 1.0, ("x2", "x1^2 x2"): -1.0}, 0.7)])
    model = constrained(prior, rule).fit(x, t=0.01)
    names = model.get_feature_names()
    z, y = model.residual(dc.data.Trajectory(np.arange(len(x)) * 0.01, x))
    theta = model.feature_library_.transform(z)
    a = np.zeros(theta.shape[1])
    a[names.index("x2")], a[names.index("x1^2 x2")] = 1.0, -1.0
    free = np.linalg.lstsq(theta, y[:, 1], rcond=None)[0]
    assert a @ free > 0.7                                   # unconstrained: violated
    p = theta.shape[1]
    kkt = np.block([[theta.T @ theta, a[:, None]], [a[None, :], np.zeros((1, 1))]])
    solution = np.linalg.solve(kkt, np.r_[theta.T @ y[:, 1], 0.7])
    assert solution[p] > 0                                  # its multiplier: the bound binds
    np.testing.assert_allclose(model.coef_[1], solution[:p], atol=1e-8)
    chunks = iter([x[i:i + 333] for i in range(0, len(x), 333)])
    np.testing.assert_allclose(constrained(prior, rule).fit(chunks, t=0.01).coef_,
                               model.coef_, atol=1e-8)
    on_dask = constrained(prior, rule).fit(da.from_array(x, chunks=(500, 2)), t=0.01)
    np.testing.assert_allclose(on_dask.coef_, model.coef_, atol=1e-8)


def test_constraints_hold_with_the_automatic_threshold(data):
    """The default threshold='auto' chooses supports under the constraints: no correction in
    the kinematic equation, the bound respected, the true terms kept."""
    x, prior = data
    rule = dc.Constraints(exact_equations=["x1"], at_most=[({("x2", "x2"): 1.0}, 0.3)])
    model = dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(3),
                                constraints=rule).fit(x, t=0.01)
    names = model.get_feature_names()
    assert not model.coef_[0].any()
    assert model.coef_[1, names.index("x2")] <= 0.3 + 1e-10
    assert model.coef_[1, names.index("x2")] == pytest.approx(0.3, abs=1e-6)
    assert model.coef_[1, names.index("x1^2 x2")] < -0.3
