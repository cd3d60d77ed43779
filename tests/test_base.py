"""scikit-learn's contract where it applies: NotFittedError is also scikit-learn's, and fitted
models pickle (pickle, joblib, a multiprocessing pool) with the same predictions after."""
from __future__ import annotations

import multiprocessing
import pickle
import subprocess
import sys

import joblib
import numpy as np
import pytest
import sklearn.exceptions
from sklearn.utils.validation import check_is_fitted

import discrepancy as dc
from discrepancy.errors import NotFittedError
from discrepancy.symbolic import symbol

T = np.arange(400) * 0.01
X = np.c_[np.sin(T), np.cos(T)]
U = np.cos(3 * T)[:, None]


def states_only_prior(x):
    return np.c_[x[:, 1], -x[:, 0]]


def fitted_models():
    fd, stlsq = "finite_difference", dc.STLSQ(threshold=0.05)
    return {
        "plain": dc.DiscrepancyModel(differentiation_method=fd, optimizer=stlsq).fit(X, T, u=U),
        "auto smoothing": dc.DiscrepancyModel().fit(X, T),
        "sympy prior, fourier": dc.DiscrepancyModel(
            prior=[symbol("x2"), -symbol("x1")], feature_library="poly(2)+fourier(1)",
            differentiation_method=fd, optimizer=stlsq).fit(X, T),
        "states-only callable prior": dc.DiscrepancyModel(
            prior=states_only_prior, differentiation_method=fd, optimizer=stlsq).fit(X, T),
        "numpy function terms": dc.DiscrepancyModel(
            feature_library=dc.CustomLibrary(functions={"sq": np.square}),
            differentiation_method=fd, optimizer=stlsq).fit(X, T),
        "map": dc.DiscrepancyModel.from_prior([0.9 * symbol("x")], state_names=["x"],
                                              discrete_time=True),
    }


MODELS = fitted_models()


def _predict(model):
    x = X[:20, :model.n_states_]
    return model.predict(x, U[:20] if model.n_inputs_ else None)


@pytest.mark.parametrize("make", [dc.DiscrepancyModel, dc.STLSQ, dc.PolynomialLibrary])
def test_not_fitted_is_also_sklearns_error(make):
    estimator = make()
    with pytest.raises(sklearn.exceptions.NotFittedError) as caught:
        estimator.check_is_fitted()
    assert isinstance(caught.value, NotFittedError) and isinstance(caught.value, AttributeError)
    with pytest.raises(sklearn.exceptions.NotFittedError):
        check_is_fitted(estimator)


def test_predict_before_fit_is_sklearns_not_fitted_error():
    with pytest.raises(sklearn.exceptions.NotFittedError, match=r"call fit\(x, t\) first"):
        dc.DiscrepancyModel().predict(X)
    check_is_fitted(MODELS["plain"])          # a fitted model passes sklearn's check


def test_the_error_pickles_and_stays_both_kinds():
    error = pickle.loads(pickle.dumps(NotFittedError("not fitted")))
    assert isinstance(error, NotFittedError)
    assert isinstance(error, sklearn.exceptions.NotFittedError)


def test_import_without_sklearn_leaves_it_unimported():
    code = ("import sys, discrepancy as dc, numpy as np\n"
            "try:\n    dc.DiscrepancyModel().predict(np.zeros((3, 2)))\n"
            "except dc.errors.NotFittedError:\n    pass\n"
            "print('sklearn' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "False"


@pytest.mark.parametrize("name", sorted(MODELS))
def test_fitted_models_pickle_with_the_same_predictions(name):
    model = MODELS[name]
    again = pickle.loads(pickle.dumps(model))
    np.testing.assert_array_equal(_predict(again), _predict(model))
    np.testing.assert_array_equal(again.coef_, model.coef_)
    assert again.get_feature_names() == model.get_feature_names()
    x0 = X[0, :model.n_states_]
    steps = 5 if model.discrete_time else T[:5]
    kw = {"u": U[:5]} if model.n_inputs_ else {}
    np.testing.assert_array_equal(again.simulate(x0, steps, **kw), model.simulate(x0, steps, **kw))


def test_fitted_models_through_joblib(tmp_path):
    path = tmp_path / "models.joblib"
    joblib.dump(MODELS, path)
    loaded = joblib.load(path)
    for name, model in MODELS.items():
        np.testing.assert_array_equal(_predict(loaded[name]), _predict(model))


def test_fitted_models_through_a_process_pool():
    names = sorted(MODELS)
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        predictions = pool.map(_predict, [MODELS[n] for n in names])
    for name, prediction in zip(names, predictions, strict=True):
        np.testing.assert_array_equal(prediction, _predict(MODELS[name]))


def test_clone_is_an_unfitted_copy_with_the_constructor_arguments_as_sklearn_clone_gives():
    import sklearn.base

    import discrepancy as dc
    from discrepancy.base import clone
    from discrepancy.errors import NotFittedError

    theta = np.random.default_rng(0).normal(size=(50, 3))
    fitted = dc.STLSQ(threshold=0.2, alpha=1e-3).fit(theta, theta @ [1.0, 0.0, -2.0])
    copy = clone(fitted)
    assert type(copy) is dc.STLSQ and copy is not fitted
    assert copy.get_params() == sklearn.base.clone(fitted).get_params()
    with pytest.raises(NotFittedError):
        copy.check_is_fitted()
    fitted.check_is_fitted()     # the source keeps its fit
