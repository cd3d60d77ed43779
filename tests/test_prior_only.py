"""The prior alone as a first-class model: fitted, simulated, scored, exported, saved."""
import warnings

import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import ParameterError


def test_from_prior_simulates_the_prior_and_exports_it(tmp_path):
    x1, x2 = sp.symbols("x1 x2")
    model = dc.DiscrepancyModel.from_prior([x2, -x1])
    assert model.prior_only_ and model.equations() == ["prior", "prior"]
    t = np.arange(0, 10, 0.01)
    np.testing.assert_allclose(model.simulate([1.0, 0.0], t),
                               np.c_[np.cos(t), -np.sin(t)], atol=1e-7)
    assert model.to_sympy() == [sp.Symbol("x2", real=True), -sp.Symbol("x1", real=True)]
    model.save(tmp_path / "prior.json")
    loaded = dc.load_model(tmp_path / "prior.json")
    assert loaded.prior_only_ and not np.any(loaded.coef_)


def test_from_prior_of_a_callable_needs_the_state_names():
    with pytest.raises(ParameterError, match="state_names"):
        dc.DiscrepancyModel.from_prior(lambda x, u=None: -x)
    model = dc.DiscrepancyModel.from_prior(lambda x, u: -x + u, state_names=["v"],
                                           input_names="u")
    np.testing.assert_allclose(model.predict(np.array([[1.0]]), np.array([[3.0]])), [[2.0]])


def test_prior_only_optimizer_fits_without_a_warning_and_scores_the_prior(vdp_data,
                                                                         helpers):
    prior = helpers.vdp_rhs(0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = dc.DiscrepancyModel(prior=prior, optimizer="prior_only").fit(
            vdp_data.x, t=vdp_data.dt)
    assert model.prior_only_ and not np.any(model.coef_)
    assert model.forecast_selection_ is None
    # the prior's own trajectory error, by scipy
    sim = helpers.integrate(prior, vdp_data.x[0], vdp_data.t)
    expected = np.linalg.norm(sim - vdp_data.x) / np.linalg.norm(vdp_data.x)
    assert model.score(vdp_data.x, t=vdp_data.dt, metric="trajectory") == pytest.approx(
        expected, rel=1e-5)
    # derivative error of the prior alone: 1 - R^2 of the analytic derivatives
    assert model.score(vdp_data.x, t=vdp_data.dt, x_dot=vdp_data.x_dot) == pytest.approx(
        np.mean(1 - np.sum((vdp_data.x_dot - prior(vdp_data.x)) ** 2, axis=0)
                / np.sum((vdp_data.x_dot - vdp_data.x_dot.mean(axis=0)) ** 2, axis=0)),
        rel=1e-9)
    assert dc.PriorOnly().fit(np.ones((10, 3)), np.ones(10)).coef_.tolist() == [[0, 0, 0]]
