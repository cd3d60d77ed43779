"""The extrapolation guard: a fitted model knows the range of the states and inputs it was
fitted on and warns, naming the variable and the distance, when it leaves it."""
import json
import warnings

import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.errors import ExtrapolationWarning


@pytest.fixture(scope="module")
def fitted(vdp_data, helpers):
    x = vdp_data.x + 0.01 * np.random.default_rng(0).standard_normal(vdp_data.x.shape)
    model = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1),
                                feature_library=dc.PolynomialLibrary(3)).fit(x, t=0.01)
    return model, x


def test_the_region_is_the_range_of_the_training_data(fitted):
    model, x = fitted
    np.testing.assert_array_equal(model.region_.low, x.min(axis=0))
    np.testing.assert_array_equal(model.region_.high, x.max(axis=0))
    assert model.region_.names == ("x1", "x2")


def test_simulate_and_predict_warn_once_naming_the_state_and_how_far(fitted):
    model, x = fitted
    top = x[:, 0].max()
    with pytest.warns(ExtrapolationWarning) as caught:
        model.predict(np.array([[top + 1.5, 0.0]]))
    assert len(caught) == 1
    message = str(caught[0].message)
    assert "x1 reached" in message and f"{1.5:.3g} above" in message and "x2" not in message
    t = np.arange(0, 5, 0.01)
    with pytest.warns(ExtrapolationWarning, match=r"simulate left.*x\d reached") as caught:
        model.simulate([4.0, 0.0], t)
    assert len([w for w in caught if w.category is ExtrapolationWarning]) == 1


def test_no_warning_inside_the_region_or_for_the_prior_alone(fitted, helpers):
    model, x = fitted
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.simulate([-0.2, -0.3], np.arange(0, 25, 0.01))
        model.predict(x)
        model.predict_ahead(x, 0.01, steps=5)
        prior = dc.DiscrepancyModel(prior=helpers.vdp_rhs(0.1), optimizer="prior_only").fit(
            x, t=0.01)
        prior.predict(10 * x)


def test_inputs_are_guarded_too(helpers):
    t = np.arange(2001) * 0.01
    u = np.sin(0.7 * t)[:, None]
    f = lambda x, u: np.c_[x[:, 1], -x[:, 0] - 0.3 * x[:, 1] + u[:, 0]]   # noqa: E731
    x = helpers.integrate(lambda z, v: f(z[None], np.atleast_2d(v))[0], [0.0, 0.0], t,
                          u=lambda s: np.array([np.sin(0.7 * s)]))
    model = dc.DiscrepancyModel(prior=lambda x, u: np.c_[x[:, 1], -x[:, 0] + 0.5 * u[:, 0]],
                                feature_library=dc.PolynomialLibrary(1)).fit(x, t=0.01, u=u)
    assert model.region_.names == ("x1", "x2", "u")
    assert model.equations()[1] == "prior - 0.300 x2 + 0.500 u"    # the truth's
    with pytest.warns(ExtrapolationWarning, match=r"u reached 3, 2 above"):
        model.predict(x[:5], 3 * np.ones((5, 1)))


def test_only_variables_the_learned_terms_use_are_watched(helpers):
    """The learned terms are the user's prior's correction: a variable none of them uses,
    or one they see through sin and cos only (an angle that turns over), is not
    extrapolated anywhere."""
    from discrepancy.models.simulate.region import watched_names

    q, v, u = (dc.symbolic.symbol(n) for n in ("q", "v", "u"))
    names = ("q", "v", "u")
    assert watched_names([v, v ** 3], names) == ("v",)
    assert watched_names([sp.sin(q), sp.cos(2 * q) * v], names) == ("v",)
    assert watched_names([sp.sin(q), q * v], names) == ("q", "v")
    assert watched_names([sp.sin(q / 2)], names) == ("q",)            # period 4 pi
    t = np.arange(2001) * 0.01
    x = helpers.integrate(lambda z, _: np.array([z[1], -9.81 * np.sin(z[0]) - 0.3 * z[1]]),
                          [0.5, 9.0], t)
    assert np.ptp(x[:, 0]) > 4 * np.pi                                 # turns over
    model = dc.DiscrepancyModel(
        prior=[v, -8 * sp.sin(q)], state_names=["q", "v"],
        feature_library=dc.CustomLibrary([sp.sin(q), sp.cos(q), v])).fit(x, t=0.01)
    assert model.equations()[1] == "prior - 1.810 sin(q) - 0.300 v"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.predict(np.array([[100.0, 0.0]]))                      # q far outside
    with pytest.warns(ExtrapolationWarning, match="v reached 30") as caught:
        model.predict(np.array([[100.0, 30.0]]))
    assert "q reached" not in str(caught[0].message)


def test_the_region_is_saved_and_loaded_and_old_files_still_load(fitted, tmp_path, helpers):
    model, _ = fitted
    path = tmp_path / "m.json"
    model.save(path)
    loaded = dc.load_model(path, prior=helpers.vdp_rhs(0.1))
    np.testing.assert_array_equal(loaded.region_.low, model.region_.low)
    np.testing.assert_array_equal(loaded.region_.high, model.region_.high)
    with pytest.warns(ExtrapolationWarning):
        loaded.predict(np.array([[10.0, 0.0]]))
    doc = json.loads(path.read_text())
    assert doc["version"] == 4
    doc["version"] = 2                     # a file written before the region was stored
    del doc["region"], doc["fit"]["selection"], doc["parameters"]
    old = dc.DiscrepancyModel.from_state(doc, prior=helpers.vdp_rhs(0.1))
    assert old.region_ is None
    np.testing.assert_array_equal(old.coef_, model.coef_)
    doc = json.loads(path.read_text())
    doc["region"]["low"] = [1e3, 1e3]      # low above high: tampered
    with pytest.raises(dc.errors.ModelFileError, match="region"):
        dc.DiscrepancyModel.from_state(doc, prior=helpers.vdp_rhs(0.1))
