"""Adversarial rows that could hang or allocate without bound: run in one child process
under a memory cap and a time limit per row (see ``adversarial.run_isolated``). Each row is
one expression, evaluated after ``PRELUDE``; it must raise the expected DiscrepancyError
(well within its time limit) or return the right answer."""
from __future__ import annotations

import pytest

from adversarial import Case, check_isolated, params, raises, returns, run_isolated_once
from discrepancy.errors import (
    DataError,
    FeatureError,
    ModelFileError,
    ParameterError,
    ResourceError,
    ShapeError,
    SimulationError,
)

PRELUDE = """
import json, subprocess, sys
import numpy as np, sympy as sp
import dask.array as da
import discrepancy as dc
from discrepancy.symbolic import symbol
T = np.arange(2000) * 0.01
X = np.c_[np.sin(T), np.cos(T)]
XD = np.c_[X[:, 1], -X[:, 0]]
RNG = np.random.default_rng(0)
FD = "finite_difference"

def fit(x=X, library=None, **kw):
    return dc.DiscrepancyModel(feature_library=library, differentiation_method=FD,
                               optimizer=dc.STLSQ(threshold=0.05)).fit(x, 0.01, **kw)

def wide(n, m=200):
    return RNG.normal(size=(m, n))

def model_file(features):
    doc = fit(x_dot=XD).to_state()
    doc["features"] = features
    doc["coefficients"] = [[1.0] * len(features)] * 2
    with open("m.json", "w") as f:
        json.dump(doc, f)
    return dc.load_model("m.json")

def cli(*argv):
    run = subprocess.run([sys.executable, "-m", "discrepancy.cli", *argv], capture_output=True,
                         text=True, timeout=60)
    lines = run.stderr.strip().splitlines()
    return run.returncode if len(lines) == 1 and lines[0].startswith("error: ") else run.stderr

def names(n):
    return [f"v{i}" for i in range(n)]

def plan(**kw):
    import casadi as ca
    from discrepancy.control import plan_trajectory
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    double = ca.Function("f", [x, u], [ca.vertcat(x[1], u)])
    return plan_trajectory(double, **{"x0": [0, 0], "xf": [1, 0], "T": 1.0, "n_intervals": 10,
                                      **kw})

def sign_model():
    v = np.linspace(-2, 2, 401)[:, None]
    lib = dc.CustomLibrary([sp.sign(symbol("x1"))])
    return dc.DiscrepancyModel(feature_library=lib, differentiation_method=FD,
                               optimizer=dc.STLSQ(threshold=0.05)).fit(v, 0.01, x_dot=-np.sign(v))
"""

CASES = [
    Case("isolated", "fit: Fourier library of 10**9 frequencies", "fit(library=dc.FourierLibrary(10**9))", raises(ResourceError, r"FourierLibrary\(n_frequencies=1000000000\) of 2 variables would have 4,000,000,000 columns")),
    Case("isolated", "fit: degree 3 on 400 states", "fit(wide(400), library=dc.PolynomialLibrary(3))", raises(ResourceError, r"of 400 variables would have 10,827,401 columns")),
    Case("isolated", "fit: degree 10 on 50 states", "fit(wide(50), library=dc.PolynomialLibrary(10))", raises(ResourceError, r"75,394,027,566 columns")),
    Case("isolated", "fit: degree 5 on 20 states", "fit(wide(20), library=dc.PolynomialLibrary(5))", raises(ResourceError, r"53,130 columns")),
    Case("isolated", "fit: degree 4 on 20 states (Gram statistics)", "fit(wide(20), library=dc.PolynomialLibrary(4))", raises(ResourceError, r"the Gram statistics of 10626 library columns would need \d+(\.\d+)? GB")),
    Case("isolated", "fit: degree 10**20 on 10 states", "fit(wide(10), library=dc.PolynomialLibrary(10**20))", raises(ResourceError, r"about 10\^\d+ columns")),
    Case("isolated", "fit: degree 30 on 10 states", "fit(wide(10), library=dc.PolynomialLibrary(30))", raises(ResourceError, r"847,660,528 columns")),
    Case("isolated", "fit: spec poly(99999999999999999999)", "fit(wide(3), library='poly(99999999999999999999)')", raises(ResourceError, r"about 10\^\d+ columns")),
    Case("isolated", "fit: product of four degree-2 libraries on 10 states", "fit(wide(10), library=dc.PolynomialLibrary(2) * dc.PolynomialLibrary(2) * dc.PolynomialLibrary(2) * dc.PolynomialLibrary(2))", raises(ResourceError, r"columns; at most 50,000")),
    Case("isolated", "fit: weak form of 10**6 samples and 1771 columns", "dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(3), differentiation_method=dc.WeakForm(61), optimizer=dc.STLSQ(threshold=0.1)).fit(wide(20, 10**6), 0.01)", raises(ResourceError, r"weak form's integrals of 1000000 samples and 1771 columns")),
    Case("isolated", "bootstrap: blocks of 2 rows of 252 columns", "dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(5), differentiation_method=FD, optimizer=dc.STLSQ(threshold=0.1)).fit(wide(5, 20000), 0.01, x_dot=wide(5, 20000)).bootstrap(wide(5, 20000), 0.01, x_dot=wide(5, 20000), block_length=2, n_resamples=2)", raises(ResourceError, r"bootstrap's statistics of about 10000 blocks of 252 columns")),
    Case("isolated", "bootstrap: interval of 10**7 samples x 500 resamples", "(lambda m: m.predict_interval(np.zeros((10**7, 2)), uncertainty=m.bootstrap(X, 0.01, x_dot=XD, n_resamples=500)))(fit(x_dot=XD))", raises(ResourceError, r"500 resampled predictions of 10000000 samples")),
    Case("isolated", "library alone: degree 10**20 on 10 variables", "dc.PolynomialLibrary(10**20).fit(names(10))", raises(ResourceError, r"PolynomialLibrary\(degree=100000000000000000000\) of 10 variables would have about 10\^")),
    Case("isolated", "library alone: degree 3 on 400 variables", "dc.PolynomialLibrary(3).fit(names(400))", raises(ResourceError, r"of 400 variables would have 10,827,401 columns")),
    Case("isolated", "library alone: degree 10 on 50 variables", "dc.PolynomialLibrary(10).fit(names(50))", raises(ResourceError, r"75,394,027,566 columns; at most 50,000")),
    Case("isolated", "library alone: degree 5 on 20 variables", "dc.PolynomialLibrary(5).fit(names(20))", raises(ResourceError, r"53,130 columns")),
    Case("isolated", "library alone: degree 30 on 10 variables", "dc.PolynomialLibrary(30).fit(names(10))", raises(ResourceError, r"847,660,528 columns")),
    Case("isolated", "library alone: degree 10**9, powers only", "dc.PolynomialLibrary(10**9, include_interaction=False).fit(['x1'])", raises(ResourceError, r"1,000,000,001 columns")),
    Case("isolated", "library alone: degree 10**20 of distinct products", "dc.PolynomialLibrary(10**20, interaction_only=True).fit(['a', 'b', 'c']).n_features_", returns(lambda v: v == "8")),
    Case("isolated", "library alone: 10**9 Fourier frequencies", "dc.FourierLibrary(10**9).fit(['a', 'b'])", raises(ResourceError, r"FourierLibrary\(n_frequencies=1000000000\) of 2 variables would have 4,000,000,000")),
    Case("isolated", "library alone: product of 600 x 600 columns", "(dc.FourierLibrary(300) * dc.FourierLibrary(300)).fit(['a'])", raises(ResourceError, r"would have 360,000 columns")),
    Case("isolated", "library alone: spec fourier(1000000000)", "dc.libraries.spec.parse_library('fourier(1000000000)').fit(['a', 'b'])", raises(ResourceError, r"4,000,000,000 columns")),
    Case("isolated", "library alone: spec poly(99999999999999999999)", "dc.libraries.spec.parse_library('poly(99999999999999999999)').fit(['a', 'b'])", raises(ResourceError, r"about 10\^\d+ columns")),
    Case("isolated", "energy: state form with a 10**9-frequency library", "dc.EnergyDiscrepancy(energy=lambda s: (s ** 2).sum(1), feature_library=dc.FourierLibrary(10**9), optimizer=dc.STLSQ()).fit(X[:, :1], T, dq=X[:, 1:])", raises(ResourceError, r"columns; at most 50,000")),
    Case("isolated", "control: plan of 10**9 intervals", "plan(n_intervals=10**9)", raises(ResourceError, r"a plan of 1000000000 intervals would need")),
    Case("isolated", "control: plan with 10**7 substeps", "plan(substeps=10**7)", raises(ParameterError, r"plan_trajectory: substeps must be an integer >= 1 and <= 10000")),
    Case("isolated", "simulate: map for 10**12 steps", "dc.DiscrepancyModel(discrete_time=True).fit(X).simulate([0.0, 1.0], 10**12)", raises(ResourceError, r"1000000000000 steps x 2 states")),
    Case("isolated", "simulate: learned sign term, adaptive method", "sign_model().simulate([1.0], np.linspace(0, 2, 201), method='RK45')", raises(SimulationError, r"stopped at t = 1\.0\d* of 2 .*the budget of \d+ right-hand-side evaluations is spent")),
    Case("isolated", "simulate: learned sign term, default method", "float(sign_model().simulate([1.0], np.linspace(0, 2, 201))[50, 0])", returns(lambda v: abs(float(v) - 0.5) < 1e-9)),
    Case("isolated", "simulate: rk4 with 10**6 substeps", "fit(x_dot=XD).simulate([0.0, 1.0], T, method='rk4', substeps=10**6)", raises(ParameterError, r"substeps must be an integer >= 1 and <= 10000")),
    Case("isolated", "control: replay with 10**10 samples", "__import__('discrepancy.control', fromlist=['replay']).replay(lambda x, u: -x, [1.0], [0, 1, 2], np.zeros((2, 1)), samples=10**10)", raises(ResourceError, r"replay's dense output \(2 intervals x 10000000001 samples")),
    Case("isolated", "control: replay with NaN in t", "__import__('discrepancy.control', fromlist=['replay']).replay(lambda x, u: -x, [1.0], [0, np.nan, 2], np.zeros((2, 1)))", raises(DataError, r"^t must be finite; found nan at row 1")),
    Case("isolated", "io.load: HDF5 x of 32 GB", "__import__('h5py').File('big.h5', 'w').create_dataset('x', shape=(2 * 10**9, 2), dtype='f8').file.close() or dc.io.load('big.h5')", raises(ResourceError, r"reading array 'x' \(2000000000, 2\) of big.h5 would need 32 GB")),
    Case("isolated", "model file: 60 nested powers", "model_file([json.loads('[\"pow\", ' * 60 + '[\"sym\", \"x1\"]' + ', [\"num\", 64, 1]]' * 60), ['sym', 'x2']]).predict(np.array([[2.0, 0.0]]))", raises(FeatureError, r"library column 'x1\^\d+' is inf at row 0 \(x1 = 2, x2 = 0\)")),
    Case("isolated", "model file: product of 10**5 factors", "model_file([['mul'] + [['sym', 'x1']] * 10**5, ['sym', 'x2']]).coef_.shape", returns(lambda v: v == "(2, 2)")),
    Case("isolated", "model file: 50,001 features", "model_file([['num', k, 1] for k in range(50001)])", raises(ResourceError, r"the model file's library would have 50,001 columns")),
    Case("isolated", "model file: JSON nested 10**6 deep", "open('deep.json', 'w').write('[' * 10**6 + ']' * 10**6) and dc.load_model('deep.json')", raises(ModelFileError, r"not a usable JSON document \(RecursionError\)")),
    Case("isolated", "library: frequency 1e-300", "dc.FourierLibrary(frequencies=[1e-300]).fit(['x']).n_features_", returns(lambda v: v == "2")),
    Case("isolated", "library: frequency 1e10 pi", "dc.FourierLibrary(frequencies=[np.pi * 1e10]).fit(['x']).n_features_", returns(lambda v: v == "2")),
    Case("isolated", "library: spec with a 5000-digit degree", "dc.libraries.spec.parse_library('poly(' + '9' * 5000 + ')')", raises(ParameterError, r"library spec 'poly\(9+\.\.\.: poly needs an integer of at most 100 digits")),
    Case("isolated", "differentiation: spec with a 5000-digit window", "dc.differentiation.get_differentiation_method('savitzky_golay(window_length=' + '9' * 5000 + ')')", raises(ParameterError, r"differentiation_method 'savitzky_golay\(window_length=9+\.\.\. is not")),
    Case("isolated", "differentiation: Savitzky-Golay of degree 999", "dc.SavitzkyGolay(1001, 999)(X, T)", raises(ParameterError, r"SavitzkyGolay: polyorder must be an integer >= 1 and <= 30; got 999")),
    Case("isolated", "differentiation: trend filter of order 1000", "dc.TrendFiltered(order=1000)(X[:200], T[:200])", raises(ShapeError, r"x has 200 samples, fewer than the 1002 that TrendFiltered\(order=1000\) needs")),
    Case("isolated", "optimizer: Lasso with 10**9 sweeps and tol 1e-300", "dc.Lasso(alpha=1e-3, max_iter=10**9, tol=1e-300).fit(RNG.normal(size=(200, 5)), RNG.normal(size=200)).coef_.shape", returns(lambda v: v == "(1, 5)")),
    Case("isolated", "optimizer: SR3 with 10**9 iterations and tol 1e-300", "dc.SR3(max_iter=10**9, tol=1e-300).fit(RNG.normal(size=(200, 5)), RNG.normal(size=200)).coef_.shape", returns(lambda v: v == "(1, 5)")),
    Case("isolated", "cli: fit --library fourier(1000000000)", "np.savetxt('run.csv', np.c_[T, X], delimiter=',', header='t,x1,x2', comments='') or cli('fit', '--data', 'run.csv', '--library', 'fourier(1000000000)')", returns(lambda v: v == "1")),
    Case("isolated", "cli: fit --library poly(99999999999999999999)", "cli('fit', '--data', 'run.csv', '--library', 'poly(99999999999999999999)')", returns(lambda v: v == "1")),
    Case("isolated", "simulate: compiled RK4 with the largest substeps on 3 samples", "fit(x_dot=XD).simulate(X[0], T[:3], method='rk4', substeps=10000).shape", returns(lambda v: v == "(3, 2)")),
    Case("isolated", "fit_outputs: the largest substeps on 3 samples", "dc.DiscrepancyModel(prior=[symbol('x2'), -symbol('x1')], feature_library='poly(1)', optimizer=dc.STLSQ(threshold=0.05)).fit_outputs(np.sin(T[:3]), T[:3], outputs=['x1'], substeps=10000)", raises(ParameterError, r"substeps must be an integer in \[1, 100\]")),
    Case("isolated", "io.load: a CSV of 20,000 columns", "open('wide.csv', 'w').write(','.join(['t'] + names(20000)) + '\\n' + ','.join(['0'] * 20001) + '\\n' + ','.join(['1'] * 20001) + '\\n') and dc.io.load('wide.csv').x.shape", returns(lambda v: v == "(2, 20000)")),
    Case("isolated", "cli: simulate --t 0:1e12:1", "fit(x_dot=XD).save('m.json') or cli('simulate', '--model', 'm.json', '--x0=0,1', '--t', '0:1e12:1')", returns(lambda v: v == "2")),
]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    return run_isolated_once(PRELUDE, CASES, cwd=tmp_path_factory.mktemp("isolated"),
                             tmp_path_factory=tmp_path_factory)


@params(CASES)
def test_case(case, results):
    check_isolated(case, results)
