"""Adversarial rows for the components used alone: feature libraries, optimizers and
differentiation methods (see ``adversarial.py`` for the machinery)."""
from __future__ import annotations

import numpy as np
import sympy as sp

import discrepancy as dc
from adversarial import Case, check, params, raises, returns
from discrepancy.differentiation import get_differentiation_method
from discrepancy.errors import (
    DataError,
    ExportError,
    FeatureError,
    NotFittedError,
    ParameterError,
    ResourceError,
    ShapeError,
    UnknownNameError,
)
from discrepancy.libraries.spec import parse_library
from discrepancy.optimizers import get_optimizer
from discrepancy.symbolic import symbol

RNG = np.random.default_rng(1)
Z = RNG.normal(size=(100, 2))
THETA = RNG.normal(size=(100, 3))
Y = THETA @ np.array([[1.0], [0.0], [-2.0]])
T = np.arange(100) * 0.01
X1 = symbol("x1")


def lib_on(library, names=("x1", "x2"), z=Z):
    """Θ of ``library`` fitted to ``names``, on ``z``."""
    return library.fit(list(names)).transform(z)


def names_of(n):
    return [f"v{i}" for i in range(n)]


def custom(f):
    return lambda: lib_on(dc.CustomLibrary(functions={"f": f}))


def diff(method, x=Z, t=T):
    return get_differentiation_method(method)(x, t)


def exact(expected, atol=1e-9):
    return lambda value: np.allclose(value, expected, atol=atol)


LSTSQ = np.linalg.lstsq(THETA, Y, rcond=None)[0].T
T_RAGGED = np.cumsum(RNG.uniform(0.5, 1.5, 50))

CASES = [
    # --- libraries
    Case("library", "negative degree", lambda: lib_on(dc.PolynomialLibrary(-1)), raises(ParameterError, r"PolynomialLibrary: degree must be an integer >= 0")),
    Case("library", "fractional degree", lambda: lib_on(dc.PolynomialLibrary(2.5)), raises(ParameterError, r"degree must be an integer")),
    Case("library", "degree a string", lambda: lib_on(dc.PolynomialLibrary("2")), raises(ParameterError, r"degree must be an integer.*'2'")),
    Case("library", "degree True", lambda: lib_on(dc.PolynomialLibrary(True)), raises(ParameterError, r"degree must be an integer")),
    Case("library", "degree NaN", lambda: lib_on(dc.PolynomialLibrary(np.nan)), raises(ParameterError, r"degree must be an integer")),
    Case("library", "degree 0 without bias", lambda: lib_on(dc.PolynomialLibrary(0, include_bias=False)), raises(ParameterError, r"produces no features")),
    Case("library", "include_bias a word", lambda: lib_on(dc.PolynomialLibrary(include_bias="yes")), raises(ParameterError, r"include_bias must be True or False")),
    Case("library", "interaction_only 1", lambda: lib_on(dc.PolynomialLibrary(interaction_only=1)), raises(ParameterError, r"interaction_only must be True or False")),
    Case("library", "variables empty", lambda: lib_on(dc.PolynomialLibrary(variables=[])), raises(ParameterError, r"variables must be None or a non-empty list")),
    Case("library", "variables unknown name", lambda: lib_on(dc.PolynomialLibrary(variables=["x9"])), raises(UnknownNameError, r"variables of PolynomialLibrary.*'x9'")),
    Case("library", "variables index too large", lambda: lib_on(dc.PolynomialLibrary(variables=[5])), raises(UnknownNameError, r"variables of PolynomialLibrary.*got 5")),
    Case("library", "variables negative index", lambda: lib_on(dc.PolynomialLibrary(variables=[-1])), raises(UnknownNameError, r"variables of PolynomialLibrary.*got -1")),
    Case("library", "variables True", lambda: lib_on(dc.PolynomialLibrary(variables=[True])), raises(ParameterError, r"variables must be")),
    Case("library", "variables a string", lambda: lib_on(dc.PolynomialLibrary(variables="x1")), raises(ParameterError, r"variables must be")),
    Case("library", "Fourier 0 frequencies", lambda: lib_on(dc.FourierLibrary(0)), raises(ParameterError, r"n_frequencies must be an integer >= 1")),
    Case("library", "Fourier frequencies empty", lambda: lib_on(dc.FourierLibrary(frequencies=[])), raises(ParameterError, r"frequencies must be None or a non-empty list")),
    Case("library", "Fourier frequency 0", lambda: lib_on(dc.FourierLibrary(frequencies=[0])), raises(ParameterError, r"frequencies must be")),
    Case("library", "Fourier frequency inf", lambda: lib_on(dc.FourierLibrary(frequencies=[np.inf])), raises(ParameterError, r"frequencies must be")),
    Case("library", "Fourier frequency a word", lambda: lib_on(dc.FourierLibrary(frequencies=["a"])), raises(ParameterError, r"frequencies must be")),
    Case("library", "Fourier neither sin nor cos", lambda: lib_on(dc.FourierLibrary(include_sin=False, include_cos=False)), raises(ParameterError, r"include_sin or include_cos")),
    Case("library", "Fourier frequency 0.5", lambda: lib_on(dc.FourierLibrary(frequencies=[0.5]), ["x1"], Z[:, :1]), returns(exact(np.c_[np.sin(Z[:, 0] / 2), np.cos(Z[:, 0] / 2)]))),
    Case("library", "Fourier frequency pi", lambda: lib_on(dc.FourierLibrary(frequencies=[np.pi], include_cos=False), ["x1"], Z[:, :1]), returns(exact(np.sin(np.pi * Z[:, :1])))),
    Case("library", "Custom with nothing", lambda: lib_on(dc.CustomLibrary()), raises(ParameterError, r"CustomLibrary needs expressions=, functions= or both")),
    Case("library", "Custom expressions empty", lambda: lib_on(dc.CustomLibrary(expressions=[])), raises(ParameterError, r"expressions must be None or a non-empty list")),
    Case("library", "Custom expression a string", lambda: lib_on(dc.CustomLibrary(expressions=["x1**2"])), raises(ParameterError, r"expressions\[0\] must be a sympy expression")),
    Case("library", "Custom unknown symbol", lambda: lib_on(dc.CustomLibrary(expressions=[symbol("y")])), raises(UnknownNameError, r"expressions\[0\].*\['y'\]")),
    Case("library", "Custom unsupported function", lambda: lib_on(dc.CustomLibrary(expressions=[sp.gamma(X1)])), raises(ExportError, r"gamma")),
    Case("library", "Custom complex constant", lambda: lib_on(dc.CustomLibrary(expressions=[X1 + sp.I])), raises(ExportError, r"I is not a finite real number")),
    Case("library", "Custom function shadows log", lambda: lib_on(dc.CustomLibrary(functions={"log": np.log1p})), raises(ParameterError, r"\['log'\] would shadow")),
    Case("library", "Custom function name not an identifier", lambda: lib_on(dc.CustomLibrary(functions={"1f": np.sin})), raises(ParameterError, r"functions must be None or a non-empty mapping of identifier")),
    Case("library", "Custom function not callable", lambda: lib_on(dc.CustomLibrary(functions={"f": 3})), raises(ParameterError, r"functions must be")),
    Case("library", "Custom functions empty", lambda: lib_on(dc.CustomLibrary(functions={})), raises(ParameterError, r"functions must be")),
    Case("library", "Custom function raises", custom(lambda v: 1 / 0), raises(FeatureError, r"library term 'f\(x1\)' raised ZeroDivisionError")),
    Case("library", "Custom function returns complex", custom(lambda v: v + 1j), raises(FeatureError, r"'f\(x1\)' returned complex")),
    Case("library", "Custom function returns 3 values", custom(lambda v: v[:3]), raises(FeatureError, r"'f\(x1\)' must return 100 numbers")),
    Case("library", "Custom function returns a string", custom(lambda v: "x"), raises(FeatureError, r"'f\(x1\)' must return 100 numbers")),
    Case("library", "Custom function returns a constant", custom(lambda v: 2.0), returns(exact(np.full((100, 2), 2.0)))),
    Case("library", "Custom constant expression", lambda: lib_on(dc.CustomLibrary(expressions=[sp.Integer(3)])), returns(exact(np.full((100, 1), 3.0)))),
    Case("library", "library plus a number", lambda: dc.PolynomialLibrary() + 3, raises(ParameterError, r"libraries can only be added to libraries; got int")),
    Case("library", "library times a string", lambda: dc.PolynomialLibrary() * "x", raises(ParameterError, r"libraries can only be multiplied by libraries; got str")),
    Case("library", "sum keeps one copy of shared columns", lambda: (dc.PolynomialLibrary(2) + dc.PolynomialLibrary(1)).fit(["a", "b"]).n_features_, returns(lambda n: n == 6)),
    Case("library", "sum of nothing", lambda: lib_on(dc.libraries.base.ConcatLibrary([])), raises(ParameterError, r"libraries must be a non-empty list")),
    Case("library", "transform before fit", lambda: dc.PolynomialLibrary().transform(Z), raises(NotFittedError, r"PolynomialLibrary.transform called before fit")),
    Case("library", "transform with 3 columns", lambda: lib_on(dc.PolynomialLibrary(), z=np.zeros((5, 3))), raises(ShapeError, r"Z must be \(m, 2\)")),
    Case("library", "fit to a number of names", lambda: dc.PolynomialLibrary().fit(3), raises(ShapeError, r"names must be a list of distinct identifiers.*got 3")),
    Case("library", "fit to names that are numbers", lambda: dc.PolynomialLibrary().fit([1, 2]), raises(ShapeError, r"names must be a list of distinct identifiers")),
    Case("library", "fit to repeated names", lambda: dc.FourierLibrary().fit(["a", "a"]), raises(ShapeError, r"names must be a list of distinct identifiers")),
    Case("library", "transform of text", lambda: dc.PolynomialLibrary().fit(["a"]).transform("x"), raises(ShapeError, r"^Z must be a numeric array")),
    Case("library", "names before fit", lambda: dc.FourierLibrary().get_feature_names(), raises(NotFittedError, r"get_feature_names called before fit")),
    Case("library", "out of the wrong shape", lambda: dc.PolynomialLibrary().fit(["a"]).transform(Z[:, :1], out=np.empty((3, 3))), raises(ShapeError, r"out must be float64 of shape \(100, 3\)")),
    Case("library", "spec poly(2, )", lambda: parse_library("poly(2, )"), raises(ParameterError, r"library spec 'poly\(2, \)'")),
    Case("library", "spec poly 2", lambda: parse_library("poly 2"), raises(ParameterError, r"library spec 'poly 2'")),
    Case("library", "spec poly()", lambda: parse_library("poly()"), raises(ParameterError, r"library spec 'poly\(\)': poly needs an integer")),
    Case("library", "spec not a string", lambda: parse_library(3), raises(ParameterError, r"library spec")),
    # --- optimizers
    Case("optimizer", "negative threshold", lambda: dc.STLSQ(threshold=-1).fit(THETA, Y), raises(ParameterError, r"STLSQ: threshold must be")),
    Case("optimizer", "threshold a word", lambda: dc.STLSQ(threshold="high").fit(THETA, Y), raises(ParameterError, r"threshold must be .*'auto'")),
    Case("optimizer", "threshold NaN", lambda: dc.STLSQ(threshold=np.nan).fit(THETA, Y), raises(ParameterError, r"threshold must be")),
    Case("optimizer", "negative ridge", lambda: dc.STLSQ(alpha=-1).fit(THETA, Y), raises(ParameterError, r"STLSQ: alpha must be")),
    Case("optimizer", "max_iter 0", lambda: dc.STLSQ(max_iter=0).fit(THETA, Y), raises(ParameterError, r"max_iter must be an integer >= 1")),
    Case("optimizer", "max_iter 2.5", lambda: dc.STLSQ(max_iter=2.5).fit(THETA, Y), raises(ParameterError, r"max_iter must be an integer")),
    Case("optimizer", "unbias a word", lambda: dc.STLSQ(unbias="no").fit(THETA, Y), raises(ParameterError, r"unbias must be True or False")),
    Case("optimizer", "constraints a number", lambda: dc.STLSQ(constraints=42).fit(THETA, Y), raises(ParameterError, r"constraints must be None or LinearConstraints")),
    Case("optimizer", "theta with NaN", lambda: dc.STLSQ().fit(np.where(THETA > 2, np.nan, THETA), Y), raises(DataError, r"^theta must be finite")),
    Case("optimizer", "y with too few rows", lambda: dc.STLSQ().fit(THETA, Y[:-1]), raises(ShapeError, r"^y must have 100 rows")),
    Case("optimizer", "1-D theta", lambda: dc.STLSQ().fit(THETA[:, 0], Y), raises(ShapeError, r"^theta must be 2-D")),
    Case("optimizer", "theta with 0 columns", lambda: dc.STLSQ().fit(THETA[:, :0], Y), raises(ShapeError, r"^theta must have at least 1 column")),
    Case("optimizer", "complex theta", lambda: dc.STLSQ().fit(THETA + 1j, Y), raises(DataError, r"^theta must be real")),
    Case("optimizer", "y with inf", lambda: dc.STLSQ().fit(THETA, np.where(Y > 1, np.inf, Y)), raises(DataError, r"^y must be finite")),
    Case("optimizer", "theta so large its squares overflow", lambda: dc.STLSQ().fit(THETA * 1e200, Y), raises(DataError, r"^theta's sums of squares overflow")),
    Case("optimizer", "theta all zero gives 0", lambda: dc.STLSQ(threshold=0.0).fit(np.zeros((20, 2)), np.ones(20)).coef_, returns(exact(np.zeros((1, 2))))),
    Case("optimizer", "threshold 0 is least squares", lambda: dc.STLSQ(threshold=0.0, alpha=0.0).fit(THETA, Y).coef_, returns(exact(LSTSQ))),
    Case("optimizer", "threshold inf removes every term", lambda: dc.STLSQ(threshold=np.inf).fit(THETA, Y), raises(ParameterError, r"threshold must be")),
    Case("optimizer", "gram not square", lambda: dc.STLSQ().fit_gram(np.zeros((3, 2)), np.zeros((3, 1))), raises(ShapeError, r"gram must be square")),
    Case("optimizer", "gram with NaN", lambda: dc.STLSQ().fit_gram(np.full((2, 2), np.nan), np.zeros((2, 1))), raises(DataError, r"^gram must be finite")),
    Case("optimizer", "rhs with too few rows", lambda: dc.STLSQ().fit_gram(np.eye(3), np.zeros((2, 1))), raises(ShapeError, r"^rhs must have 3 rows")),
    Case("optimizer", "gram not symmetric", lambda: dc.STLSQ().fit_gram(np.array([[1.0, 2.0], [0.0, 1.0]]), np.ones(2)), raises(DataError, r"gram must be symmetric")),
    Case("optimizer", "gram with a negative diagonal", lambda: dc.STLSQ().fit_gram(-np.eye(2), np.ones(2)), raises(DataError, r"gram must be symmetric with a non-negative diagonal")),
    Case("optimizer", "negative n_samples", lambda: dc.Lasso().fit_gram(np.eye(2), np.ones(2), n_samples=-5), raises(ParameterError, r"n_samples must be")),
    Case("optimizer", "yy of the wrong length", lambda: dc.STLSQ().fit_gram(np.eye(2), np.ones(2), yy=[1.0, 2.0]), raises(ShapeError, r"^yy must have 1 columns")),
    Case("optimizer", "auto threshold without yy", lambda: dc.STLSQ(threshold="auto").fit_gram(np.eye(2), np.ones(2)), raises(ParameterError, r"threshold='auto' needs")),
    Case("optimizer", "fit_gram equals fit", lambda: dc.STLSQ(threshold=0.5).fit_gram(THETA.T @ THETA, THETA.T @ Y).coef_, returns(exact(dc.STLSQ(threshold=0.5).fit(THETA, Y).coef_, 1e-9))),
    Case("optimizer", "Lasso negative alpha", lambda: dc.Lasso(alpha=-1).fit(THETA, Y), raises(ParameterError, r"Lasso: alpha must be")),
    Case("optimizer", "Lasso max_iter 0", lambda: dc.Lasso(max_iter=0).fit(THETA, Y), raises(ParameterError, r"Lasso: max_iter must be")),
    Case("optimizer", "Lasso tol 0", lambda: dc.Lasso(tol=0).fit(THETA, Y), raises(ParameterError, r"Lasso: tol must be")),
    Case("optimizer", "Lasso with tiny alpha is least squares", lambda: dc.Lasso(alpha=1e-12).fit(THETA, Y).coef_, returns(exact(LSTSQ, 1e-6))),
    Case("optimizer", "SR3 negative lambda", lambda: dc.SR3(reg_weight_lam=-1).fit(THETA, Y), raises(ParameterError, r"SR3: reg_weight_lam must be")),
    Case("optimizer", "SR3 regularizer l3", lambda: dc.SR3(regularizer="l3").fit(THETA, Y), raises(ParameterError, r"SR3: regularizer must be one of 'l0', 'l1', 'l2'")),
    Case("optimizer", "SR3 nu 0", lambda: dc.SR3(relax_coeff_nu=0).fit(THETA, Y), raises(ParameterError, r"SR3: relax_coeff_nu must be")),
    Case("optimizer", "SR3 nu inf", lambda: dc.SR3(relax_coeff_nu=np.inf).fit(THETA, Y), raises(ParameterError, r"SR3: relax_coeff_nu must be")),
    Case("optimizer", "SR3 lambda 0 is least squares", lambda: dc.SR3(reg_weight_lam=0.0, max_iter=200, tol=1e-12).fit(THETA, Y).coef_, returns(exact(LSTSQ, 1e-6))),
    Case("optimizer", "spec with an unknown option", lambda: get_optimizer("stlsq(threshold=0.1, bogus=1)"), raises(ParameterError, r"'stlsq': STLSQ has no parameter 'bogus'; valid parameters: threshold")),
    Case("optimizer", "set_params unknown", lambda: dc.STLSQ().set_params(bogus=1), raises(ParameterError, r"STLSQ has no parameter 'bogus'")),
    Case("optimizer", "spec with a list value", lambda: get_optimizer("stlsq(threshold=[1])").fit(THETA, Y), raises(ParameterError, r"threshold must be")),
    Case("optimizer", "constraints of the wrong size", lambda: dc.STLSQ(constraints=dc.optimizers.linear_constraints.LinearConstraints(2, 7)).fit(THETA, Y), raises(ShapeError, r"constraints are for 2 equations of 7 terms")),
    Case("optimizer", "statistics of -1 columns", lambda: dc.GramStatistics(-1, 2), raises(ParameterError, r"GramStatistics: p must be an integer >= 0; got -1")),
    Case("optimizer", "statistics of 10**6 columns", lambda: dc.GramStatistics(10**6, 2), raises(ResourceError, r"Gram statistics of 1000000 columns would need 8 TB")),
    Case("optimizer", "fit_statistics of text", lambda: dc.STLSQ().fit_statistics("x"), raises(ParameterError, r"stats must be GramStatistics; got 'x'")),
    # --- differentiation methods
    Case("differentiation", "finite differences on 2 samples", lambda: diff("finite_difference", Z[:2], T[:2]), raises(ShapeError, r"x has 2 samples, fewer than the 3")),
    Case("differentiation", "x with NaN", lambda: diff("finite_difference", np.where(Z > 2, np.nan, Z)), raises(DataError, r"^x must be finite")),
    Case("differentiation", "complex x", lambda: diff("finite_difference", Z + 1j), raises(DataError, r"^x must be real")),
    Case("differentiation", "t of the wrong length", lambda: diff("finite_difference", t=T[:-1]), raises(ShapeError, r"t must be a step or a 1-D array of 100")),
    Case("differentiation", "t decreasing", lambda: diff("finite_difference", t=-T), raises(DataError, r"^t must be strictly increasing")),
    Case("differentiation", "t a step, as in PySINDy", lambda: diff("finite_difference", t=0.01), returns(lambda v: np.allclose(v, np.gradient(Z, 0.01, axis=0, edge_order=2), rtol=1e-12, atol=1e-12))),
    Case("differentiation", "even Savitzky-Golay window", lambda: diff(dc.SavitzkyGolay(4)), raises(ParameterError, r"window_length must be an odd integer >= 3")),
    Case("differentiation", "polyorder equal to the window", lambda: diff(dc.SavitzkyGolay(5, 5)), raises(ParameterError, r"polyorder must be below window_length")),
    Case("differentiation", "windows for 2 of 3 columns", lambda: diff(dc.SavitzkyGolay([5, 7]), np.zeros((100, 3))), raises(ParameterError, r"window_length has 2 values; x has 3 columns")),
    Case("differentiation", "polyorder 0", lambda: diff(dc.SavitzkyGolay(5, 0)), raises(ParameterError, r"polyorder must be an integer >= 1")),
    Case("differentiation", "window of 10**9", lambda: diff(dc.SavitzkyGolay(10**9 + 1)), raises(ShapeError, r"x has 100 samples, fewer than the 1000000001")),
    Case("differentiation", "smooth a word", lambda: diff(dc.SavitzkyGolay(smooth="yes")), raises(ParameterError, r"smooth must be True or False")),
    Case("differentiation", "spline order 7", lambda: diff(dc.Spline(order=7)), raises(ParameterError, r"Spline: order must be an integer >= 1 and <= 5")),
    Case("differentiation", "spline negative s", lambda: diff(dc.Spline(s=-1)), raises(ParameterError, r"Spline: s must be")),
    Case("differentiation", "smoothing spline negative lam", lambda: diff(dc.SmoothingSpline(lam=-1)), raises(ParameterError, r"SmoothingSpline: lam must be")),
    Case("differentiation", "trend filter order -1", lambda: diff(dc.TrendFiltered(order=-1)), raises(ParameterError, r"TrendFiltered: order must be")),
    Case("differentiation", "Kalman alpha 0", lambda: diff(dc.Kalman(alpha=0)), raises(ParameterError, r"Kalman: alpha must be")),
    Case("differentiation", "spectral cutoff 0", lambda: diff(dc.Spectral(cutoff=0)), raises(ParameterError, r"Spectral: cutoff must be")),
    Case("differentiation", "spectral cutoff 2", lambda: diff(dc.Spectral(cutoff=2)), raises(ParameterError, r"Spectral: cutoff must be")),
    Case("differentiation", "spectral on non-uniform t", lambda: diff(dc.Spectral(), t=T ** 2 + T), raises(DataError, r"Spectral needs uniformly spaced t")),
    Case("differentiation", "weak form window 4", lambda: dc.DiscrepancyModel(differentiation_method=dc.WeakForm(4)).fit(Z, 0.01), raises(ParameterError, r"WeakForm: window_length must be None or an odd integer >= 3; got 4")),
    Case("differentiation", "weak form power 1", lambda: dc.DiscrepancyModel(differentiation_method=dc.WeakForm(power=1)).fit(Z, 0.01), raises(ParameterError, r"WeakForm: power must be an integer >= 2")),
    Case("differentiation", "weak form called for a derivative", lambda: diff(dc.WeakForm(31)), raises(ParameterError, r"WeakForm has no pointwise derivative")),
    Case("differentiation", "weak window longer than x", lambda: dc.DiscrepancyModel(differentiation_method=dc.WeakForm(301)).fit(Z, 0.01), raises(ShapeError, r"window_length 301 is longer than a trajectory of 100")),
    Case("differentiation", "auto with an even degree", lambda: diff(dc.AutoSmoothing(polyorder=4)), raises(ParameterError, r"AutoSmoothing: polyorder must be an odd integer >= 3")),
    Case("differentiation", "auto looking at 10 rows", lambda: diff(dc.AutoSmoothing(sample_rows=10)), raises(ParameterError, r"sample_rows must be an integer >= 100")),
    Case("differentiation", "auto on 20 samples falls back to finite differences", lambda: diff("auto", Z[:20], T[:20]), returns(lambda v: np.allclose(v, np.gradient(Z[:20], T[:20], axis=0, edge_order=2), rtol=1e-12, atol=1e-12))),
    Case("differentiation", "dequantised with resolution 0", lambda: diff(dc.Dequantised(resolution=0), np.zeros((300, 1)), np.arange(300.0)), raises(ParameterError, r"resolution must be > 0")),
    Case("differentiation", "dequantised with a method of the wrong type", lambda: diff(dc.Dequantised(method=42, resolution=0.1)), raises(ParameterError, r"Dequantised: method must be")),
    Case("differentiation", "spec with a non-literal", lambda: get_differentiation_method("savitzky_golay(window_length=abc)"), raises(ParameterError, r"window_length must be .*; got 'abc'")),
    Case("differentiation", "spec unclosed", lambda: get_differentiation_method("savitzky_golay(window_length=31"), raises(ParameterError, r"savitzky_golay\(window_length=31")),
    Case("differentiation", "spec with an unknown option", lambda: get_differentiation_method("finite_difference(axis=1)"), raises(ParameterError, r"'finite_difference': FiniteDifference has no parameter 'axis'")),
    Case("differentiation", "constant x has derivative 0", lambda: diff("finite_difference", np.ones((100, 2))), returns(exact(np.zeros((100, 2))))),
    Case("differentiation", "finite differences exact on t^2, non-uniform t", lambda: diff("finite_difference", T_RAGGED[:, None] ** 2, T_RAGGED), returns(exact(2 * T_RAGGED[:, None], 1e-8))),
    Case("differentiation", "Savitzky-Golay exact on a cubic", lambda: diff(dc.SavitzkyGolay(7, 3), T[:, None] ** 3), returns(exact(3 * T[:, None] ** 2, 1e-8))),
    Case("differentiation", "model.differentiate of a map", lambda: dc.DiscrepancyModel(discrete_time=True).differentiate(Z), raises(ParameterError, r"discrete-time model has no derivatives")),
]


@params(CASES)
def test_case(case):
    check(case)
