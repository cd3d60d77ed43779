"""Adversarial rows for ``DiscrepancyModel(...)`` and ``fit``: data, times, inputs, weights,
the prior and every constructor argument (see ``adversarial.py`` for the machinery)."""
from __future__ import annotations

import numpy as np
import sympy as sp

import discrepancy as dc
from adversarial import Case, check, circle, fast, params, raises, returns
from discrepancy.errors import (
    ConvergenceError,
    DataError,
    FeatureError,
    ParameterError,
    PriorError,
    ShapeError,
    UnknownNameError,
)
from discrepancy.symbolic import symbol

T, X, XD = circle(200)
U = np.sin(3 * T)[:, None]
X1, X2 = symbol("x1"), symbol("x2")
MODEL_ARGS = ("prior", "feature_library", "optimizer", "differentiation_method", "state_names",
              "input_names", "constraints", "discrete_time")


def fit(x=X, t=0.01, **kw):
    """A fast fit (finite differences, fixed threshold) with any argument replaced."""
    return fast(**{k: kw.pop(k) for k in list(kw) if k in MODEL_ARGS}).fit(x, t, **kw)


def put(a, value, i=3, j=0):
    """A copy of ``a`` with ``a[i, j] = value`` (``j`` None: a 1-D row)."""
    out = np.array(a, dtype=np.result_type(a, value))
    out[(i,) if out.ndim == 1 else (i, j)] = value
    return out


def prior(value):
    """A prior returning ``value(x)``."""
    return lambda x, u=None: value(x)


def coef_close(reference):
    return lambda m: np.allclose(m.coef_, reference().coef_, atol=1e-10)


ROTATION = np.array([[0, 0, 1.0, 0, 0, 0], [0, -1.0, 0, 0, 0, 0]])  # x1' = x2, x2' = -x1


def rotation(model) -> bool:
    return np.allclose(model.coef_, ROTATION, atol=1e-6)

CASES = [
    # --- x
    Case("fit", "x with NaN", lambda: fit(put(X, np.nan)), raises(DataError, r"^x must be finite.*row 3")),
    Case("fit", "x with inf in column 1", lambda: fit(put(X, np.inf, 5, 1)), raises(DataError, r"^x must be finite.*row 5, column 1")),
    Case("fit", "x with -inf", lambda: fit(put(X, -np.inf)), raises(DataError, r"^x must be finite")),
    Case("fit", "complex x", lambda: fit(X + 1j), raises(DataError, r"^x must be real")),
    Case("fit", "x of strings", lambda: fit(np.full((50, 2), "a")), raises(ShapeError, r"^x must be a numeric array")),
    Case("fit", "ragged x", lambda: fit([[1.0, 2.0], [3.0]]), raises(ShapeError, r"x\[0\] must be a numeric array|^x")),
    Case("fit", "3-D x", lambda: fit(np.zeros((20, 2, 2))), raises(ShapeError, r"^x must be 2-D")),
    Case("fit", "x with 0 columns", lambda: fit(np.zeros((50, 0))), raises(ShapeError, r"^x must have at least 1 column")),
    Case("fit", "x with 1 row", lambda: fit(X[:1]), raises(ShapeError, r"^x must have at least 2 samples")),
    Case("fit", "x with 0 rows", lambda: fit(X[:0]), raises(ShapeError, r"^x must have at least 2 samples")),
    Case("fit", "x None", lambda: fit(None), raises(ShapeError, r"^x must be")),
    Case("fit", "x a number", lambda: fit(3.0), raises(ShapeError, r"^x must be")),
    Case("fit", "x a string", lambda: fit("data.csv"), raises(ShapeError, r"^x must be a numeric array")),
    Case("fit", "x a dict", lambda: fit({"x": X}), raises(ShapeError, r"^x must be")),
    Case("fit", "x of datetimes", lambda: fit(np.arange(10).astype("datetime64[s]")), raises(DataError, r"^x must be plain numbers")),
    Case("fit", "x an empty list", lambda: fit([]), raises(ShapeError, r"^x must hold at least one trajectory")),
    Case("fit", "x trajectories of 2 and 3 columns", lambda: fit([X, np.c_[X, X[:, 0]]]), raises(ShapeError, r"x\[1\]")),
    Case("fit", "NaN in the second trajectory", lambda: fit([X, put(X, np.nan, 7, 1)]), raises(DataError, r"^x\[1\] must be finite.*row 7, column 1")),
    Case("fit", "second trajectory of 1 row", lambda: fit([X, X[:1]]), raises(ShapeError, r"^x\[1\] must have at least 2 samples")),
    Case("fit", "x a list of Chunk objects", lambda: fit([dc.Chunk(X[:100]), dc.Chunk(X[100:])]), raises(ParameterError, r"^x is a list of Chunk.*iter\(")),
    Case("fit", "x that overflows the library", lambda: fit(X * 1e300), raises(FeatureError, r"library column '.*' (is inf|overflows)")),
    Case("fit", "integer x", lambda: fit((100 * X).astype(int), x_dot=(100 * XD).astype(int)), returns(rotation)),
    Case("fit", "float32 x", lambda: fit(X.astype(np.float32), x_dot=XD), returns(rotation)),
    Case("fit", "1-D x is one state", lambda: fit(np.exp(-T), x_dot=-np.exp(-T)), returns(lambda m: m.n_states_ == 1 and np.isclose(m.coef_[0, 1], -1))),
    Case("fit", "x a tuple of trajectories", lambda: fit((X, X), x_dot=(XD, XD)), returns(rotation)),
    Case("fit", "constant x: g is 0", lambda: fit(np.ones((50, 2))), returns(lambda m: m.complexity == 0)),
    Case("fit", "boolean x", lambda: fit(X > 0), returns(lambda m: m.coef_.shape == (2, 6))),
    # --- t
    Case("fit", "t = 0", lambda: fit(t=0.0), raises(DataError, r"^t as a time step must be a positive")),
    Case("fit", "negative step", lambda: fit(t=-0.01), raises(DataError, r"^t as a time step must be a positive")),
    Case("fit", "NaN step", lambda: fit(t=np.nan), raises(DataError, r"^t as a time step must be a positive")),
    Case("fit", "inf step", lambda: fit(t=np.inf), raises(DataError, r"^t as a time step must be a positive")),
    Case("fit", "t a word", lambda: fit(t="fast"), raises(DataError, r"^t must be a positive time step")),
    Case("fit", "t True", lambda: fit(t=True), raises(DataError, r"^t must be a positive time step")),
    Case("fit", "t complex", lambda: fit(t=0.01j), raises(DataError, r"^t")),
    Case("fit", "t of the wrong length", lambda: fit(t=T[:-1]), raises(ShapeError, r"^t must be a step or a 1-D array of 200")),
    Case("fit", "decreasing t", lambda: fit(t=T[::-1]), raises(DataError, r"^t must be strictly increasing.*t\[1\]")),
    Case("fit", "repeated time", lambda: fit(t=put(T, T[4], 5, None)), raises(DataError, r"^t must be strictly increasing.*t\[5\]")),
    Case("fit", "NaN time", lambda: fit(t=put(T, np.nan, 9, None)), raises(DataError, r"^t must be finite.*row 9")),
    Case("fit", "datetime t", lambda: fit(t=np.arange(200).astype("datetime64[ms]")), raises(DataError, r"^t must be plain numbers")),
    Case("fit", "t as a column (m, 1)", lambda: fit(t=T[:, None]), raises(ShapeError, r"^t must be 1-D")),
    Case("fit", "t list shorter than x list", lambda: fit([X, X], t=[T]), raises(ShapeError, r"^t must be a list of 2")),
    Case("fit", "t a dict", lambda: fit(t={"dt": 0.01}), raises(DataError, r"^t must be a positive time step")),
    Case("fit", "step so small the derivatives overflow", lambda: fit(X * 1e10, t=1e-300), raises(FeatureError, r"target of equation 0.*overflows|is inf")),
    Case("fit", "step so large the times overflow", lambda: fit(t=1e308), raises(DataError, r"^t as a time step of 1e\+308 puts the last of 200 samples beyond float range")),
    Case("fit", "non-uniform t with Savitzky-Golay", lambda: fit(t=T ** 1.5, differentiation_method="savitzky_golay"), raises(DataError, r"uniformly spaced t")),
    Case("fit", "t None is a unit step", lambda: fit(X, None, x_dot=XD), returns(rotation)),
    Case("fit", "numpy float32 step", lambda: fit(t=np.float32(0.01), x_dot=XD), returns(rotation)),
    # --- u
    Case("fit", "u with too few rows", lambda: fit(u=U[:-1]), raises(ShapeError, r"^u must have 200 rows")),
    Case("fit", "u with NaN", lambda: fit(u=put(U, np.nan, 11)), raises(DataError, r"^u must be finite.*row 11")),
    Case("fit", "complex u", lambda: fit(u=U + 1j), raises(DataError, r"^u must be real")),
    Case("fit", "3-D u", lambda: fit(u=U[:, :, None]), raises(ShapeError, r"^u must be 2-D")),
    Case("fit", "u with 0 columns", lambda: fit(u=np.zeros((200, 0))), raises(ShapeError, r"^u must have at least 1 column")),
    Case("fit", "u an array for a list of x", lambda: fit([X, X], u=U), raises(ShapeError, r"^u must be a list of 2")),
    Case("fit", "u for some trajectories only", lambda: fit([X, X], u=[U, None]), raises(ShapeError, r"^u must be given for all trajectories")),
    Case("fit", "u of strings", lambda: fit(u=np.full((200, 1), "on")), raises(ShapeError, r"^u must be a numeric array")),
    Case("fit", "u with 1 vs 2 columns across trajectories", lambda: fit([X, X], u=[U, np.c_[U, U]]), raises(ShapeError, r"every u must have 1 input")),
    Case("fit", "1-D u is one input", lambda: fit(u=U[:, 0], x_dot=XD), returns(lambda m: m.n_inputs_ == 1 and m.input_names_ == ["u"])),
    # --- x_dot
    Case("fit", "x_dot with 3 columns", lambda: fit(x_dot=np.zeros((200, 3))), raises(ShapeError, r"^x_dot must have 2 columns")),
    Case("fit", "x_dot with NaN", lambda: fit(x_dot=put(XD, np.nan, 12, 1)), raises(DataError, r"^x_dot must be finite.*row 12, column 1")),
    Case("fit", "x_dot with too few rows", lambda: fit(x_dot=XD[:10]), raises(ShapeError, r"^x_dot must have 200 rows")),
    Case("fit", "complex x_dot", lambda: fit(x_dot=XD * 1j), raises(DataError, r"^x_dot must be real")),
    Case("fit", "x_dot an array for a list of x", lambda: fit([X, X], x_dot=XD), raises(ShapeError, r"^x_dot must be a list of 2")),
    # --- sample_weight
    Case("fit", "negative weight", lambda: fit(sample_weight=put(np.ones(200), -1.0, 4, None)), raises(DataError, r"^sample_weight must be >= 0.*row 4")),
    Case("fit", "NaN weight", lambda: fit(sample_weight=put(np.ones(200), np.nan, 6, None)), raises(DataError, r"^sample_weight must be finite.*row 6")),
    Case("fit", "weights of the wrong length", lambda: fit(sample_weight=np.ones(199)), raises(ShapeError, r"^sample_weight must have 200 rows")),
    Case("fit", "all weights zero", lambda: fit(sample_weight=np.zeros(200)), raises(DataError, r"^sample_weight must have at least one positive")),
    Case("fit", "weight a word", lambda: fit(sample_weight="heavy"), raises(ShapeError, r"^sample_weight must be a numeric array")),
    Case("fit", "2-D weights", lambda: fit(sample_weight=np.ones((200, 2))), raises(ShapeError, r"^sample_weight must be 1-D")),
    Case("fit", "weights list for one trajectory of two", lambda: fit([X, X], sample_weight=[1.0]), raises(ShapeError, r"^sample_weight must be a list of 2")),
    Case("fit", "one trajectory weighted 0, the other 1", lambda: fit([X, 5 * X], x_dot=[XD, XD], sample_weight=[1.0, 0.0]), returns(rotation)),
    Case("fit", "a scalar weight is no weight", lambda: fit(x_dot=XD, sample_weight=3.0), returns(coef_close(lambda: fit(x_dot=XD)))),
    Case("fit", "positional u after t", lambda: dc.DiscrepancyModel().fit(X, 0.01, U), raises(ParameterError, r"must be passed by name")),
    # --- prior
    Case("prior", "a number", lambda: fit(prior=42), raises(ParameterError, r"prior must be None or a callable")),
    Case("prior", "a string", lambda: fit(prior="x2"), raises(ParameterError, r"prior must be")),
    Case("prior", "an empty list", lambda: fit(prior=[]), raises(ParameterError, r"prior must be")),
    Case("prior", "one expression for two states", lambda: fit(prior=[X2]), raises(ParameterError, r"prior must have one expression per state")),
    Case("prior", "strings instead of expressions", lambda: fit(prior=["x2", "x1"]), raises(ParameterError, r"prior\[0\] must be a sympy expression")),
    Case("prior", "an unknown symbol", lambda: fit(prior=[X2, symbol("y")]), raises(UnknownNameError, r"prior\[1\].*\['y'\]")),
    Case("prior", "a complex sympy constant", lambda: fit(prior=[X2 + sp.I, X1]), raises(PriorError, r"prior\[0\].*I is not a finite real")),
    Case("prior", "sympy zoo (1/0)", lambda: fit(prior=[X2 / 0, X1]), raises(PriorError, r"prior\[0\].*zoo is not a finite real")),
    Case("prior", "sympy log of a negative", lambda: fit(prior=[sp.log(X1 - 5), X1]), raises(PriorError, r"prior")),
    Case("prior", "returns complex", lambda: fit(prior=prior(lambda x: x + 0j)), raises(PriorError, r"^prior must return real values")),
    Case("prior", "returns one column", lambda: fit(prior=prior(lambda x: x[:, :1])), raises(PriorError, r"prior must return an array of shape \(200, 2\).*\(200, 1\)")),
    Case("prior", "returns x transposed", lambda: fit(prior=prior(lambda x: x.T)), raises(PriorError, r"prior must return .*\(2, 200\)")),
    Case("prior", "returns NaN", lambda: fit(prior=prior(lambda x: x * np.nan)), raises(PriorError, r"prior returned non-finite values")),
    Case("prior", "raises", lambda: fit(prior=prior(lambda x: 1 / 0)), raises(PriorError, r"prior raised ZeroDivisionError")),
    Case("prior", "returns a string", lambda: fit(prior=prior(lambda x: "fast")), raises(PriorError, r"prior must return a numeric array")),
    Case("prior", "returns None", lambda: fit(prior=prior(lambda x: None)), raises(PriorError, r"prior must return")),
    Case("prior", "takes three arguments", lambda: fit(prior=lambda x, u, p: x), raises(PriorError, r"prior raised TypeError")),
    Case("prior", "returns a scalar", lambda: fit(prior=prior(lambda x: 1.0)), raises(PriorError, r"prior must return an array of shape")),
    Case("prior", "returns nested lists", lambda: fit(prior=prior(lambda x: x.tolist()), x_dot=XD), returns(lambda m: m.coef_.shape == (2, 6))),
    Case("prior", "takes x only", lambda: fit(prior=lambda x: np.c_[x[:, 1], -x[:, 0]], x_dot=XD), returns(lambda m: np.allclose(m.coef_, 0, atol=1e-9))),
    Case("prior", "sympy prior equal to the truth", lambda: fit(prior=[X2, -X1], x_dot=XD), returns(lambda m: np.allclose(m.coef_, 0, atol=1e-9))),
    # --- library, optimizer and differentiation arguments of the model
    Case("model", "feature_library a number", lambda: fit(feature_library=42), raises(ParameterError, r"feature_library must be")),
    Case("model", "feature_library the class", lambda: fit(feature_library=dc.PolynomialLibrary), raises(ParameterError, r"feature_library must be")),
    Case("model", "library spec unclosed", lambda: fit(feature_library="poly("), raises(ParameterError, r"library spec 'poly\('")),
    Case("model", "library spec trailing +", lambda: fit(feature_library="poly(2) + "), raises(ParameterError, r"library spec")),
    Case("model", "library spec unknown name", lambda: fit(feature_library="cubic(3)"), raises(ParameterError, r"unknown library 'cubic'")),
    Case("model", "library spec negative degree", lambda: fit(feature_library="poly(-1)"), raises(ParameterError, r"library spec")),
    Case("model", "library spec fractional degree", lambda: fit(feature_library="poly(2.5)"), raises(ParameterError, r"library spec")),
    Case("model", "library spec unknown variable", lambda: fit(feature_library="poly(2, x9)"), raises(UnknownNameError, r"'x9'")),
    Case("model", "library spec empty", lambda: fit(feature_library=""), raises(ParameterError, r"library spec")),
    Case("model", "library spec with code", lambda: fit(feature_library="__import__('os')"), raises(ParameterError, r"library spec")),
    Case("model", "library spec power", lambda: fit(feature_library="poly(2)**2"), raises(ParameterError, r"library spec")),
    Case("model", "library spec poly(2)", lambda: fit(feature_library="poly(2)", x_dot=XD), returns(rotation)),
    Case("model", "optimizer spec 'stlsq'", lambda: fit(optimizer="stlsq", x_dot=XD), returns(rotation)),
    Case("model", "optimizer negative threshold", lambda: fit(optimizer="stlsq(threshold=-1)"), raises(ParameterError, r"threshold")),
    Case("model", "optimizer unknown", lambda: fit(optimizer="bogus"), raises(UnknownNameError, r"'bogus'")),
    Case("model", "optimizer spec with code", lambda: fit(optimizer="stlsq(threshold=__import__('os'))"), raises(ParameterError, r"optimizer|threshold")),
    Case("model", "optimizer a number", lambda: fit(optimizer=42), raises(ParameterError, r"optimizer must be")),
    Case("model", "optimizer the class", lambda: fit(optimizer=dc.STLSQ), raises(ParameterError, r"optimizer must be")),
    Case("model", "differentiation unknown", lambda: fit(differentiation_method="savgol"), raises(UnknownNameError, r"'savgol'")),
    Case("model", "differentiation np.gradient", lambda: fit(differentiation_method=np.gradient), raises(ParameterError, r"differentiation_method must be")),
    Case("model", "differentiation even window", lambda: fit(differentiation_method="savitzky_golay(window_length=4)"), raises(ParameterError, r"window_length must be an odd integer")),
    Case("model", "differentiation window longer than x", lambda: fit(differentiation_method=dc.SavitzkyGolay(301)), raises(ShapeError, r"x has 200 samples.*301")),
    Case("model", "state_names too few", lambda: fit(state_names=["a"]), raises(ShapeError, r"^state_names must have 2 names")),
    Case("model", "state_names repeated", lambda: fit(state_names=["a", "a"]), raises(ShapeError, r"^state_names must be distinct identifiers")),
    Case("model", "state_names with a space", lambda: fit(state_names=["a", "b c"]), raises(ShapeError, r"^state_names must be distinct identifiers")),
    Case("model", "state_names numbers", lambda: fit(state_names=[1, 2]), raises(ParameterError, r"state_names must be")),
    Case("model", "state_names a keyword", lambda: fit(state_names=["lambda", "b"], x_dot=XD), returns(lambda m: m.get_feature_names()[1] == "lambda")),
    Case("model", "state_names a function name", lambda: fit(state_names=["sin", "cos"], x_dot=XD), returns(rotation)),
    Case("model", "state named like an input", lambda: fit(u=U, state_names=["a", "u"], input_names=["u"]), raises(ParameterError, r"must not share names.*\['u'\]")),
    Case("model", "input_names too many", lambda: fit(u=U, input_names=["a", "b"]), raises(ShapeError, r"^input_names must have 1 names")),
    Case("model", "constraints a number", lambda: fit(constraints=42), raises(ParameterError, r"constraints must be")),
    Case("model", "constraints on an unknown state", lambda: fit(constraints=dc.Constraints(exact_equations=["x9"])), raises(UnknownNameError, r"'x9'")),
    Case("model", "constraints with Lasso", lambda: fit(optimizer=dc.Lasso(), constraints=dc.Constraints(exact_equations=["x1"])), raises(ParameterError, r"constraints need an optimizer")),
    Case("model", "constraints naming a state as a string", lambda: fit(constraints=dc.Constraints(exact_equations="x1")), raises(ParameterError, r"Constraints.exact_equations must be a list of state names; got the string 'x1'")),
    Case("model", "constraints that cannot all hold", lambda: fit(constraints=dc.Constraints(equal=[({("x1", "x2"): 1}, 1)], at_most=[({("x1", "x2"): 1}, 0)])), raises(ConvergenceError, r"inconsistent")),
    Case("model", "make_setup of -1 states", lambda: dc.DiscrepancyModel().make_setup(-1, 0), raises(ParameterError, r"make_setup: n_states must be an integer >= 1; got -1")),
    Case("model", "make_setup of 2.5 states", lambda: dc.DiscrepancyModel().make_setup(2.5, 0), raises(ParameterError, r"make_setup: n_states must be an integer >= 1; got 2.5")),
    Case("model", "fit_statistics of text", lambda: fit(x_dot=XD).fit_statistics("stats", fit(x_dot=XD).setup_), raises(ParameterError, r"stats must be GramStatistics")),
    Case("model", "Van der Pol with alpha 'a'", lambda: dc.systems.VanDerPol(alpha="a"), raises(ParameterError, r"VanDerPol: alpha must be a finite number; got 'a'")),
    Case("model", "Van der Pol rhs of 3 states", lambda: dc.systems.VanDerPol().rhs(np.zeros((3, 3))), raises(ShapeError, r"^x must have 2 columns")),
    Case("model", "constraints only a string", lambda: dc.Constraints(only="x1"), raises(ParameterError, r"Constraints.only must be None or a mapping")),
    Case("model", "constraints equal a number", lambda: dc.Constraints(equal=3), raises(ParameterError, r"Constraints.equal must be a list")),
    Case("model", "Savitzky-Golay window None", lambda: fit(differentiation_method=dc.SavitzkyGolay(window_length=None)), raises(ParameterError, r"SavitzkyGolay: window_length must be an odd integer >= 3 or a list.*got None")),
    Case("model", "Kalman too smooth to solve", lambda: dc.Kalman(alpha=1e12)(*circle(400)[1::-1]), raises(ConvergenceError, r"Kalman\(alpha=1000000000000.0\) failed on these data")),
    Case("model", "trend filter of 10**12 iterations", lambda: fit(differentiation_method=dc.TrendFiltered(max_iter=10**12)), raises(ConvergenceError, r"TrendFiltered.* failed on these data \(OverflowError")),
    Case("model", "Dequantised encoders of text", lambda: fit(differentiation_method=dc.Dequantised(resolution=1e-6, encoders="x")), raises(ShapeError, r"encoders must be a numeric array")),
    Case("model", "discrete_time a word", lambda: fit(discrete_time="yes"), raises(ParameterError, r"discrete_time must be")),
]


@params(CASES)
def test_case(case):
    check(case)
