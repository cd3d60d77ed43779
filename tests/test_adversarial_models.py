"""Adversarial rows for fitted models: predict, discrepancy, score, export, simulate and the
bootstrap (see ``adversarial.py`` for the machinery)."""
from __future__ import annotations

import pickle

import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from adversarial import Case, check, circle, fast, params, raises, returns
from discrepancy.errors import (
    ConvergenceError,
    DataError,
    ExportError,
    FeatureError,
    ModelFileError,
    NotFittedError,
    ParameterError,
    ResourceError,
    ShapeError,
    SimulationError,
)
from discrepancy.symbolic import symbol


def sklearn_not_fitted(call) -> bool:
    """Whether ``call`` raises an error that is ours and scikit-learn's NotFittedError."""
    import sklearn.exceptions
    try:
        call()
    except sklearn.exceptions.NotFittedError as e:
        return isinstance(e, NotFittedError)
    return False


T, X, XD = circle(400)
X1, X2 = symbol("x1"), symbol("x2")


S = np.linspace(0.5, 3, 200)[:, None]
U = np.cos(T)[:, None]
V = np.linspace(-2, 2, 401)[:, None]


@pytest.fixture(scope="module", autouse=True)
def fitted_models():
    """The rows' fitted models, fitted when the module's first row runs (see prepare)."""
    prepare()


def prepare():
    """The rows' fitted models (ROT, CALL, ...) as module globals, fitted once: not at
    collection (every worker collects every module); also called by the reach test, which
    runs rows of this table in a process where this module's tests did not run."""
    global ROT, CALL, SYM, LOG, FUNC, WITH_U, MAP, SIGN, SQUARE, NOISY, UNC
    if "UNC" in globals():
        return
    ROT = fast().fit(X, 0.01, x_dot=XD)                                      # g = rotation
    CALL = fast(prior=lambda x, u: np.c_[x[:, 1], 0 * x[:, 0]]).fit(X, 0.01, x_dot=XD)
    SYM = fast(prior=[X2, sp.Integer(0)]).fit(X, 0.01, x_dot=XD)
    LOG = fast(feature_library=dc.CustomLibrary([sp.log(X1)])).fit(S, 0.01, x_dot=2 * np.log(S))
    FUNC = fast(feature_library=dc.CustomLibrary(functions={"sq": np.square})).fit(S, 0.01, x_dot=S ** 2)
    WITH_U = fast(feature_library=dc.PolynomialLibrary(1)).fit(X[:, :1], 0.01, u=U, x_dot=-X[:, :1] + U)
    MAP = fast(discrete_time=True, feature_library=dc.PolynomialLibrary(1)).fit(0.9 ** np.arange(50.0)[:, None])
    SIGN = fast(feature_library=dc.CustomLibrary([sp.sign(X1)])).fit(V, 0.01, x_dot=-np.sign(V))
    SQUARE = fast(feature_library=dc.PolynomialLibrary(2)).fit(S, 1.0, x_dot=S ** 2)   # x' = x^2
    NOISY = fast().fit(X + 0.01 * np.random.default_rng(0).normal(size=X.shape), 0.01)
    UNC = NOISY.bootstrap(X, 0.01, x_dot=XD, n_resamples=20)


TS = np.linspace(0, 1, 11)


def score(metric, m=None, **kw):
    return (ROT if m is None else m).score(X, 0.01, x_dot=XD, metric=metric, **kw)


def sim(x0=(0.0, 1.0), t=TS, m=None, **kw):
    return (ROT if m is None else m).simulate(x0, t, **kw)


def exact(expected, atol=1e-6):
    return lambda value: np.allclose(value, expected, atol=atol)


def boot(**kw):
    return NOISY.bootstrap(X, 0.01, **{"n_resamples": 20, **kw})


CASES = [
    # --- predict and discrepancy
    Case("predict", "before fit", lambda: fast().predict(X), raises(NotFittedError, r"call fit\(x, t\) first")),
    Case("predict", "before fit, caught as scikit-learn's NotFittedError", lambda: sklearn_not_fitted(lambda: fast().predict(X)), returns(lambda v: v is True)),
    Case("model", "a fitted model through pickle", lambda: pickle.loads(pickle.dumps(SYM)).predict(X), returns(lambda v: np.allclose(v, XD, atol=1e-9))),
    Case("model", "a model with numpy function terms through pickle", lambda: pickle.loads(pickle.dumps(FUNC)).predict(S), returns(lambda v: np.allclose(v, S ** 2, atol=1e-9))),
    Case("predict", "predict_ahead of a map iterates it", lambda: MAP.predict_ahead(0.9 ** np.arange(6.0)[:, None], steps=2)[:, 0], returns(lambda v: np.allclose(v, 0.9 ** np.arange(2.0, 6.0), rtol=1e-9))),
    Case("model", "fit_outputs of a map", lambda: fast(discrete_time=True).fit_outputs(X, u=None, outputs=["x1", "x2"]), raises(ParameterError, r"fit_outputs simulates continuous-time models.*discrete_time=True")),
    Case("model", "fit_outputs with substeps=0", lambda: fast().fit_outputs(X[:, :1], t=0.01, outputs=["x1"], x0=[1.0, 0.0], substeps=0), raises(ParameterError, r"substeps must be an integer in \[1, 100\].*got 0")),
    Case("model", "estimate_initial_state with substeps=2.5", lambda: ROT.estimate_initial_state(X[:20, :1], t=0.01, outputs=["x1"], substeps=2.5), raises(ParameterError, r"substeps must be an integer in \[1, 100\].*got 2.5")),
    Case("model", "refine of a map", lambda: MAP.refine(0.9 ** np.arange(50.0), outputs=["x1"]), raises(ParameterError, r"refine simulates continuous-time models.*discrete_time=True")),
    Case("model", "estimate_initial_state of a map", lambda: MAP.estimate_initial_state(0.9 ** np.arange(50.0), outputs=["x1"]), raises(ParameterError, r"estimate_initial_state simulates continuous-time models")),
    Case("predict", "x with 3 columns", lambda: ROT.predict(np.zeros((5, 3))), raises(ShapeError, r"^x must have 2 columns")),
    Case("predict", "x with NaN", lambda: ROT.predict(np.full((5, 2), np.nan)), raises(DataError, r"^x must be finite")),
    Case("predict", "complex x", lambda: ROT.predict(X + 1j), raises(DataError, r"^x must be real")),
    Case("predict", "u for a model without inputs", lambda: ROT.predict(X, U), raises(ShapeError, r"u was given but the model was fitted without inputs")),
    Case("predict", "no u for a model with inputs", lambda: WITH_U.predict(X[:, :1]), raises(ShapeError, r"u is required.*\['u'\]")),
    Case("predict", "u with too few rows", lambda: WITH_U.predict(X[:, :1], U[:5]), raises(ShapeError, r"^u must have 400 rows")),
    Case("predict", "list x with an array u", lambda: WITH_U.predict([X[:, :1]], U), raises(ShapeError, r"^u must be a list of 1 arrays")),
    Case("predict", "one state as a flat row for two states", lambda: ROT.predict(np.array([0.1, 0.2])), raises(ShapeError, r"^x must be 2-D")),
    Case("predict", "a term undefined at the point", lambda: LOG.predict(np.array([[-1.0]])), raises(FeatureError, r"library column 'log\(x1\)' is nan at row 0 \(x1 = -1\)")),
    Case("predict", "a nested list of numbers", lambda: ROT.predict([[0.1, 0.2]]), raises(ShapeError, r"x is a list holding numbers; .*np.array\(x\)")),
    Case("predict", "discrepancy of a string", lambda: ROT.discrepancy("x"), raises(ShapeError, r"^x must be a numeric array")),
    Case("predict", "0 rows give 0 rows", lambda: ROT.predict(np.zeros((0, 2))), returns(lambda v: v.shape == (0, 2))),
    Case("predict", "right values", lambda: CALL.predict(X), returns(exact(XD))),
    Case("predict", "a list gives a list", lambda: ROT.discrepancy([X, X[:3]]), returns(lambda v: len(v) == 2 and np.allclose(v[1], XD[:3], atol=1e-6))),
    # --- score
    Case("score", "unknown metric", lambda: score("mse"), raises(ParameterError, r"metric must be one of r2, rmse, trajectory.*'mse'")),
    Case("score", "metric returning a word", lambda: score(lambda a, b: "x"), raises(ParameterError, r"metric must return a finite number \(or finite numbers\); got 'x'")),
    Case("score", "metric returning an array, as PySINDy's multioutput", lambda: score(lambda a, b: np.ones(3)), returns(exact(np.ones(3)))),
    Case("score", "metric returning NaN", lambda: score(lambda a, b: np.nan), raises(ParameterError, r"metric must return a finite number \(or finite numbers\); got nan")),
    Case("score", "metric returning None", lambda: score(lambda a, b: None), raises(ParameterError, r"metric must return a finite number \(or finite numbers\); got None")),
    Case("score", "metric raising", lambda: score(lambda a, b: 1 / 0), raises(ParameterError, r"metric raised ZeroDivisionError")),
    Case("score", "metric a number", lambda: score(42), raises(ParameterError, r"metric must be one of")),
    Case("score", "metric an array of names", lambda: score(np.array(["r2"])), raises(ParameterError, r"metric must be one of")),
    Case("score", "x with 3 columns", lambda: ROT.score(np.zeros((50, 3)), 0.01), raises(ShapeError, r"^x must have 2 columns \(the model's states")),
    Case("score", "u for a model without inputs", lambda: ROT.score(X, 0.01, u=U), raises(ShapeError, r"^u must have 0 columns")),
    Case("score", "trajectory metric on two trajectories", lambda: ROT.score([X, X], 0.01, metric="trajectory"), raises(ShapeError, r"metric='trajectory' scores one trajectory")),
    Case("score", "trajectory metric on x = 0", lambda: ROT.score(np.zeros((50, 2)), 0.01, metric="trajectory"), raises(DataError, r"norm of x, which is 0")),
    Case("score", "one sample", lambda: ROT.score(X[:1], 0.01), raises(ShapeError, r"^x must have at least 2 samples")),
    Case("score", "before fit", lambda: fast().score(X, 0.01), raises(NotFittedError, r"fit")),
    Case("score", "positional u", lambda: WITH_U.score(X[:, :1], 0.01, U), raises(ParameterError, r"must be passed by name")),
    Case("score", "exact model scores 1", lambda: score("r2"), returns(lambda v: abs(v - 1) < 1e-9)),
    Case("score", "trajectory error of the exact model", lambda: ROT.score(X, T, metric="trajectory"), returns(lambda v: v < 1e-6)),
    # --- export and output
    Case("export", "unknown part", lambda: ROT.to_sympy(part="everything"), raises(ParameterError, r"part must be one of 'hybrid', 'discrepancy'; got 'everything'")),
    Case("export", "hybrid of a callable prior", lambda: CALL.to_sympy(part="hybrid"), raises(ExportError, r"prior is a Python callable")),
    Case("export", "latex precision -1", lambda: ROT.to_latex(precision=-1), raises(ParameterError, r"to_latex: precision must be an integer >= 1")),
    Case("export", "latex precision 2.5", lambda: ROT.to_latex(precision=2.5), raises(ParameterError, r"precision must be an integer")),
    Case("export", "latex precision 10**6", lambda: ROT.to_latex(precision=10**6), raises(ParameterError, r"precision must be an integer >= 1 and <= 17")),
    Case("export", "equations precision a word", lambda: ROT.equations(precision="3"), raises(ParameterError, r"equations: precision must be an integer")),
    Case("export", "print lhs of one name", lambda: ROT.print(lhs=["a"]), raises(ParameterError, r"lhs must be a list of 2 strings")),
    Case("export", "print lhs a string", lambda: ROT.print(lhs="ab"), raises(ParameterError, r"lhs must be a list of 2 strings")),
    Case("export", "part an array", lambda: ROT.to_latex(part=np.zeros(0)), raises(ParameterError, r"part must be one of 'hybrid', 'discrepancy'")),
    Case("export", "save to a number", lambda: ROT.save(3), raises(ParameterError, r"path must be a file name \(text or a pathlib.Path\); got 3")),
    Case("export", "casadi of a callable prior", lambda: CALL.to_casadi(), raises(ExportError, r"callable")),
    Case("export", "casadi of a numpy function term", lambda: FUNC.to_casadi(part="discrepancy"), raises(ExportError, r"sq\(x1\)")),
    Case("export", "save to a folder", lambda: ROT.save("."), raises(ModelFileError, r"path '.' is a folder")),
    Case("export", "save into a missing folder", lambda: ROT.save("no/such/folder/m.json"), raises(ModelFileError, r"cannot write 'no/such/folder/m.json'")),
    Case("export", "save before fit", lambda: fast().save("m.json"), raises(NotFittedError, r"fit")),
    Case("export", "coefficients before fit", lambda: fast().coefficients(), raises(NotFittedError, r"fit")),
    Case("export", "with_coefficients of the wrong shape", lambda: ROT.with_coefficients(np.zeros((2, 3))), raises(ShapeError, r"coef must have shape \(2, 6\); got \(2, 3\)")),
    Case("export", "with_coefficients with NaN", lambda: ROT.with_coefficients(np.full((2, 6), np.nan)), raises(DataError, r"coef must be finite; got 12 non-finite entries")),
    Case("export", "with_coefficients of text", lambda: ROT.with_coefficients("abc"), raises(ShapeError, r"coef must be a numeric array; got 'abc'")),
    Case("export", "sympy of the hybrid", lambda: SYM.to_sympy(), returns(lambda e: e[0] == X2 and abs(float(e[1].coeff(X1)) + 1) < 1e-9)),
    Case("export", "latex of the discrepancy", lambda: CALL.to_latex(part="discrepancy"), returns(lambda s: "x_{1}" in s and "- 1.0" in s)),
    # --- simulate
    Case("simulate", "before fit", lambda: fast().simulate([0, 0], TS), raises(NotFittedError, r"fit")),
    Case("simulate", "x0 of 3 numbers", lambda: sim([0, 0, 0]), raises(ShapeError, r"^x0 must be 2 numbers")),
    Case("simulate", "x0 with NaN", lambda: sim([np.nan, 0]), raises(DataError, r"^x0 must be finite")),
    Case("simulate", "x0 a word", lambda: sim("ab"), raises(ShapeError, r"^x0 must be a numeric array")),
    Case("simulate", "x0 ragged", lambda: sim([[0.0], [1.0, 2.0]]), raises(ShapeError, r"^x0 must be a numeric array")),
    Case("simulate", "complex x0", lambda: sim([1j, 0]), raises(DataError, r"^x0 must be real")),
    Case("simulate", "one output time", lambda: sim(t=[0.0]), raises(ShapeError, r"^t must be a 1-D array of at least 2")),
    Case("simulate", "decreasing t", lambda: sim(t=TS[::-1]), raises(DataError, r"^t must be strictly increasing")),
    Case("simulate", "NaN in t", lambda: sim(t=[0, np.nan, 1]), raises(DataError, r"^t must be finite")),
    Case("simulate", "t a number", lambda: sim(t=3.0), raises(ShapeError, r"^t must be a 1-D array")),
    Case("simulate", "t 2-D", lambda: sim(t=TS[:, None]), raises(ShapeError, r"^t must be a 1-D array")),
    Case("simulate", "t of dates", lambda: sim(t=np.arange(5).astype("datetime64[s]")), raises(DataError, r"^t must be plain numbers")),
    Case("simulate", "unknown method", lambda: sim(method="bogus"), raises(ParameterError, r"method must be one of 'RK45'.*'bogus'")),
    Case("simulate", "method an array", lambda: sim(method=np.zeros(0)), raises(ParameterError, r"method must be one of 'RK45'")),
    Case("simulate", "rtol -10**30", lambda: sim(rtol=-10**30), raises(ParameterError, r"rtol must be a finite number > 0")),
    Case("simulate", "negative atol", lambda: sim(atol=-1), raises(ParameterError, r"atol must be a finite number > 0; got -1")),
    Case("simulate", "rtol 0", lambda: sim(rtol=0), raises(ParameterError, r"rtol must be a finite number > 0")),
    Case("simulate", "substeps 0", lambda: sim(method="rk4", substeps=0), raises(ParameterError, r"substeps must be an integer >= 1 and <= 10000")),
    Case("simulate", "max_evaluations 0", lambda: sim(max_evaluations=0), raises(ParameterError, r"max_evaluations must be None or an integer >= 1")),
    Case("simulate", "max_evaluations True", lambda: sim(max_evaluations=True), raises(ParameterError, r"max_evaluations must be None or an integer >= 1")),
    Case("simulate", "unknown option", lambda: sim(foo=1), raises(ParameterError, r"unknown option\(s\) \['foo'\]")),
    Case("simulate", "solver option with rk4", lambda: sim(method="rk4", max_step=0.1), raises(ParameterError, r"unknown option\(s\) \['max_step'\] for method 'rk4'")),
    Case("simulate", "unknown input hold", lambda: WITH_U.simulate([0.0], TS, u=np.zeros((11, 1)), u_hold="cubic"), raises(ParameterError, r"u_hold must be one of 'linear', 'zoh', 'bandlimited'; got 'cubic'")),
    Case("simulate", "u(t) of the wrong size", lambda: WITH_U.simulate([0.0], TS, u=lambda t: [0.0, 1.0]), raises(ShapeError, r"u\(t\) must return 1 finite value")),
    Case("simulate", "u(t) raising", lambda: WITH_U.simulate([0.0], TS, u=lambda t: 1 / 0), raises(ParameterError, r"u\(t\) raised ZeroDivisionError at t = 0")),
    Case("simulate", "u(t) NaN later", lambda: WITH_U.simulate([0.0], TS, u=lambda t: [np.nan if t > 0.5 else 0.0]), raises(ShapeError, r"u\(t\) must return 1 finite value.*at t = (0\.[6-9]|1)")),
    Case("simulate", "u(t) complex", lambda: WITH_U.simulate([0.0], TS, u=lambda t: [1j]), raises(DataError, r"u\(t\) must be real")),
    Case("simulate", "u(t) a word", lambda: WITH_U.simulate([0.0], TS, u=lambda t: "on"), raises(ShapeError, r"u\(t\) must be a numeric array")),
    Case("simulate", "sampled u with too few rows", lambda: WITH_U.simulate([0.0], TS, u=np.zeros((5, 1))), raises(ShapeError, r"^u must have 11 rows")),
    Case("simulate", "u for a model without inputs", lambda: sim(u=np.zeros((11, 1))), raises(ShapeError, r"u was given but the model has no inputs")),
    Case("simulate", "positional u", lambda: WITH_U.simulate([0.0], TS, np.zeros((11, 1))), raises(ParameterError, r"must be passed by name")),
    Case("simulate", "blow-up", lambda: SQUARE.simulate([1.0], np.linspace(0, 2, 21)), raises(SimulationError, r"simulation stopped at t = 1")),
    Case("simulate", "a learned sign term is bounded", lambda: SIGN.simulate([1.0], np.linspace(0, 2, 201)), returns(lambda x: np.allclose(x[:90, 0], 1 - np.linspace(0, 2, 201)[:90], atol=1e-6) and np.all(np.abs(x[110:]) < 0.02))),
    Case("simulate", "rotation is exact (LSODA)", lambda: sim(t=T), returns(exact(X, 1e-6))),
    Case("simulate", "rotation by compiled rk4", lambda: sim(t=T, method="rk4"), returns(exact(X, 1e-6))),
    Case("simulate", "rotation by rk4 stepped in Python", lambda: sim(t=T, method="rk4", compiled=False), returns(exact(X, 1e-6))),
    Case("simulate", "sampled input with a zero-order hold", lambda: WITH_U.simulate([0.0], T, u=np.ones((400, 1)), u_hold="zoh"), returns(lambda x: np.allclose(x[:, 0], 1 - np.exp(-T), atol=1e-6))),
    Case("simulate", "map for 10**12 steps", lambda: MAP.simulate([1.0], 10**12), raises(ResourceError, r"simulation's output \(1000000000000 steps x 1 states\)")),
    Case("simulate", "map for 0 steps", lambda: MAP.simulate([1.0], 0), raises(ParameterError, r"t must be the number of steps")),
    Case("simulate", "map for 2.5 steps", lambda: MAP.simulate([1.0], 2.5), raises(ParameterError, r"t must be the number of steps")),
    Case("simulate", "map for '10' steps", lambda: MAP.simulate([1.0], "10"), raises(ParameterError, r"t must be the number of steps")),
    Case("simulate", "map that diverges", lambda: MAP.with_coefficients(np.array([[0.0, 1e300]])).simulate([1e10], 5), raises(ConvergenceError, r"the map diverged at step")),
    Case("simulate", "map iterates exactly", lambda: MAP.simulate([1.0], 5), returns(exact(0.9 ** np.arange(5.0)[:, None], 1e-9))),
    # --- bootstrap and intervals
    Case("bootstrap", "0 resamples", lambda: boot(n_resamples=0), raises(ParameterError, r"bootstrap: n_resamples must be an integer >= 2")),
    Case("bootstrap", "1 resample", lambda: boot(n_resamples=1), raises(ParameterError, r"n_resamples must be an integer >= 2; got 1")),
    Case("bootstrap", "2.5 resamples", lambda: boot(n_resamples=2.5), raises(ParameterError, r"n_resamples must be an integer")),
    Case("bootstrap", "block_length 0", lambda: boot(block_length=0), raises(ParameterError, r"block_length must be an integer >= 2.*got 0")),
    Case("bootstrap", "block_length 1", lambda: boot(block_length=1), raises(ParameterError, r"block_length must be an integer >= 2")),
    Case("bootstrap", "block_length 3 does not divide the segment", lambda: boot(block_length=3), raises(ParameterError, r"divides the fit's cross-validation segment")),
    Case("bootstrap", "unknown method", lambda: boot(method="jackknife"), raises(ParameterError, r"bootstrap: method must be one of 'wild', 'pairs'")),
    Case("bootstrap", "seed a word", lambda: boot(seed="a"), raises(ParameterError, r"bootstrap: seed must be None or an integer >= 0")),
    Case("bootstrap", "negative seed", lambda: boot(seed=-1), raises(ParameterError, r"seed must be")),
    Case("bootstrap", "data with 3 columns", lambda: NOISY.bootstrap(np.zeros((400, 3)), 0.01), raises(ShapeError, r"^x must have 2 columns")),
    Case("bootstrap", "too few blocks", lambda: NOISY.bootstrap(X[:40], 0.01, n_resamples=5, block_length=16), raises(ParameterError, r"only \d+ blocks")),
    Case("bootstrap", "before fit", lambda: fast().bootstrap(X, 0.01), raises(NotFittedError, r"fit")),
    Case("bootstrap", "10**12 resamples", lambda: boot(n_resamples=10**12), raises(ResourceError, r"1000000000000 resampled coefficient matrices")),
    Case("bootstrap", "exact data have no spread", lambda: ROT.bootstrap(X, 0.01, x_dot=XD, n_resamples=10).std, returns(lambda s: np.all(s < 1e-8))),
    Case("bootstrap", "interval of another model's bootstrap", lambda: CALL.predict_interval(X, uncertainty=UNC), raises(ParameterError, r"uncertainty must be this model's bootstrap")),
    Case("bootstrap", "interval of a number", lambda: NOISY.predict_interval(X, uncertainty=3), raises(ParameterError, r"uncertainty must be this model's bootstrap")),
    Case("bootstrap", "level 1.5", lambda: NOISY.predict_interval(X, uncertainty=UNC, level=1.5), raises(ParameterError, r"level must be a finite number > 0 and < 1; got 1.5")),
    Case("bootstrap", "simulated band of 1 draw", lambda: NOISY.simulate_interval([0, 1], TS, uncertainty=UNC, n_draws=1), raises(ParameterError, r"n_draws must be None or an integer >= 2")),
    Case("bootstrap", "simulated band with seed 'x'", lambda: NOISY.simulate_interval([0, 1], TS, uncertainty=UNC, seed="x"), raises(ParameterError, r"simulate_interval: seed must be None or an integer >= 0")),
    Case("bootstrap", "simulated band at level 0", lambda: NOISY.simulate_interval([0, 1], TS, uncertainty=UNC, level=0), raises(ParameterError, r"level must be a finite number > 0 and < 1")),
]


@params(CASES)
def test_case(case, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    check(case)
