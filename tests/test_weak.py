"""The weak (integral) form against systems with known coefficients."""
import dask.array as da
import numpy as np
import pytest

import discrepancy as dc
from discrepancy.errors import ShapeError

A = np.array([[-0.1, 2.0], [-2.0, -0.1]])   # a damped linear oscillator, plus an input
B = np.array([0.0, 1.0])


def forced(helpers, x0, t):
    """States (scipy, tight tolerances) and input samples of x' = A x + B sin(1.3 t)."""
    x = helpers.integrate(lambda x, u: A @ x + B * u[0], x0, t,
                          lambda tau: np.array([np.sin(1.3 * tau)]))
    return x, np.sin(1.3 * t)[:, None]


def test_weak_form_recovers_a_forced_linear_system_from_several_trajectories(helpers):
    t = np.arange(3000) * 0.01
    runs = [forced(helpers, x0, t) for x0 in ([1.0, 0.0], [0.0, -2.0])]
    model = dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                differentiation_method="weak(window_length=101)")
    model.fit([x for x, _ in runs], t=0.01, u=[u for _, u in runs])
    names = model.get_feature_names()
    expected = np.zeros_like(model.coef_)
    expected[:, [names.index("x1"), names.index("x2")]] = A
    expected[:, names.index("u")] = B
    np.testing.assert_allclose(model.coef_, expected, atol=1e-8)


def test_weak_form_chosen_window_with_a_prior_and_noise(vdp_data, helpers):
    x = vdp_data.x + 0.05 * np.random.default_rng(0).standard_normal(vdp_data.x.shape)
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                feature_library=dc.PolynomialLibrary(3),
                                differentiation_method="weak").fit(x, t=0.01)
    assert isinstance(model.differentiation_method_, dc.WeakForm)
    assert model.differentiation_method_.window_length >= 61
    names = model.get_feature_names()
    assert model.coef_[1, names.index("x2")] == pytest.approx(0.4, rel=0.05)
    assert model.coef_[1, names.index("x1^2 x2")] == pytest.approx(-0.4, rel=0.05)


def test_weak_form_streams_and_runs_on_dask_like_in_memory(helpers):
    t = np.arange(5000) * 0.01
    x, u = forced(helpers, [1.0, 0.5], t)
    x = x + 1e-3 * np.random.default_rng(1).standard_normal(x.shape)

    def model():
        return dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(2),
                                   differentiation_method=dc.WeakForm(81),
                                   optimizer=dc.STLSQ(threshold=0.0))
    ref = model().fit(x, t=0.01, u=u)
    chunks = iter([dc.Chunk(x[i:i + 700], u=u[i:i + 700]) for i in range(0, len(x), 700)])
    streamed = model().fit(chunks, t=0.01)
    on_dask = model().fit(da.from_array(x, chunks=900), t=0.01, u=da.from_array(u, chunks=900))
    for other in (streamed, on_dask):
        np.testing.assert_allclose(other.statistics_.gram, ref.statistics_.gram, rtol=1e-10)
        np.testing.assert_allclose(other.coef_, ref.coef_, rtol=1e-8, atol=1e-10)


def test_a_window_longer_than_a_trajectory_is_refused():
    x = np.random.default_rng(0).standard_normal((50, 2))
    with pytest.raises(ShapeError, match="window_length 101 is longer than a trajectory of 50"):
        dc.DiscrepancyModel(differentiation_method=dc.WeakForm(101)).fit(x, t=0.1)
