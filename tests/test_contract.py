"""The estimator contract, checked for every public component (scikit-learn's
``estimator_checks`` idea): constructors store their arguments, ``clone`` and the params
round trip work, ``repr`` shows what was set, use before ``fit`` is a NotFittedError,
fitting twice gives the same result, and fitted models survive a save/load round trip.

Each case says how to build the component, fit it on data with a known answer, and read
what the fit produced; the checks are the same for all.
"""
from __future__ import annotations

import inspect
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import sympy as sp
from sklearn.base import clone

import discrepancy as dc
from discrepancy import FieldWeakForm
from discrepancy.base import Estimator
from discrepancy.differentiation import Differentiator
from discrepancy.differentiation.spatial import SpatialDifferentiator
from discrepancy.errors import NotFittedError, ParameterError

T = np.arange(2001) * 0.01
DECAY = 0.1   # a damped oscillator: x1' = -0.1 x1 + x2, x2' = -x1 - 0.1 x2
X = np.exp(-DECAY * T)[:, None] * np.c_[np.sin(T), np.cos(T)]
X_DOT = X @ np.array([[-DECAY, -1.0], [1.0, -DECAY]])
THETA = np.c_[np.ones_like(T), X, X[:, 0] * X[:, 1]]
Y = THETA @ np.array([[0.0, 2.0], [1.5, 0.0], [0.0, -0.5], [0.7, 0.0]])


@dataclass
class Case:
    make: Callable[[], Estimator]
    fit: Callable[[Any], Any]            # fits the object, returns it
    output: Callable[[Any], np.ndarray]  # what the fit produced (compared across fits)
    unfitted: Callable[[Any], Any]       # a call that needs a fit


def _library_case(make):
    return Case(make, lambda lib: lib.fit(["x1", "x2"]), lambda lib: lib.transform(X),
                lambda lib: lib.transform(X))


def _optimizer_case(make):
    return Case(make, lambda opt: opt.fit(THETA, Y), lambda opt: opt.coef_,
                lambda opt: opt.check_is_fitted())


def _differentiator_case(make, x=X):
    return Case(make, lambda d: d, lambda d: np.hstack(d(x, T[:len(x)])), lambda d: None)


XS = np.linspace(0, 2 * np.pi, 64, endpoint=False)
GRID_STEP = XS[1] - XS[0]
# the heat equation u_t = 0.1 u_xx, two decaying modes on a periodic grid: (time, x)
FIELD = (np.exp(-0.1 * T[:60])[:, None] * np.sin(XS)[None, :]
         + 0.5 * np.exp(-0.4 * T[:60])[:, None] * np.sin(2 * XS + 1)[None, :])


def _spatial_case(make):
    return Case(make, lambda d: d, lambda d: d.derivative(FIELD, 1, 2, GRID_STEP, True),
                lambda d: None)


def _pde_fit(model):
    return model.fit(FIELD, t=0.01, grid=dc.Grid(XS, periodic=True))


def _pde_library_case(make):
    names = ["u", "u_x", "u_xx"]
    return Case(make, lambda lib: lib.fit(names),
                lambda lib: lib.transform(np.c_[FIELD[0], FIELD[1], FIELD[2]]),
                lambda lib: lib.transform(np.zeros((2, 3))))


def _model_fit(model):
    return model.fit(X, t=T, x_dot=X_DOT)


def oscillator_energy(x):
    """Energy of x'' = -x for x = [q, dq] (the damped oscillator above loses it)."""
    return 0.5 * (x[:, 0] ** 2 + x[:, 1] ** 2)


def _energy_case(make):
    return Case(make, lambda m: m.fit(X[:, :1], T, dq=X_DOT[:, :1]), lambda m: m.coef_,
                lambda m: m.predict(X[:, :1], T, dq=X_DOT[:, :1]))


CASES = {
    "PolynomialLibrary": _library_case(lambda: dc.PolynomialLibrary(degree=3)),
    "FourierLibrary": _library_case(lambda: dc.FourierLibrary(n_frequencies=2)),
    "CustomLibrary": _library_case(
        lambda: dc.CustomLibrary([sp.Symbol("x1") * sp.Symbol("x2")])),
    "ConcatLibrary": _library_case(lambda: dc.PolynomialLibrary(2) + dc.FourierLibrary(1)),
    "TensorLibrary": _library_case(
        lambda: dc.FourierLibrary(1, variables=["x1"]) * dc.PolynomialLibrary(1)),
    "STLSQ": _optimizer_case(lambda: dc.STLSQ(threshold=0.1)),
    "STLSQ auto": _optimizer_case(lambda: dc.STLSQ(threshold="auto")),
    "Lasso": _optimizer_case(lambda: dc.Lasso(alpha=1e-4, unbias=True)),
    "SR3": _optimizer_case(lambda: dc.SR3(reg_weight_lam=0.01)),
    "PriorOnly": _optimizer_case(dc.PriorOnly),
    "ConstrainedSR3": _optimizer_case(lambda: dc.ConstrainedSR3(reg_weight_lam=0.01)),
    "EnsembleOptimizer": _optimizer_case(lambda: dc.EnsembleOptimizer(
        dc.STLSQ(threshold=0.1), bagging=True, n_models=5, random_state=0)),
    "SpatialSpectral": _spatial_case(dc.SpatialSpectral),
    "SpatialFiniteDifference": _spatial_case(lambda: dc.SpatialFiniteDifference(order=4)),
    "SpatialSavitzkyGolay": _spatial_case(dc.SpatialSavitzkyGolay),
    "PDELibrary": _pde_library_case(lambda: dc.PDELibrary(derivative_order=1)),
    "FieldWeakForm": Case(dc.FieldWeakForm, lambda w: w, lambda w: _pde_fit(
        dc.PDEDiscrepancyModel(feature_library=dc.PDELibrary(derivative_order=2),
                               differentiation_method=w)).coef_, lambda w: None),
    "PDEDiscrepancyModel": Case(
        lambda: dc.PDEDiscrepancyModel(feature_library=dc.PDELibrary(derivative_order=2)),
        _pde_fit, lambda m: m.coef_, lambda m: m.coefficients()),
    "FiniteDifference": _differentiator_case(dc.FiniteDifference),
    "SavitzkyGolay": _differentiator_case(lambda: dc.SavitzkyGolay(window_length=31)),
    "Spline": _differentiator_case(lambda: dc.Spline(s=1e-4)),
    "TrendFiltered": _differentiator_case(lambda: dc.TrendFiltered(alpha=1e-3),
                                          x=X[:300]),
    "Kalman": _differentiator_case(lambda: dc.Kalman(alpha=0.1), x=X[:300]),
    # scipy's GCV for the smoothing parameter is a Python loop: 2.9 s per call on 2001 samples
    "SmoothingSpline": _differentiator_case(dc.SmoothingSpline, x=X[:300]),
    "Spectral": _differentiator_case(lambda: dc.Spectral(cutoff=0.5)),
    "WeakForm": Case(lambda: dc.WeakForm(61), lambda w: w, lambda w: np.hstack(w.rows(X, T, X)),
                     lambda w: None),
    "AutoSmoothing": _differentiator_case(dc.AutoSmoothing),
    "Dequantised": _differentiator_case(
        lambda: dc.Dequantised(resolution=0.01), x=np.round(X / 0.01) * 0.01),
    "DissipationDiscrepancy": _energy_case(
        lambda: dc.DissipationDiscrepancy(oscillator_energy, max_terms=2)),
    "EnergyDiscrepancy": _energy_case(
        lambda: dc.EnergyDiscrepancy(oscillator_energy, feature_library=dc.FourierLibrary(1),
                                     optimizer=dc.STLSQ(threshold=1e-3))),
    "DiscrepancyModel": Case(
        lambda: dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(3),
                                    optimizer=dc.STLSQ(threshold=0.05)),
        _model_fit, lambda m: m.coef_, lambda m: m.predict(X)),
}
IDS = sorted(CASES)


def test_every_public_component_has_a_case():
    public = {name for name in dc.__all__ if isinstance(getattr(dc, name), type)
              and issubclass(getattr(dc, name), Estimator)}
    covered = {name.split()[0] for name in CASES}
    assert public - {"ConcatLibrary", "TensorLibrary"} <= covered, public - covered


@pytest.mark.parametrize("name", IDS)
def test_constructor_stores_its_arguments_unchanged(name):
    obj = CASES[name].make()
    params = obj.get_params(deep=False)
    assert set(params) == set(type(obj)._param_defaults())
    rebuilt = type(obj)(**params)
    for key, value in params.items():
        assert getattr(rebuilt, key) is value, key


@pytest.mark.parametrize("name", IDS)
def test_constructor_validates_nothing(name):
    """Garbage is stored as given and refused only when used (fit, call)."""
    cls = type(CASES[name].make())
    garbage = {k: object() for k, v in cls._param_defaults().items()}
    obj = cls(**garbage)
    assert all(getattr(obj, k) is v for k, v in garbage.items())


@pytest.mark.parametrize("name", IDS)
def test_clone_and_params_round_trip(name):
    obj = CASES[name].make()
    copy = clone(obj)
    assert copy is not obj and type(copy) is type(obj)
    assert repr(copy) == repr(obj)
    before = obj.get_params(deep=True)
    obj.set_params(**obj.get_params(deep=False))
    assert repr(obj.get_params(deep=True)) == repr(before)
    with pytest.raises(ParameterError, match="no parameter 'not_a_parameter'"):
        obj.set_params(not_a_parameter=1)


@pytest.mark.parametrize("name", IDS)
def test_repr_names_the_class_and_the_changed_arguments(name):
    obj = CASES[name].make()
    text = repr(obj)
    assert text.startswith(type(obj).__name__ + "(")
    defaults = type(obj)._param_defaults()
    for key, value in obj.get_params(deep=False).items():
        changed = defaults[key] is inspect.Parameter.empty or value is not defaults[key] and \
            not (isinstance(value, (int, float, str, bool)) and value == defaults[key])
        shown = re.search(rf"[(, ]{key}=", text) is not None
        assert shown == changed, (key, text)


@pytest.mark.parametrize("name", [n for n in IDS  # differentiators hold no fitted state
                                  if not isinstance(CASES[n].make(), (Differentiator,
                                                                      SpatialDifferentiator,
                                                                      FieldWeakForm))])
def test_use_before_fit_is_a_not_fitted_error(name):
    case = CASES[name]
    with pytest.raises(NotFittedError):
        case.unfitted(case.make())


@pytest.mark.parametrize("name", IDS)
def test_fitting_twice_gives_the_same_result(name):
    case = CASES[name]
    obj = case.make()
    first = np.array(case.output(case.fit(obj)), dtype=float)
    second = np.array(case.output(case.fit(obj)), dtype=float)
    fresh = np.array(case.output(case.fit(clone(obj))), dtype=float)
    np.testing.assert_array_equal(first, second)
    np.testing.assert_array_equal(first, fresh)


@pytest.mark.parametrize("name", IDS)
def test_fit_leaves_the_parameters_untouched(name):
    case = CASES[name]
    obj = case.make()
    before, text = repr(obj.get_params(deep=True)), repr(obj)
    case.fit(obj)
    assert repr(obj.get_params(deep=True)) == before
    assert repr(obj) == text  # fitted state never shows in the repr


def test_model_save_load_round_trip(tmp_path):
    model = _model_fit(CASES["DiscrepancyModel"].make())
    truth = np.zeros_like(model.coef_)
    truth[:, 1:3] = [[-DECAY, 1.0], [-1.0, -DECAY]]     # columns 1, x1, x2, x1^2, ...
    np.testing.assert_allclose(model.coef_, truth, atol=1e-8)
    model.save(tmp_path / "m.json")
    loaded = dc.load_model(tmp_path / "m.json")
    np.testing.assert_array_equal(loaded.coef_, model.coef_)
    np.testing.assert_allclose(loaded.predict(X), model.predict(X), rtol=1e-14)
    assert repr(loaded.optimizer_) == repr(model.optimizer_)
    assert repr(loaded.differentiation_method_) == repr(model.differentiation_method_)
    refit = clone(loaded).fit(X, t=T, x_dot=X_DOT)  # a loaded model is a whole model
    np.testing.assert_allclose(refit.coef_, model.coef_, atol=1e-12)
