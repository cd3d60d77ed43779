"""Export: CasADi equals predict(), LaTeX holds the coefficients, numpy-only terms refuse."""
from __future__ import annotations

import re

import casadi as ca
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import ExportError
from discrepancy.symbolic import symbol

x1, x2, u = symbol("x1"), symbol("x2"), symbol("u")


def true_rhs(x, uu):
    """x1' = x2, x2' = -x1 + 0.35 x2 - 0.25 x1^2 x2 + 0.5 sin(x1) u + 0.125 exp(-x2^2) (exact)."""
    return np.column_stack([x[:, 1], -x[:, 0] + 0.35 * x[:, 1] - 0.25 * x[:, 0] ** 2 * x[:, 1]
                            + 0.5 * np.sin(x[:, 0]) * uu[:, 0] + 0.125 * np.exp(-x[:, 1] ** 2)])


PRIOR = [x2, -x1]


def prior_callable(x, uu):
    return np.column_stack([x[:, 1], -x[:, 0]])


def library():
    return (dc.PolynomialLibrary(degree=3, variables=["x1", "x2"])
            + dc.FourierLibrary(variables=["x1"]) * dc.PolynomialLibrary(
                degree=1, include_bias=False, variables=["u"])
            + dc.CustomLibrary(expressions=[sp.exp(-x2**2), sp.tanh(x1)]))


@pytest.fixture(scope="module")
def samples():
    rng = np.random.default_rng(11)
    return rng.uniform(-2, 2, size=(400, 2)), rng.uniform(-1, 1, size=(400, 1))


def fitted(prior, samples, lib=None):
    x, uu = samples
    model = dc.DiscrepancyModel(prior=prior, feature_library=lib or library(),
                                optimizer=dc.STLSQ(threshold=0.05))
    return model.fit(x, t=1.0, u=uu, x_dot=true_rhs(x, uu))


@pytest.fixture(scope="module")
def sympy_model(samples):
    return fitted(PRIOR, samples)


def evaluate(function, x, uu):
    """CasADi function evaluated row by row, ``(m, n)``."""
    return np.vstack([np.asarray(function(xi, ui)).ravel() for xi, ui in zip(x, uu, strict=True)])


def test_fit_is_exact(sympy_model):
    # the export tests below rely on these being the true coefficients
    exprs = sympy_model.feature_expressions_
    coef = dict(zip(exprs, sympy_model.coefficients()[1], strict=True))
    active = {k: v for k, v in coef.items() if v != 0}
    expected = {x2: 0.35, x1**2 * x2: -0.25, sp.sin(x1) * u: 0.5, sp.exp(-x2**2): 0.125}
    assert active.keys() == expected.keys()
    for e, v in expected.items():
        assert abs(active[e] - v) < 1e-9 * abs(v)
    assert not np.any(sympy_model.coefficients()[0])


def test_feature_names_of_negated_terms(sympy_model):
    names = sympy_model.get_feature_names()
    assert "exp(-x2^2)" in names


def test_to_casadi_equals_predict_at_random_states(sympy_model):
    f = sympy_model.to_casadi()
    assert isinstance(f, ca.Function)
    assert f.n_in() == 2 and f.n_out() == 1
    assert f.size_in(0) == (2, 1) and f.size_in(1) == (1, 1) and f.size_out(0) == (2, 1)
    rng = np.random.default_rng(5)
    x, uu = rng.uniform(-3, 3, size=(50, 2)), rng.uniform(-2, 2, size=(50, 1))
    got = evaluate(f, x, uu)
    np.testing.assert_allclose(got, sympy_model.predict(x, uu), rtol=1e-12, atol=1e-12)
    # independent truth: the hybrid is the true system
    np.testing.assert_allclose(got, true_rhs(x, uu), rtol=1e-8, atol=1e-8)


def test_to_casadi_default_refuses_a_callable_prior(samples):
    model = fitted(prior_callable, samples)
    with pytest.raises(ExportError, match="callable"):
        model.to_casadi()


def test_to_casadi_hybrid_of_a_callable_prior_refuses(samples):
    model = fitted(prior_callable, samples)
    with pytest.raises(ExportError, match="callable"):
        model.to_casadi(part="hybrid")


def test_to_casadi_discrepancy_part_with_a_callable_prior(samples):
    model = fitted(prior_callable, samples)
    g = model.to_casadi(part="discrepancy")
    rng = np.random.default_rng(6)
    x, uu = rng.uniform(-3, 3, size=(30, 2)), rng.uniform(-2, 2, size=(30, 1))
    np.testing.assert_allclose(evaluate(g, x, uu), model.discrepancy(x, uu), rtol=1e-12,
                               atol=1e-12)


def test_to_casadi_without_inputs_takes_only_x(vdp_data):
    model = dc.DiscrepancyModel(prior=[x2, sp.Rational(1, 10) * (1 - x1**2) * x2 - x1],
                                feature_library=dc.PolynomialLibrary(degree=3),
                                optimizer=dc.STLSQ(threshold=0.05))
    model.fit(vdp_data.x, t=vdp_data.dt, x_dot=vdp_data.x_dot)
    f = model.to_casadi()
    assert f.n_in() == 1
    x = np.random.default_rng(0).uniform(-2, 2, size=(20, 2))
    got = np.vstack([np.asarray(f(xi)).ravel() for xi in x])
    np.testing.assert_allclose(got, model.predict(x), rtol=1e-12, atol=1e-12)
    # CasADi can differentiate the exported model: its Jacobian is the true one
    xs = ca.SX.sym("x", 2)
    jac = ca.Function("J", [xs], [ca.jacobian(f(xs), xs)])
    a, b = 0.3, -0.7
    expected = [[0, 1], [-2 * 0.5 * a * b - 1, 0.5 * (1 - a**2)]]
    np.testing.assert_allclose(np.asarray(jac([a, b])), expected, atol=1e-9)


def test_numpy_only_term_in_an_active_position_refuses_casadi(samples):
    x, uu = samples
    lib = library() + dc.CustomLibrary(functions={"sawtooth": lambda v: v - np.floor(v)},
                                       variables=["x2"])

    def rhs(x, uu):
        return true_rhs(x, uu) + np.column_stack([0 * x[:, 0], 0.2 * (x[:, 1] - np.floor(x[:, 1]))])

    model = dc.DiscrepancyModel(prior=PRIOR, feature_library=lib,
                                optimizer=dc.STLSQ(threshold=0.05))
    model.fit(x, t=1.0, u=uu, x_dot=rhs(x, uu))
    assert "sawtooth(x2)" in model.equations()[1]
    with pytest.raises(ExportError, match=re.escape("sawtooth(x2)")):
        model.to_casadi()
    with pytest.raises(ExportError, match=re.escape("sawtooth(x2)")):
        model.to_casadi(part="discrepancy")


def test_inactive_numpy_only_term_does_not_block_export(samples):
    lib = library() + dc.CustomLibrary(functions={"sawtooth": lambda v: v - np.floor(v)},
                                       variables=["x2"])
    model = fitted(PRIOR, samples, lib)
    names = model.get_feature_names()
    assert model.coefficients()[:, names.index("sawtooth(x2)")].tolist() == [0.0, 0.0]
    f = model.to_casadi()
    x, uu = samples
    np.testing.assert_allclose(evaluate(f, x[:20], uu[:20]), model.predict(x[:20], uu[:20]),
                               rtol=1e-12, atol=1e-12)


def _latex_numbers(text):
    return [float(v) for v in re.findall(r"(?<![\w^{])\d+\.\d+", text)]


def test_to_latex_holds_the_coefficients(sympy_model):
    text = sympy_model.to_latex(precision=4)
    assert text.startswith("\\begin{aligned}") and text.rstrip().endswith("\\end{aligned}")
    lines = text.split("\\\\")
    assert len(lines) == 2
    assert r"\dot{x_{1}}" in lines[0] and r"\dot{x_{2}}" in lines[1]
    # first equation is the prior alone; second has the four fitted coefficients, rounded
    assert _latex_numbers(lines[0]) == []
    numbers = sorted(_latex_numbers(lines[1]))
    np.testing.assert_allclose(numbers, [0.125, 0.25, 0.35, 0.5], atol=1e-4)
    assert r"\sin" in lines[1] and "e^{- x_{2}^{2}}" in lines[1]


def test_to_latex_of_the_discrepancy_only(samples):
    model = fitted(prior_callable, samples)
    text = model.to_latex(precision=3)
    assert r"\delta \dot{x_{2}}" in text
    lines = text.split("\\\\")
    assert "&= 0" in lines[0]
    np.testing.assert_allclose(sorted(_latex_numbers(lines[1])), [0.125, 0.25, 0.35, 0.5],
                               atol=1e-3)


def test_to_sympy_of_a_callable_prior_model_is_the_discrepancy(samples):
    model = fitted(prior_callable, samples)
    g = model.to_sympy()
    expected = 0.35 * x2 - 0.25 * x1**2 * x2 + 0.5 * sp.sin(x1) * u + 0.125 * sp.exp(-x2**2)
    assert g[0] == 0
    difference = sp.expand(g[1] - expected)
    terms = sp.Add.make_args(difference) if difference != 0 else ()
    assert all(abs(float(t.as_coeff_Mul()[0])) < 1e-9 for t in terms), difference
    with pytest.raises(ExportError):
        model.to_sympy(part="hybrid")


def test_saturations_evaluate_store_and_export_exactly():
    """Min and Max (a sensor that saturates, an overflow) are exact terms: numpy, model
    files and CasADi agree with the definition on points on both sides of each kink."""
    import casadi as ca

    from discrepancy.symbolic import compile_numpy, from_data, to_casadi, to_data
    a, b = sp.symbols("a b", real=True)
    expr = sp.Min(a, 10) + 2 * sp.Max(a - b, 0, b)
    points = np.array([[12.0, 3.0], [4.0, 5.0], [-1.0, -2.0], [10.0, 10.0]])
    truth = np.minimum(points[:, 0], 10) + 2 * np.maximum.reduce(
        [points[:, 0] - points[:, 1], np.zeros(4), points[:, 1]])
    np.testing.assert_allclose(compile_numpy(expr, ["a", "b"])(points), truth)
    assert from_data(to_data(expr)) == expr
    z = ca.SX.sym("z", 2)
    f = ca.Function("f", [z], [to_casadi(expr, {"a": z[0], "b": z[1]})])
    np.testing.assert_allclose([float(f(p)) for p in points], truth)
