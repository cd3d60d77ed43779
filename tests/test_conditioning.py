"""Nearly collinear terms are named, from the Gram statistics alone (in memory, streamed and
on Dask alike), and well-posed fits stay silent."""
import warnings

import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import IllConditionedWarning
from discrepancy.models.core.conditioning import collinear_terms


def test_an_input_equal_to_a_state_is_named():
    t = np.linspace(0, 10, 500)
    x = np.sin(t)[:, None]
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(1, include_bias=False),
                                optimizer=dc.STLSQ(threshold=0.0, alpha=0.0))
    named = r"equation of x1 \(terms x1, u: condition number inf"
    with pytest.warns(IllConditionedWarning, match=named):
        model.fit(x, t=t, u=x.copy(), x_dot=np.cos(t)[:, None])
    assert model.conditioning_["x1"] > 1e10


def test_a_well_posed_fit_gives_no_warning_and_its_condition_number():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(400, 2))
    x_dot = x @ np.array([[1.0, 0.5], [-2.0, 0.3]])
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(1, include_bias=False),
                                optimizer=dc.STLSQ(threshold=0.0, alpha=0.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error", IllConditionedWarning)
        model.fit(x, x_dot=x_dot, t=0.1)
    unit = x / np.linalg.norm(x, axis=0)
    expected = np.linalg.cond(unit) ** 2          # independent: singular values of Θ
    assert model.conditioning_["x1"] == pytest.approx(expected, rel=1e-8)


def test_the_trading_terms_are_the_collinear_ones():
    rng = np.random.default_rng(1)
    a, b, c = rng.normal(size=(3, 300))
    theta = np.column_stack([a, b, a + 1e-7 * c, c])    # columns 0 and 2 nearly equal
    condition, terms = collinear_terms(theta.T @ theta, np.ones(4, bool))
    assert condition > 1e12 and list(terms) == [0, 2]
    condition, terms = collinear_terms(theta.T @ theta, np.array([True, True, False, True]))
    assert condition < 10 and condition == pytest.approx(
        np.linalg.cond(theta[:, [0, 1, 3]] / np.linalg.norm(theta[:, [0, 1, 3]], axis=0)) ** 2,
        rel=1e-6)
