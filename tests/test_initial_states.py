"""Initial states from several starts: a rectified output whose sign a start at zero cannot
find, the best start's state against the simulated truth, and the warning when no start
fits (a model of the wrong frequency)."""
import functools
import warnings

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import discrepancy as dc
from discrepancy.errors import InitialStateWarning
from discrepancy.models.outputs.initial_states import best_start
from discrepancy.models.outputs.output_error import records_of
from discrepancy.models.outputs.output_fit import prepare

pytest.importorskip("casadi")
POS, VEL, U = sp.symbols("pos vel u", real=True)


@functools.lru_cache
def oscillator(stiffness=1.0, m=800, dt=0.05):
    t = np.arange(m) * dt
    u = np.sin(0.8 * t) + 0.6 * np.sin(1.9 * t + 0.4)
    x = solve_ivp(lambda s, z: [z[1], -stiffness * z[0] - 0.2 * z[1] + np.interp(s, t, u)],
                  (0, t[-1]), [0.4, -0.8], t_eval=t, rtol=1e-11, atol=1e-11,
                  max_step=dt).y.T
    return t, u, x


def exact_model(t, u, x):
    """The true oscillator as a fitted model (prior = truth, no discrepancy terms)."""
    model = dc.DiscrepancyModel(prior=[VEL, -POS - 0.2 * VEL + U], state_names=["pos", "vel"],
                                input_names=["u"], feature_library=dc.CustomLibrary([POS]),
                                optimizer=dc.PriorOnly())
    return model.fit(x, t=t, u=u, x_dot=np.gradient(x, t, axis=0))


@pytest.mark.parametrize("k", [20, 94, 168, 242, 390, 464])
def test_a_rectified_output_needs_more_than_a_start_at_zero(k):
    """y = |pos| over 10 samples: from zero, the fit of these windows ends on the mirrored
    branch (pos of the wrong sign; a local minimum, as the input's effect over 0.5 s is
    small); the starts from the inverse of the output map (both signs) include the true
    branch, and the best fit is the true state."""
    t, u, x = oscillator()
    window = slice(k, k + 10)
    y = np.abs(x[window, 0])
    model = exact_model(t, u, x)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InitialStateWarning)
        x0 = model.estimate_initial_state(y, t=t[window], u=u[window], outputs=[sp.Abs(POS)])
    np.testing.assert_allclose(x0, x[k], atol=1e-5)
    records, _ = records_of(model, y, t[window], u[window], 4, "linear")
    fit, _, rows = prepare(model.setup_, records, outputs=[sp.Abs(POS)], x0=None,
                           x0_bounds=None, substeps=4,
                           free=np.zeros_like(model.coef_, bool))
    from_zero, _, _ = best_start(fit, model.coef_, rows, [("zeros", np.zeros((1, 2)))])
    assert np.sign(from_zero[0, 0]) == -np.sign(x[k, 0])


def test_no_start_fitting_the_window_is_warned_about_with_its_size():
    """Data of an oscillator three times stiffer over two of its periods: no initial state
    of the model makes it follow them."""
    t, u, x = oscillator(stiffness=9.0)
    model = exact_model(t, u, x)
    window = slice(100, 160)
    with pytest.warns(InitialStateWarning, match=r"times the outputs' spread"):
        model.estimate_initial_state(x[window, 0], t=t[window], u=u[window], outputs=["pos"])


def test_the_best_of_several_starts_for_each_of_several_records():
    t, u, x = oscillator()
    model = exact_model(t, u, x)
    windows = [slice(60, 75), slice(200, 215), slice(300, 315)]
    with warnings.catch_warnings():
        warnings.simplefilter("error", InitialStateWarning)
        x0s = model.estimate_initial_state([x[w, 0] for w in windows],
                                           t=[t[w] for w in windows],
                                           u=[u[w] for w in windows], outputs=["pos"])
    np.testing.assert_allclose(x0s, [x[w.start] for w in windows], atol=1e-5)
