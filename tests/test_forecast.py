"""Batched forecasts and their scores against closed forms: a decaying exponential
forecast by linear models (the best initial state and its residual by hand), the
horizon where the prior's error saturates, discrete maps."""
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.fitting.held_out import Window
from discrepancy.selection.forecast import forecast_scores, prepare
from discrepancy.selection.horizon import choose_steps


def window(t, x, u=None, origin=0, fold=0):
    w = Window(fold, origin, len(t))
    w.append(t, x, u)
    return w


def setup_of(prior, n=1, r=0, **kw):
    return dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(1),
                               differentiation_method=dc.SavitzkyGolay(7, 3), **kw
                               ).make_setup(n, r)


def test_score_of_a_linear_model_is_the_residual_after_the_best_initial_state():
    """Data 2 exp(-t/2); the model x' = -x + c x (c = 0 is the prior alone) simulates
    x0 exp((c - 1) t): the best x0 and its mean squared residual are a least-squares fit."""
    dt = 0.01
    t = np.arange(401) * dt
    data = 2 * np.exp(-0.5 * t)[:, None]
    setup = setup_of(lambda x, u=None: -x)
    origins = prepare([window(t, data)], setup)
    s = origins.stride
    steps = origins.max_steps
    times = t[::s][:steps + 1]
    y = data[::s, 0][:steps + 1]
    scale = data[:, 0].std()
    for c in (0.0, 0.3, 0.5):
        coef = np.zeros((1, 1, 2))
        coef[0, 0, 1] = c                       # columns: 1, x1
        got = forecast_scores(setup, origins, coef, np.array([0]), steps).score[0]
        e = np.exp((c - 1) * times)
        best = (y @ e) / (e @ e)
        expected = np.mean(((best * e - y) / scale) ** 2)
        assert got == pytest.approx(expected, rel=2e-5, abs=1e-14)   # RK4 steps of s dt
    assert expected < 1e-12     # c = 0.5 is the truth: nothing left


def test_rows_with_their_own_coefficients_and_windows_in_one_batch():
    dt = 0.01
    t = np.arange(201) * dt
    one, two = 2 * np.exp(-0.5 * t)[:, None], np.exp(-0.2 * t)[:, None]
    setup = setup_of(lambda x, u=None: -x)
    origins = prepare([window(t, one), window(t, two)], setup)
    steps = origins.max_steps
    coef = np.zeros((4, 1, 2))
    coef[:, 0, 1] = [0.5, 0.5, 0.8, 0.8]         # right, wrong, right, wrong
    scores = forecast_scores(setup, origins, coef, np.array([0, 1, 1, 0]), steps).score
    assert max(scores[0], scores[2]) < 1e-12 < min(scores[1], scores[3])


def test_a_diverging_forecast_is_capped_not_infinite():
    t = np.arange(301) * 0.01
    setup = setup_of(lambda x, u=None: -x)
    origins = prepare([window(t, np.exp(-t)[:, None])], setup)
    coef = np.zeros((1, 1, 2))
    coef[0, 0, 1] = 60.0                          # x' = 59 x: e^(59 t) leaves any range
    got = forecast_scores(setup, origins, coef, np.array([0]), origins.max_steps)
    assert np.isfinite(got.score[0]) and got.score[0] > 10
    assert got.lead[0, -1] == 100.0                   # the cap from the divergence on


def test_inputs_enter_the_steps_linearly_between_samples():
    """x' = -x + u with u = t: exact solution x = t - 1 + 2 exp(-t) from x0 = 1; the prior
    alone (the truth) scores ~0, a model without the input does not."""
    t = np.arange(301) * 0.01
    x = (t - 1 + 2 * np.exp(-t))[:, None]
    setup = setup_of(lambda x, u: -x + u, r=1)
    origins = prepare([window(t, x, t[:, None])], setup)
    zero = np.zeros((1, 1, setup.n_features))
    assert forecast_scores(setup, origins, zero, np.array([0]),
                           origins.max_steps).score[0] < 1e-12
    wrong = zero.copy()
    wrong[0, 0, setup.library.get_feature_names().index("u")] = -1.0
    assert forecast_scores(setup, origins, wrong, np.array([0]),
                           origins.max_steps).score[0] > 1e-3


def test_maps_iterate_and_score_exactly():
    """x[k+1] = 0.9 x[k] with the prior x[k+1] = x[k]: correction -0.1 x is exact."""
    k = np.arange(60)
    x = (3 * 0.9 ** k)[:, None]
    setup = setup_of(lambda x, u=None: x, discrete_time=True)
    origins = prepare([window(k.astype(float), x)], setup)
    assert origins.stride == 1
    coef = np.zeros((2, 1, 2))
    coef[1, 0, 1] = -0.1
    scores = forecast_scores(setup, origins, coef, np.array([0, 0]), origins.max_steps).score
    e = np.ones(60)                              # the prior keeps x0: best x0 is the mean
    expected = np.mean(((x[:, 0] - x[:, 0].mean() * e) / x[:, 0].std()) ** 2)
    assert scores[0] == pytest.approx(expected, rel=1e-9)
    assert scores[1] < 1e-20


def test_horizon_is_where_the_prior_error_reaches_one_standard_deviation():
    leads = np.arange(201)
    rising = np.tile((leads / 50.0) ** 2, (4, 1))     # RMS = lead / 50
    assert choose_steps(rising) == 50
    assert choose_steps(np.full((4, 201), 1e-4)) == 200          # never saturates
    assert choose_steps(np.full((4, 201), 9.0)) == 8              # at least MIN_STEPS
    ragged = np.tile((leads / 50.0) ** 2, (2, 1))
    ragged[1, 30:] = np.nan                         # one window ends early
    assert choose_steps(ragged) == 50
