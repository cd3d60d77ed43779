"""The weak form for fields: integration by parts (symbolic and numeric) against analytic
fields, and Hermite de-biasing against the noise's known moments."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.pde.divergence import Jet, divergence_form
from discrepancy.pde.weak import bump, integrate_space, integrate_time, unbiased
from discrepancy.symbolic import symbol

JET = Jet(["u", "v"], ["x", "y"])
S = {n: symbol(n) for n in "u v u_x u_y u_xx u_xy u_yy u_xxx u_xxxx v_x v_xx".split()}


def total(beta, h):
    for axis, k in enumerate(beta):
        for _ in range(k):
            h = JET.total_derivative(h, axis)
    return h


@pytest.mark.parametrize("expr", [
    S["u_xxxx"], S["u"] * S["u_x"], S["u"] ** 2 * S["u_x"], S["u"] * S["u_xx"],
    S["u_x"] * S["u_xx"], S["u"] * S["u_xxx"], S["v"] * S["u_xx"], S["u"] * S["v_x"],
    S["u_xy"], S["u"] * S["u_yy"] + S["u_x"] * S["u_y"], 3 * S["u"] ** 3 * S["u_xx"],
    S["u"] ** 2 + S["v"], sp.Integer(2)])
def test_divergence_form_is_an_identity(expr):
    form = divergence_form(expr, JET)
    assert sp.expand(sum(total(b, h) for b, h in form.items()) - expr) == 0


@pytest.mark.parametrize("expr, lowest", [
    (S["u_xxxx"], 0), (S["u"] * S["u_x"], 0), (S["u"] ** 2 * S["u_x"], 0),
    (S["u"] * S["u_xx"], 1), (S["u"] * S["u_xxx"], 1), (S["u_xy"], 0)])
def test_divergence_form_moves_derivatives_onto_the_test_function(expr, lowest):
    form = divergence_form(expr, JET)
    assert max(JET.order(h) for h in form.values()) == lowest


def analytic(t, x):
    """u = (1 + sin t / 2) sin x + cos(2x) / 3 + 1 and its derivatives in t and x."""
    a = 1 + 0.5 * np.sin(t)[:, None]
    u = a * np.sin(x) + np.cos(2 * x) / 3 + 1
    ut = 0.5 * np.cos(t)[:, None] * np.sin(x) + 0 * x
    d = {1: a * np.cos(x) - 2 * np.sin(2 * x) / 3, 2: -a * np.sin(x) - 4 * np.cos(2 * x) / 3,
         3: -a * np.cos(x) + 8 * np.sin(2 * x) / 3, 4: a * np.sin(x) + 16 * np.cos(2 * x) / 3}
    return u, ut, d


def test_weak_rows_equal_direct_integrals_of_the_analytic_terms():
    x = np.linspace(0, 2 * np.pi, 96, endpoint=False)
    t = np.arange(120) * 0.05
    grid = dc.Grid(x, periodic=True)
    u, ut, d = analytic(t, x)
    u_, ux, uxx, uxxxx = symbol("u"), symbol("u_x"), symbol("u_xx"), symbol("u_xxxx")
    terms = [u_ * uxx, uxxxx, u_ ** 2 * ux, ux ** 2, u_ * symbol("u_xxx")]
    values = [u * d[2], d[4], u ** 2 * d[1], d[1] ** 2, u * d[3]]
    form = dc.FieldWeakForm([14, 20], power=10, noise_std=0)
    model = dc.PDEDiscrepancyModel(feature_library=dc.CustomLibrary(terms),
                                   differentiation_method=form)
    setup = model.make_setup(1, 0, grid)
    theta, y, signal = setup.rows(dc.data.fields.as_field_runs(u, t, grid)[0])
    index = np.arange(0, 96, 6)             # every sixth point (96 // 16 centres)

    def direct(values):
        space = integrate_space(values[..., None], 1, bump(20, 10, 0, x[1] - x[0]), index, True)
        return integrate_time(space, bump(14, 10, 0, t[1] - t[0])).ravel()

    time_of_row = np.repeat(np.arange(120), len(index))
    inside = (time_of_row >= 14) & (time_of_row < 120 - 14)   # the test function fits
    assert np.all(theta[~inside] == 0) and np.all(signal[~inside] == 0)
    for j, v in enumerate(values):
        exact = direct(v)
        assert np.max(np.abs(theta[inside, j] - exact[inside])) < 5e-6 * np.max(np.abs(exact))
    assert np.max(np.abs(signal[inside, 0] - direct(ut)[inside])) < 1e-6 * np.max(
        np.abs(direct(ut)))


def test_unbiased_monomials_have_the_right_mean_under_noise():
    rng = np.random.default_rng(0)
    u_, v_ = symbol("u"), symbol("v")
    h = 2 * u_ ** 3 * v_ ** 2 - u_ ** 2 + 4 * u_ * v_
    fixed = unbiased(h, {"u": 0.3, "v": 0.2})
    f = sp.lambdify([u_, v_], fixed)
    a, b = 0.7, -1.1
    noisy = f(a + 0.3 * rng.standard_normal(2_000_000), b + 0.2 * rng.standard_normal(2_000_000))
    assert np.mean(noisy) == pytest.approx(float(h.subs({u_: a, v_: b})), abs=5e-3)
    assert unbiased(u_ * symbol("u_x"), {"u": 0.3}) == u_ * symbol("u_x")  # left alone


def test_bump_derivatives_are_exact_derivatives():
    w, q, h = 20, 8, 0.1
    s_ = sp.Symbol("s")
    psi = (1 - (s_ / (w * h)) ** 2) ** q
    points = np.arange(-w, w + 1) * h
    for order in (0, 1, 2, 3):
        exact = sp.lambdify(s_, sp.diff(psi, s_, order))(points) * h   # times the step
        assert np.max(np.abs(bump(w, q, order, h) - exact)) < 1e-12 * np.max(np.abs(exact))
