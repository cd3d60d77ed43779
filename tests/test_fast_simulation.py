"""Simulation with measured inputs: inputs between samples, and the compiled RK4 map against
the Python stepper and against an accurate solution with the true continuous input."""
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import discrepancy as dc
from discrepancy.errors import SimulationError
from discrepancy.hybrid.inputs import stage_inputs, upsample_bandlimited

DT = 0.05
FREQS = np.array([0.37, 1.1, 2.3, 4.1])      # Hz, all below the Nyquist frequency of 10 Hz


def smooth_input(t):
    """A band-limited input: a few sines, faded in over the first 5 s (a record's start
    leaves its reconstruction nothing to go on before it)."""
    t = np.asarray(t, dtype=float)
    fade = np.sin(np.pi / 2 * np.clip(t / 5.0, 0, 1)) ** 2
    return fade * np.sum(np.sin(2 * np.pi * FREQS[None, :] * t[:, None]
                                + np.arange(4)[None, :]), axis=1)


def duffing(x, u):
    return np.c_[x[:, 1], -x[:, 0] - 0.05 * x[:, 1] - 0.8 * x[:, 0] ** 3 + u[:, 0]]


def linear_prior(x, u):
    return np.c_[x[:, 1], -x[:, 0] - 0.05 * x[:, 1] + u[:, 0]]


@pytest.fixture(scope="module")
def model():
    """The hybrid model with the Duffing term, fitted on exact derivatives at the sampled
    states: the coefficients are exact whatever the states' integration error (rtol 1e-8 and
    1e-11 give the same coefficients to 1e-15), so the states need not be accurate."""
    t = np.arange(4001) * DT
    u = smooth_input(t)[:, None]
    sol = solve_ivp(lambda s, x: duffing(x[None], smooth_input([s])[:, None])[0],
                    (0, t[-1]), [0.2, 0.0], t_eval=t, rtol=1e-8, atol=1e-8)
    x = sol.y.T
    return dc.DiscrepancyModel(prior=linear_prior, feature_library=dc.PolynomialLibrary(3),
                               optimizer=dc.STLSQ(threshold=0.05)).fit(
        x, t=t, u=u, x_dot=duffing(x, u))


def test_stage_inputs_of_each_hold():
    t = np.arange(6) * DT
    u = np.c_[np.arange(6.0) ** 2, -np.arange(6.0)]
    linear = stage_inputs(u, t, 2, 2, hold="linear")
    assert linear.shape == (5, 5, 2)
    np.testing.assert_allclose(linear[2, :, 0], [4, 5.25, 6.5, 7.75, 9])
    zoh = stage_inputs(u, t, 2, 2, hold="zoh")
    np.testing.assert_array_equal(zoh[2, :, 1], [-2] * 5)   # held through the interval's end


def test_bandlimited_reconstruction_recovers_a_bandlimited_signal_between_samples():
    t = np.arange(801) * DT
    fine = upsample_bandlimited(smooth_input(t)[:, None], 8)[:, 0]
    t_fine = np.linspace(t[0], t[-1], len(fine))
    truth = smooth_input(t_fine)
    interior = slice(40 * 8, -40 * 8)        # the last 40 samples: the record's end
    error = np.abs(fine - truth)[interior].max()
    linear = np.abs(np.interp(t_fine, t, smooth_input(t)) - truth)[interior].max()
    assert error < 0.002 * linear            # far better than straight lines
    np.testing.assert_allclose(fine[::8], smooth_input(t), atol=1e-9)  # through the samples


@pytest.mark.parametrize("hold", ["linear", "zoh", "bandlimited"])
def test_compiled_steps_equal_python_steps(model, hold):
    t = np.arange(1001) * DT
    u = smooth_input(t)[:, None]
    fast = model.simulate([0.3, -0.1], t, u=u, method="rk4", substeps=2, u_hold=hold)
    slow = model.simulate([0.3, -0.1], t, u=u, method="rk4", substeps=2, u_hold=hold,
                          compiled=False)
    np.testing.assert_allclose(fast, slow, rtol=1e-11, atol=1e-11)


def test_bandlimited_input_simulates_the_true_system_best(model):
    """Against the true system driven by the true continuous input: the band-limited hold is
    the most accurate (away from the record's end, where the input's future is unknown)."""
    t = np.arange(2001) * DT
    # rtol 1e-9: the errors compared are 2.5e-5 and more (the same to 4 digits at 1e-11)
    truth = solve_ivp(lambda s, x: duffing(x[None], smooth_input([s])[:, None])[0],
                      (0, t[-1]), [0.3, -0.1], t_eval=t, rtol=1e-9, atol=1e-9).y.T
    u = smooth_input(t)[:, None]
    errors = {hold: np.abs(model.simulate([0.3, -0.1], t, u=u, method="rk4", substeps=4,
                                          u_hold=hold) - truth)[:1500].max()
              for hold in ("bandlimited", "linear", "zoh")}   # not the record's last 25 s
    assert errors["bandlimited"] < 0.01 * errors["linear"] < errors["zoh"]


def test_sympy_prior_and_untraceable_prior_give_the_same_numbers(model):
    """The same hybrid model with its prior as sympy expressions (compiled exactly) and as a
    callable that branches on values (cannot be traced, so stepped in Python)."""
    x1, x2, u1 = sp.symbols("x1 x2 u", real=True)
    t = np.arange(1001) * DT
    u = smooth_input(t)[:, None]
    x = np.c_[np.sin(t), np.cos(1.3 * t)]
    reference = model.simulate([0.3, -0.1], t, u=u, method="rk4")
    for prior in ([x2, -x1 - 0.05 * x2 + u1],
                  lambda x, u: np.where(np.isfinite(x), linear_prior(x, u), 0.0)):
        other = dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(3),
                                    optimizer=dc.STLSQ(threshold=0.05))
        other.fit(x, t=t, u=u, x_dot=duffing(x, u))
        np.testing.assert_allclose(other.coef_, model.coef_, atol=1e-9)
        np.testing.assert_allclose(other.simulate([0.3, -0.1], t, u=u, method="rk4"),
                                   reference, rtol=1e-10, atol=1e-10)


def test_compiled_blow_up_stops_with_the_partial_trajectory():
    t = np.arange(201) * 0.1
    x = np.exp(t[:20])[:, None]
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                optimizer=dc.STLSQ(threshold=0.1)).fit(
        x, t=t[:20], x_dot=x ** 2)                         # x' = x^2 blows up at t = 1/x0
    with pytest.raises(SimulationError, match="non-finite") as info:
        model.simulate([1.0], t, method="rk4")
    partial = info.value.partial
    assert 5 <= len(partial) < len(t)
    assert np.all(np.isfinite(partial))
    np.testing.assert_allclose(partial[:5, 0], 1 / (1 - t[:5]), rtol=1e-3)
