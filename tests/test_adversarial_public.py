"""Adversarial rows for the public callables no other table reached: metrics, symbolic
helpers, the energy toolkit's functions, control's building blocks, systems, PDE models,
plots and the records users build (see ``adversarial.py`` and ``adversarial_reach.py``)."""
from __future__ import annotations

import pickle

import casadi as ca
import matplotlib
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from adversarial import Case, check, circle, fast, params, raises, returns
from discrepancy import (
    control,
    data,
    differentiation,
    energy,
    estimation,
    libraries,
    metrics,
    optimizers,
    selection,
    symbolic,
    systems,
)
from discrepancy.errors import (
    DataError,
    DiscrepancyError,
    ExportError,
    NotFittedError,
    ParameterError,
    ShapeError,
)
from discrepancy.plots import selection as selection_plots
from discrepancy.plots import trajectories as trajectory_plots
from discrepancy.plots import uncertainty as uncertainty_plots
from test_adversarial_energy_control import DQ, SOL, Q, dissipation, state_form
from test_adversarial_energy_control import FITTED as DISSIPATION
from test_adversarial_energy_control import T as ET
from test_adversarial_estimation import RUN as EKF_RUN

NAN = np.nan
X1 = symbolic.symbol("x1")
RNG = np.random.default_rng(0)
FEATURES = RNG.random((40, 3))
T, X, XD = circle(200)
FITTED = fast(feature_library=dc.PolynomialLibrary(1)).fit(X, T, x_dot=XD)
U_FIELD, U_X, U_XX = (symbolic.symbol(n) for n in ("u", "u_x", "u_xx"))
GRID = dc.Grid(np.linspace(0, 2 * np.pi, 32, endpoint=False), periodic=True)
HEAT = dc.PDEDiscrepancyModel.prior_only([0.1 * U_XX], GRID)
_q, _dq = sp.symbols("q dq")
SPRING = systems.LagrangianSystem(_dq ** 2 / 2, _q ** 2 / 2, ["q"])
_x, _u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
DOUBLE = ca.Function("f", [_x, _u], [ca.vertcat(_x[1], _u)])   # a double integrator
PLAN = control.plan_trajectory(DOUBLE, x0=[0, 0], xf=[1, 0], T=1.0, n_intervals=10)
H = lambda x: 0.5 * (x[:, 0] ** 2 + x[:, 1] ** 2)  # noqa: E731


H_STATE = state_form().energy
STATE_FORM = state_form().fit(Q, ET, dq=DQ)


UNCERTAINTY = DISSIPATION.bootstrap(Q, ET, dq=DQ, n_resamples=4)
FILTERED = EKF_RUN
LOOP = control.closed_loop(DOUBLE, lambda k, x: np.zeros(1), [0.0, 0.0], dt=0.1, steps=3)


@pytest.fixture(scope="module", autouse=True)
def fitted_choices():
    """The rows' blind and forecast-chosen fits, made when the module's first row runs."""
    prepare()


def prepare():
    """The chosen fits (BLIND, CHOSEN, PROCEDURE) as module globals, made once: not at
    collection (every worker collects every module, and the blind energy fit alone took
    1.4 s); also called by the reach test, which may run these rows in another process."""
    global BLIND, CHOSEN, PROCEDURE
    if "PROCEDURE" in globals():
        return
    BLIND = energy.blind_fit(dissipation(), Q, ET, split=1600)
    CHOSEN = dc.DiscrepancyModel(differentiation_method="finite_difference",
                                 selection="forecast",
                                 feature_library=dc.PolynomialLibrary(1)).fit(X, T, x_dot=XD)
    PROCEDURE = dc.choose_procedure(
        dc.DiscrepancyModel(prior=lambda x, u: np.c_[x[:, 1], -x[:, 0]]), X, T,
        candidates={"linear": dc.PolynomialLibrary(1)}, progress=False)


DECAY = ca.Function("g", [_x, _u], [-_x])
MPC_DOUBLE = control.MPC(DOUBLE, horizon=5, dt=0.1, Q=[1, 1], R=[1])
MAP_U = np.sin(0.3 * np.arange(60))[:, None]


def iterate_map(x0, steps, u=MAP_U):
    """``x[k+1] = 0.9 x[k] + 0.5 u[k]`` by hand, ``steps`` values from ``x0``."""
    out = [x0]
    for k in range(steps - 1):
        out.append(0.9 * out[-1] + 0.5 * u[k, 0])
    return np.array(out)


def map_model():
    return dc.DiscrepancyModel(discrete_time=True, feature_library=dc.PolynomialLibrary(1),
                               optimizer=dc.STLSQ(threshold=0.01))


def reloaded(model):
    model.save("map.json")
    return dc.load_model("map.json")


MAP_X = iterate_map(1.0, 60)[:, None]
MAP = map_model().fit(MAP_X, 1.0, u=MAP_U)


def heat_field(m=21):
    """The heat equation u_t = 0.1 u_xx from sin(x): u = exp(-0.1 t) sin(x), exact."""
    t = np.arange(m) * 0.05
    return np.exp(-0.1 * t)[:, None] * np.sin(GRID.coordinates[0])[None, :], t


def equal(expected, **tol):
    return lambda value: np.allclose(value, expected, **tol)


def is_figure(value):
    """A matplotlib figure (closed once checked)."""
    import matplotlib.pyplot as plt

    drawn = isinstance(value, matplotlib.figure.Figure) and len(value.axes) > 0
    plt.close(value)
    return drawn


CASES = [
    # metrics: against numpy by hand
    Case("metrics", "rms_error of a known offset", lambda: metrics.rms_error([1, 2, 3], [2, 3, 4]), returns(equal(1.0))),
    Case("metrics", "rms_error shapes differ", lambda: metrics.rms_error([1, 2, 3], [1, 2]), raises(ShapeError, r"measured and predicted must have the same shape")),
    Case("metrics", "nrmse of a text", lambda: metrics.nrmse("abc", [1, 2, 3]), raises(ShapeError, r"measured must be a numeric array")),
    Case("metrics", "nrmse NaN in predicted", lambda: metrics.nrmse([1, 2, 3], [1, NAN, 3]), raises(DataError, r"predicted must be finite")),
    Case("metrics", "nrmse of a constant signal", lambda: metrics.nrmse([2.0, 2.0, 2.0], [2.0, 2.1, 2.0]), raises(DataError, r"measured column\(s\) \[0\] are constant, so nrmse")),
    Case("metrics", "fit_percent of a constant second column", lambda: metrics.fit_percent([[1.0, 5.0], [2.0, 5.0]], [[1.0, 5.0], [2.0, 5.0]]), raises(DataError, r"column\(s\) \[1\] are constant, so fit_percent")),
    Case("metrics", "rms_error of no samples", lambda: metrics.rms_error([], []), raises(DataError, r"at least one sample; got none")),
    Case("metrics", "fit_percent perfect", lambda: metrics.fit_percent([1.0, 2.0, 4.0], [1.0, 2.0, 4.0]), returns(equal(100.0))),
    Case("metrics", "fit_percent inf", lambda: metrics.fit_percent([1, np.inf, 3], [1, 2, 3]), raises(DataError, r"measured must be finite")),
    # symbolic
    Case("symbolic", "symbol of an int", lambda: symbolic.symbol(3), raises(ParameterError, r"variable name must be a non-empty string; got 3")),
    Case("symbolic", "symbol empty", lambda: symbolic.symbol(""), raises(ParameterError, r"non-empty string")),
    Case("symbolic", "adopt an unknown name", lambda: symbolic.adopt(sp.Symbol("x9"), ["x1"], label="prior"), raises(ParameterError, r"prior = x9 uses \['x9'\]")),
    Case("symbolic", "adopt a text", lambda: symbolic.adopt("x1", ["x1"], label="prior"), raises(ParameterError, r"prior must be a sympy expression; got str")),
    Case("symbolic", "compile_numpy evaluates", lambda: symbolic.compile_numpy(X1 ** 2, ["x1"])(np.array([[3.0]])), returns(equal([9.0]))),
    Case("symbolic", "compile_numpy unknown symbol", lambda: symbolic.compile_numpy(X1 + sp.Symbol("y"), ["x1"]), raises(DiscrepancyError, r"y")),
    Case("symbolic", "feature_name of a product", lambda: symbolic.feature_name(X1 ** 2, ["x1"]), returns(lambda s: s == "x1^2")),
    Case("symbolic", "from_data unknown node", lambda: symbolic.from_data(["bogus", 1]), raises(DiscrepancyError, r"bogus")),
    Case("symbolic", "from_data code text", lambda: symbolic.from_data("__import__('os')"), raises(DiscrepancyError, r"expression")),
    Case("symbolic", "from_data nested too deep", lambda: symbolic.from_data(nested(200)), raises(DiscrepancyError, r"deep|depth|nest")),
    Case("symbolic", "to_data round trip", lambda: symbolic.from_data(symbolic.to_data(X1 ** 2 / 3)), returns(lambda e: sp.simplify(e - X1 ** 2 / 3) == 0)),
    Case("symbolic", "to_data of an object", lambda: symbolic.to_data(object()), raises(ExportError, r"expr must be a sympy expression; got object")),
    Case("symbolic", "to_casadi missing variable", lambda: symbolic.to_casadi(X1, {}), raises(ExportError, r"expr = x1 uses \['x1'\], which are not among the variables \[\]")),
    Case("symbolic", "to_casadi of a text", lambda: symbolic.to_casadi("x1", {"x1": 1.0}), raises(ExportError, r"expr must be a sympy expression")),
    Case("symbolic", "CompiledExpression of compile_numpy", lambda: pickle.loads(pickle.dumps(symbolic.compile_numpy(-X1, ["x1"])))(np.array([[2.0]])), returns(equal([-2.0]))),
    # optimizers.solve_normal: against numpy's solve
    Case("optimizer", "solve_normal a known system", lambda: optimizers.solve_normal(np.array([[2.0, 1.0], [1.0, 3.0]]), np.array([1.0, 2.0])), returns(equal(np.linalg.solve([[2, 1], [1, 3]], [1, 2])))),
    Case("optimizer", "solve_normal shapes differ", lambda: optimizers.solve_normal(np.eye(2), np.ones(3)), raises(ShapeError, r"gram must be square \(p, p\) and rhs \(p,\)")),
    Case("optimizer", "solve_normal NaN gram", lambda: optimizers.solve_normal(np.full((2, 2), NAN), np.ones(2)), raises(DataError, r"gram, rhs and alpha must be finite")),
    Case("optimizer", "solve_normal not square", lambda: optimizers.solve_normal(np.ones((2, 3)), np.ones(2)), raises(ShapeError, r"gram must be square")),
    # data
    Case("data", "as_trajectories empty", lambda: data.as_trajectories(np.ones((0, 2)), 0.1), raises(ShapeError, r"x must have at least 2 samples; got shape \(0, 2\)")),
    Case("data", "as_trajectories text", lambda: data.as_trajectories("abc", 0.1), raises(ShapeError, r"x must be a numeric array")),
    Case("data", "as_trajectories negative step", lambda: data.as_trajectories(np.ones((5, 2)), -0.1), raises(DataError, r"t as a time step must be a positive finite number; got -0.1")),
    Case("data", "as_trajectories numpy int step", lambda: data.as_trajectories(np.ones((5, 2)), np.int64(1))[0].t, returns(equal([0, 1, 2, 3, 4]))),
    Case("data", "Trajectory counts samples", lambda: data.Trajectory(np.arange(3.0), np.ones((3, 2))).n_samples, returns(lambda n: n == 3)),
    Case("differentiation", "available_methods lists the registry", lambda: differentiation.available_methods(), returns(lambda names: {"finite_difference", "savitzky_golay", "spectral"} <= set(names))),
    Case("selection", "default_libraries names and columns differ", lambda: selection.default_libraries(["a"], [], np.ones((5, 2))), raises(ShapeError, r"state_names and input_names name 1 variables; x and u hold \(2,\) columns")),
    # energy toolkit
    Case("energy", "check_span lengths differ", lambda: energy.check_span(np.ones((5, 2)), np.ones(4)), raises(ShapeError, r"energy must have 5 rows")),
    Case("energy", "check_span negative tolerance", lambda: energy.check_span(np.ones((5, 2)), np.ones(5), tolerance=-1), raises(ParameterError, r"tolerance must be a number in \(0, 1\); got -1")),
    Case("energy", "energy_span_residual NaN", lambda: energy.energy_span_residual(np.full((5, 2), NAN), np.ones(5)), raises(DataError, r"theta must be finite")),
    Case("energy", "energy_span_residual spans", lambda: energy.energy_span_residual(np.c_[T, T ** 2], 1 + 2 * T - T ** 2), returns(lambda r: r < 1e-10)),
    Case("energy", "error_summary lengths differ", lambda: energy.error_summary(np.ones(5), np.ones(4)), raises(ShapeError, r"delta_h_model must have 5 rows")),
    Case("energy", "error_summary empty", lambda: energy.error_summary(np.ones(0), np.ones(0)), raises(DataError, r"delta_h must hold at least one sample")),
    Case("energy", "percent_error unknown normaliser", lambda: energy.percent_error(np.ones(5), np.ones(5), normaliser="bogus"), raises(ParameterError, r"normaliser must be 'max' or 'range'; got 'bogus'")),
    Case("energy", "percent_error zero scale", lambda: energy.percent_error(np.zeros(5), np.ones(5)), raises(DataError, r"delta_h has no size to normalise by")),
    Case("energy", "percent_error by hand", lambda: energy.percent_error(np.array([0.0, 2.0, 4.0]), np.array([0.0, 1.0, 4.0])), returns(equal([0.0, 25.0, 0.0]))),
    Case("energy", "fit_dissipation lengths differ", lambda: energy.fit_dissipation(np.ones((5, 2)), np.ones(4), ["a", "b"]), raises(ShapeError, r"delta_h must have 5 rows")),
    Case("energy", "select_terms max_terms 0", lambda: energy.select_terms(FEATURES, FEATURES[:, 0], max_terms=0), raises(ParameterError, r"max_terms must be an integer >= 1; got 0")),
    Case("energy", "select_terms numpy max_terms", lambda: energy.select_terms(FEATURES, FEATURES @ [1.0, 0, 2.0], max_terms=np.int64(2))[0], returns(lambda s: s == (0, 2))),
    Case("energy", "select_terms holdout 2", lambda: energy.select_terms(FEATURES, FEATURES[:, 0], holdout=2.0), raises(ParameterError, r"holdout must be a fraction in \[0, 0.9\); got 2.0")),
    Case("energy", "select_terms max_terms 2.5", lambda: energy.select_terms(FEATURES, FEATURES[:, 0], max_terms=2.5), raises(ParameterError, r"max_terms must be an integer >= 1; got 2.5")),
    Case("energy", "turning_points of a table", lambda: energy.turning_points(np.ones((3, 3))), raises(ShapeError, r"speed must be 1-D")),
    Case("energy", "turning_points NaN", lambda: energy.turning_points(np.array([1, NAN, -1.0])), raises(DataError, r"speed must be finite")),
    Case("energy", "turning_points of a cosine", lambda: energy.turning_points(np.cos(np.linspace(0, 4 * np.pi, 400))), returns(lambda i: len(i) == 4)),
    Case("energy", "without_stribeck of an int", lambda: energy.without_stribeck(3), raises(ParameterError, r"terms must be a sequence; got 3")),
    Case("energy", "without_stribeck drops Stribeck", lambda: energy.without_stribeck(energy.default_friction_library(["q", "dq"])), returns(lambda terms: terms and not any(t.name.startswith("Stribeck") for t in terms))),
    Case("energy", "holding_torques not callable", lambda: energy.holding_torques(3, np.ones((3, 2)), np.ones(1)), raises(ParameterError, r"energy must be a callable")),
    Case("energy", "holding_torques odd columns", lambda: energy.holding_torques(H, np.ones((3, 3)), np.ones(1)), raises(ShapeError, r"x must hold positions then speeds")),
    Case("energy", "integrated_powers times of another length", lambda: energy.integrated_powers(energy.default_friction_library(["q", "dq"])[:1], np.ones((5, 2)), np.arange(4.0), ["q", "dq"]), raises(ShapeError, r"t")),
    Case("energy", "integrated_powers names not a list", lambda: energy.integrated_powers((), np.ones((5, 2)), 0.1, 3), raises(ParameterError, r"names must be a sequence")),
    Case("energy", "choose_smoothing negative window", lambda: energy.choose_smoothing(H, np.c_[np.sin(T)], T, windows=(-3,)), raises(DataError, r"too short for any smoothing window of \[-3\]")),
    Case("energy", "support_loss_terms not callable", lambda: energy.support_loss_terms(3, ["q", "dq"]), raises(ParameterError, r"pivot_force must be a callable")),
    Case("energy", "FrictionTerm power a text", lambda: energy.FrictionTerm("a", "x**2", "W", "N m"), raises(ParameterError, r"FrictionTerm 'a': power must be a sympy expression; got str")),
    Case("energy", "default_procedures negative seconds", lambda: energy.default_procedures(dc.DissipationDiscrepancy(energy=H), -1.0, 3), raises(ParameterError, r"training_seconds must be a finite number > 0; got -1.0")),
    Case("energy", "default_procedures numpy positions", lambda: len(energy.default_procedures(dc.DissipationDiscrepancy(energy=H), 10.0, np.int64(3))), returns(lambda n: n > 0)),
] + [
    # control's building blocks (a double integrator x1' = x2, x2' = u)
    Case("control", "from_equations names as text", lambda: control.from_equations(["x1", "x2"], ["u"], [X1, X1]), raises(ParameterError, r"states must be a sequence of sympy symbols; got \['x1', 'x2'\]")),
    Case("control", "from_equations one expression short", lambda: control.from_equations(sp.symbols("x1 x2"), sp.symbols("u,"), [X1]), raises(ShapeError, r"rhs must have one expression per state \(2\); got 1")),
    Case("control", "from_equations a double integrator", lambda: float(control.from_equations(sp.symbols("x1 x2"), sp.symbols("u,"), list(sp.symbols("x2 u")))([1.0, 2.0], [3.0])[1]), returns(equal(3.0))),
    Case("control", "Limits lower above upper", lambda: control.Limits(u_bounds=np.array([[1.0, -1.0]])), raises(DiscrepancyError, r"u_bounds")),
    Case("control", "Limits.named unknown state", lambda: control.Limits.named(["x1"], ["u"], states={"bogus": (0, 1)}), raises(DiscrepancyError, r"bogus")),
    Case("control", "linearise without a plan", lambda: control.linearise(DOUBLE, "plan"), raises(DiscrepancyError, r"plan")),
    Case("control", "state_transition without a plan", lambda: control.state_transition(DOUBLE, None), raises(DiscrepancyError, r"plan")),
    Case("control", "interval_defects without a plan", lambda: control.interval_defects(DOUBLE, 3), raises(DiscrepancyError, r"plan")),
    Case("control", "parameter_sensitivity without a plan", lambda: control.parameter_sensitivity(DOUBLE, DOUBLE, 3), raises(DiscrepancyError, r"plan")),
    Case("control", "interval_defects of the planned model", lambda: float(np.max(np.abs(control.interval_defects(DOUBLE, PLAN)))), returns(lambda d: d < 1e-6)),
    Case("control", "learn_by_attempts zero attempts", lambda: control.learn_by_attempts(lambda c: None, control.DiscrepancyUpdater(FITTED), first=None, max_attempts=0), raises(ParameterError, r"max_attempts")),
    Case("control", "learn_by_attempts numpy attempts", lambda: control.learn_by_attempts(lambda c: None, control.DiscrepancyUpdater(FITTED), first=None, max_attempts=np.int64(-1)), raises(ParameterError, r"max_attempts")),
    Case("control", "DiscrepancyUpdater of a text", lambda: control.DiscrepancyUpdater("model").update(X, T), raises(ParameterError, r"model must be an unfitted DiscrepancyModel; got 'model'")),
    Case("control", "SmoothedLogUpdater numpy passes", lambda: control.SmoothedLogUpdater(FITTED, outputs=["x1"], measurement_noise=0.1, passes=np.int64(2)).passes, returns(lambda n: n == 2)),
    Case("control", "Tracker gains of a wrong shape", lambda: control.Tracker(PLAN, np.ones(3)), raises(ShapeError, r"gains must be \(N, r, n\) = \(10, 1, 2\) for this plan")),
    Case("control", "MPC.follow a text", lambda: control.MPC(DOUBLE, horizon=5, dt=0.1, Q=[1, 1], R=[1]).follow("plan"), raises(DiscrepancyError, r"plan")),
    Case("control", "MPCLaw of a text", lambda: control.MPCLaw("mpc", PLAN, None), raises(ParameterError, r"mpc must be an MPC; got str")),
    Case("control", "rk4_step NaN step", lambda: control.rk4_step(DOUBLE, NAN, 1), raises(ParameterError, r"dt must be a finite number > 0; got nan")),
    Case("control", "rk4_step negative step", lambda: control.rk4_step(DOUBLE, -0.1, 1), raises(ParameterError, r"dt must be a finite number > 0; got -0.1")),
    Case("control", "rk4_step of a text", lambda: control.rk4_step("f", 0.1, 1), raises(ParameterError, r"f must be a casadi.Function")),
    Case("control", "rk4_step numpy substeps on x' = -x", lambda: float(control.rk4_step(DECAY, 0.1, np.int64(4))([1.0, 1.0], [0.0])[0]), returns(equal(np.exp(-0.1), rtol=1e-7))),
    Case("control", "stationary_lqr zero step", lambda: control.stationary_lqr(DOUBLE, [0, 0], [0], dt=0.0, substeps=1, Q=[1, 1], R=[1]), raises(ParameterError, r"dt must be a finite number > 0; got 0.0")),
    Case("control", "stationary_lqr equilibrium of another size", lambda: control.stationary_lqr(DOUBLE, [0, 0, 0], [0], dt=0.1, substeps=1, Q=[1, 1], R=[1]), raises(ShapeError, r"x_eq must be 2 numbers")),
    Case("control", "stationary_lqr NaN weight", lambda: control.stationary_lqr(DOUBLE, [0, 0], [0], dt=0.1, substeps=1, Q=[NAN, 1], R=[1]), raises(ParameterError, r"Q must be finite weights")),
    Case("control", "stationary_lqr against scipy", lambda: control.stationary_lqr(DECAY, [0, 0], [0], dt=0.1, substeps=np.int64(2), Q=[1, 1], R=[1])[1], returns(equal(np.eye(2) / (1 - float(control.rk4_step(DECAY, 0.1, 2)([1.0, 0.0], [0.0])[0]) ** 2)))),
    Case("control", "swing_up_errors of a text", lambda: control.swing_up_errors("x", angles=[0], rates=[1]), raises(ShapeError, r"x_final must be a numeric array")),
    Case("control", "swing_up_errors negative tolerance", lambda: control.swing_up_errors(np.zeros(2), angles=[0], rates=[1], angle_tol=-1), raises(ParameterError, r"angle_tol must be a finite number > 0; got -1")),
    Case("control", "swing_up_errors wraps the angle", lambda: control.swing_up_errors(np.array([2 * np.pi + 0.01, 0.1]), angles=[0], rates=[1]), returns(lambda e: e["angle_0"] == pytest.approx(0.01) and e["success"])),
    Case("control", "MPC.solve NaN state", lambda: MPC_DOUBLE.solve([NAN, 0], np.zeros((6, 2)), np.zeros((5, 1))), raises(DataError, r"x must be finite")),
    Case("control", "MPC.solve negative terminal weight", lambda: MPC_DOUBLE.solve([0, 0], np.zeros((6, 2)), np.zeros((5, 1)), P=-np.eye(2)), raises(ParameterError, r"P must be positive semidefinite")),
    Case("control", "MPC.solve u_prev a text", lambda: MPC_DOUBLE.solve([0, 0], np.zeros((6, 2)), np.zeros((5, 1)), u_prev="a"), raises(ShapeError, r"u_prev must be a numeric array")),
    Case("control", "MPC.solve at rest stays at rest", lambda: MPC_DOUBLE.solve([0, 0], np.zeros((6, 2)), np.zeros((5, 1))).u, returns(equal(np.zeros((5, 1)), atol=1e-8))),
    Case("control", "replay a text law", lambda: control.replay(DOUBLE, [0, 0], np.arange(4) * 0.1, "law"), raises(ShapeError, r"law must be a numeric array")),
    Case("control", "tvlqr bounds reversed", lambda: control.tvlqr(DOUBLE, PLAN, Q=[1, 1], R=[1], u_bounds=[[1, -1]]), raises(ShapeError, r"u_bounds must be \(1, 2\) rows of \(lower, upper\) with lower <= upper")),
    Case("control", "interval_defects negative rtol", lambda: control.interval_defects(DOUBLE, PLAN, rtol=-1), raises(ParameterError, r"rtol must be a finite number > 0 and <= 1; got -1")),
    Case("control", "parameter_sensitivity a text perturbation", lambda: control.parameter_sensitivity(DOUBLE, "p", PLAN), raises(ParameterError, r"perturbation must be a casadi.Function \(x, u\) -> \(2, 1\); got str")),
    Case("control", "learn_by_attempts a text attempt", lambda: control.learn_by_attempts("a", control.DiscrepancyUpdater(fast()), first=None), raises(ParameterError, r"attempt must be a callable")),
    Case("control", "state_transition of x' = -x", lambda: control.state_transition(DECAY, PLAN), returns(equal(np.eye(2) * np.exp(-1.0), rtol=1e-6))),
    Case("control", "linearise a text model", lambda: control.linearise("m", PLAN), raises(ParameterError, r"model must be a casadi.Function")),
    # discrete-time maps (x[k+1] = 0.9 x[k] + 0.5 u[k]) against iterating the map by hand
    Case("model", "discrete simulate iterates the map", lambda: MAP.simulate([1.0], np.arange(6.0), u=MAP_U[:6])[:, 0], returns(equal(iterate_map(1.0, 6)))),
    Case("model", "discrete predict is one step", lambda: MAP.predict(MAP_X[:3], u=MAP_U[:3])[:, 0], returns(equal(0.9 * MAP_X[:3, 0] + 0.5 * MAP_U[:3, 0]))),
    Case("model", "discrete refine refused", lambda: MAP.refine(MAP_X, 1.0, u=MAP_U), raises(ParameterError, r"refine simulates continuous-time models.*discrete_time=True")),
    Case("model", "discrete fit_outputs refused", lambda: map_model().fit_outputs(MAP_X, 1.0, u=MAP_U, outputs=["x1"]), raises(ParameterError, r"fit_outputs simulates continuous-time models")),
    Case("model", "discrete estimate_initial_state refused", lambda: MAP.estimate_initial_state(MAP_X[:10], 1.0, u=MAP_U[:10], outputs=["x1"]), raises(ParameterError, r"estimate_initial_state simulates continuous-time models")),
    Case("model", "discrete fit_prediction_error refused", lambda: map_model().fit_prediction_error(MAP_X, 1.0, u=MAP_U, outputs=["x1"]), raises(ParameterError, r"fit_prediction_error fits continuous-time models")),
    Case("model", "discrete differentiate refused", lambda: MAP.differentiate(MAP_X, 1.0), raises(ParameterError, r"a discrete-time model has no derivatives")),
    Case("model", "discrete save and load iterates the map", lambda: reloaded(MAP).simulate([1.0], np.arange(6.0), u=MAP_U[:6])[:, 0], returns(equal(iterate_map(1.0, 6)))),
    Case("model", "discrete from_prior simulates the map", lambda: dc.DiscrepancyModel.from_prior(lambda x, u: 0.5 * x, state_names=["x"], discrete_time=True).simulate([8.0], np.arange(4.0))[:, 0], returns(equal([8.0, 4.0, 2.0, 1.0]))),
    # systems
    Case("systems", "DoublePendulum of a text", lambda: systems.DoublePendulum("params").rhs(np.zeros((1, 4)), None), raises(ParameterError, r"params must be DoublePendulumParameters; got str")),
    Case("systems", "DoublePendulumParameters negative mass", lambda: systems.DoublePendulumParameters(m1=-1.0), raises(ParameterError, r"m1")),
    Case("systems", "PendulumOnCartParameters NaN length", lambda: systems.PendulumOnCartParameters(l=NAN), raises(ParameterError, r"\bl\b")),
    Case("systems", "CartPendulumParameters zero gravity", lambda: systems.CartPendulumParameters(g=0.0), raises(ParameterError, r"CartPendulumParameters.g must be a finite number > 0; got 0.0")),
    Case("systems", "PendulumOnCart NaN motor error", lambda: systems.PendulumOnCart(motor_error=NAN).flawed_equations(), raises(ParameterError, r"motor_error must be a finite number > -1; got nan")),
    Case("systems", "DoublePendulumOnCart rhs of a wrong width", lambda: systems.DoublePendulumOnCart().rhs(np.ones((2, 3)), np.ones((2, 1))), raises(ShapeError, r"x")),
    Case("systems", "DoublePendulum energy at rest hanging", lambda: float(systems.DoublePendulum().energy(np.zeros((1, 4)))[0]), returns(lambda e: np.isfinite(e))),
    Case("systems", "System is abstract", lambda: SPRING.rhs(np.ones((2, 2)), None), returns(lambda v: np.allclose(v, [[1, -1], [1, -1]]))),
    # estimation
    Case("estimation", "KalmanFilter one scalar update", lambda: scalar_update(), returns(equal([2.6, 0.8]))),
    Case("estimation", "KalmanFilter negative noise", lambda: estimation.KalmanFilter([-X1], outputs=["x1"], process_noise=-0.1, measurement_noise=0.1, state_names=["x1"]), raises(DataError, r"process_noise must be non-negative standard deviations \(per second\); got \[-0.1\]")),
    Case("estimation", "KalmanFilter numpy substeps", lambda: estimation.KalmanFilter([-X1], outputs=["x1"], process_noise=0.1, measurement_noise=0.1, state_names=["x1"], substeps=np.int64(2)).filter(np.ones((5, 1)), 0.1, x0=[1.0], P0=[1.0]).x.shape, returns(lambda shape: shape == (5, 1))),
    # libraries and optimizers
    Case("library", "ConcatLibrary of a text", lambda: libraries.ConcatLibrary("poly").fit(X), raises(ParameterError, r"ConcatLibrary: libraries must be a non-empty list of feature libraries; got 'poly'")),
    Case("library", "ConcatLibrary empty", lambda: libraries.ConcatLibrary([]).fit(X), raises(ParameterError, r"libraries must be a non-empty list of feature libraries; got list of length 0")),
    Case("library", "TensorLibrary of a number", lambda: libraries.TensorLibrary(dc.PolynomialLibrary(1), 3).fit(X), raises(ParameterError, r"TensorLibrary: right must be a feature library; got 3")),
    Case("library", "TensorLibrary of two linear libraries", lambda: libraries.TensorLibrary(dc.PolynomialLibrary(1, include_bias=False), dc.PolynomialLibrary(1, include_bias=False)).fit(X).transform(np.array([[2.0, 3.0]])), returns(lambda v: sorted(np.ravel(v)) == [4.0, 6.0, 9.0])),
    Case("optimizer", "WrappedOptimizer of a text", lambda: optimizers.WrappedOptimizer("lasso").fit(FEATURES, FEATURES[:, :1]), raises(ParameterError, r"WrappedOptimizer: optimizer must be a scikit-learn regressor \(with fit and coef_\); got 'lasso'")),
    # fields and sources
    Case("pde", "Grid of a text", lambda: dc.Grid("abc"), raises(DiscrepancyError, r"coordinate")),
    Case("pde", "Grid not increasing", lambda: dc.Grid(np.array([0.0, 2.0, 1.0])), raises(DiscrepancyError, r"increasing")),
    Case("pde", "FieldSource negative step", lambda: dc.FieldSource([heat_field()[0]], grid=GRID, dt=-0.1), raises(DiscrepancyError, r"dt")),
    Case("pde", "FieldSource numpy chunk size", lambda: dc.FieldSource([heat_field()[0]], grid=GRID, dt=0.05, chunk_size=np.int64(8)).dt, returns(equal(0.05))),
    Case("pde", "FieldWeakForm negative power", lambda: dc.PDEDiscrepancyModel(prior=[0.1 * U_XX], differentiation_method=dc.FieldWeakForm(power=-1)).fit(*heat_field(), grid=GRID), raises(ParameterError, r"power")),
    Case("pde", "ZarrSource missing file", lambda: dc.ZarrSource(["missing.zarr"]), raises(DiscrepancyError, r"missing.zarr")),
    Case("stream", "Chunk rows differ", lambda: fast().fit([dc.Chunk(X[:50], t=T[:40])]), raises(DiscrepancyError, r"t")),
    Case("pde", "PDEDiscrepancyModel prior of a text", lambda: dc.PDEDiscrepancyModel(prior="u_xx").fit(*heat_field(), grid=GRID), raises(DiscrepancyError, r"prior")),
    Case("pde", "PDEDiscrepancyModel stores numpy-free arguments", lambda: dc.PDEDiscrepancyModel(prior=[0.1 * U_XX], field_names=("u",)), returns(lambda m: m.field_names == ("u",) and m.prior == [0.1 * U_XX])),
    Case("pde", "PDEDiscrepancyModel.fit without grid", lambda: dc.PDEDiscrepancyModel(prior=[0.1 * U_XX]).fit(heat_field()[0], 0.05, grid=None), raises(DiscrepancyError, r"grid")),
    Case("pde", "PDEDiscrepancyModel.fit NaN field", lambda: dc.PDEDiscrepancyModel(prior=[0.1 * U_XX]).fit(heat_field()[0] * NAN, 0.05, grid=GRID), raises(DataError, r"finite")),
    Case("pde", "PDEDiscrepancyModel.prior_only of a number", lambda: dc.PDEDiscrepancyModel.prior_only(3, GRID), raises(DiscrepancyError, r"prior")),
    Case("pde", "PDEDiscrepancyModel.simulate the heat equation", lambda: HEAT.simulate(heat_field()[0][0], heat_field()[1], rtol=1e-9)[-1, :, 0], returns(equal(heat_field()[0][-1], atol=1e-4))),
    Case("pde", "PDEDiscrepancyModel.simulate zero rtol", lambda: HEAT.simulate(heat_field()[0][0], heat_field()[1], rtol=0.0), raises(ParameterError, r"rtol")),
    Case("pde", "PDEDiscrepancyModel.simulate unknown boundary", lambda: HEAT.simulate(heat_field()[0][0], heat_field()[1], boundary="bogus"), raises(ParameterError, r"boundary")),
    Case("pde", "PDEDiscrepancyModel.predict wrong grid size", lambda: HEAT.predict(np.ones((3, 5))), raises(ShapeError, r"")),
    Case("pde", "PDEDiscrepancyModel.discrepancy of a text", lambda: HEAT.discrepancy("u"), raises(ShapeError, r"")),
    Case("pde", "PDEDiscrepancyModel.coefficients of the prior alone", lambda: HEAT.coefficients(), returns(lambda c: np.all(np.asarray(c) == 0))),
    Case("pde", "PDEDiscrepancyModel.equations unfitted", lambda: dc.PDEDiscrepancyModel().equations(), raises(NotFittedError, r"fit")),
    Case("pde", "PDEDiscrepancyModel.print unfitted", lambda: dc.PDEDiscrepancyModel().print(), raises(NotFittedError, r"fit")),
    Case("pde", "PDEDiscrepancyModel.to_sympy unfitted", lambda: dc.PDEDiscrepancyModel().to_sympy(), raises(NotFittedError, r"fit")),
    Case("pde", "PDEDiscrepancyModel.to_latex unfitted", lambda: dc.PDEDiscrepancyModel().to_latex(), raises(NotFittedError, r"fit")),
    Case("pde", "PDEDiscrepancyModel.get_feature_names unfitted", lambda: dc.PDEDiscrepancyModel().get_feature_names(), raises(NotFittedError, r"fit")),
    Case("pde", "PDEDiscrepancyModel.fit_statistics of a text", lambda: dc.PDEDiscrepancyModel().fit_statistics("stats", "setup"), raises(DiscrepancyError, r"stat")),
    Case("pde", "PDEDiscrepancyModel.make_setup negative fields", lambda: dc.PDEDiscrepancyModel().make_setup(-1, 0, GRID), raises(DiscrepancyError, r"field")),
    Case("pde", "PDEDiscrepancyModel.check_is_fitted unfitted", lambda: dc.PDEDiscrepancyModel().check_is_fitted(), raises(NotFittedError, r"fit")),
    Case("pde", "PDEDiscrepancyModel.set_params unknown", lambda: dc.PDEDiscrepancyModel().set_params(bogus=1), raises(ParameterError, r"bogus")),
    Case("pde", "PDEDiscrepancyModel.get_params lists field_names", lambda: dc.PDEDiscrepancyModel(field_names=["u"]).get_params()["field_names"], returns(lambda v: list(v) == ["u"])),
    # energy models' methods (a damped oscillator: H = (q^2 + dq^2) / 2 loses 0.1 dq^2 W)
    Case("energy", "DissipationDiscrepancy of a text energy", lambda: dc.DissipationDiscrepancy(energy="H").fit(Q, ET, dq=DQ), raises(ParameterError, r"DissipationDiscrepancy: energy must be a callable; got 'H'")),
    Case("energy", "EnergyDiscrepancy of a text energy", lambda: dc.EnergyDiscrepancy(energy="H").fit(Q, ET, dq=DQ), raises(ParameterError, r"EnergyDiscrepancy: energy must be a callable; got 'H'")),
    Case("energy", "EnergyDiscrepancy learns E0 - H", lambda: STATE_FORM.coef_[np.abs(STATE_FORM.coef_) > 1e-6], returns(equal([0.5, -0.5, -0.5], atol=1e-6))),
    Case("energy", "variable_names of -1 positions", lambda: DISSIPATION.variable_names(-1), raises(ParameterError, r"k \(the number of positions\) must be an integer >= 1; got -1")),
    Case("energy", "variable_names of 1.5 positions", lambda: STATE_FORM.variable_names(1.5), raises(ParameterError, r"must be an integer >= 1; got 1.5")),
    Case("energy", "variable_names numpy count", lambda: DISSIPATION.variable_names(np.int64(2)), returns(lambda names: names == ["q1", "q2", "dq1", "dq2"])),
    Case("energy", "states NaN positions", lambda: DISSIPATION.states(Q * NAN, ET, dq=DQ), raises(DataError, r"q must be finite")),
    Case("energy", "states velocities too short", lambda: STATE_FORM.states(Q, ET, dq=DQ[:10]), raises(ShapeError, r"dq must have 2000 rows")),
    Case("energy", "states times as text", lambda: STATE_FORM.states(Q, "abc", dq=DQ), raises(DataError, r"t must be a positive time step")),
    Case("energy", "measured_delta_h odd columns", lambda: DISSIPATION.measured_delta_h(np.ones((5, 3))), raises(ShapeError, r"x must hold positions then velocities, \(m, 2k\); got shape \(5, 3\)")),
    Case("energy", "measured_delta_h e0 as text", lambda: STATE_FORM.measured_delta_h(np.ones((5, 2)), e0="a"), raises(ParameterError, r"e0 must be a finite number \(J\); got 'a'")),
    Case("energy", "measured_delta_h by hand", lambda: STATE_FORM.measured_delta_h(np.array([[1.0, 0.0], [0.0, 0.0]])), returns(equal([0.0, 0.5]))),
    Case("energy", "predict start NaN", lambda: DISSIPATION.predict(Q, ET, dq=DQ, start=NAN), raises(ParameterError, r"start must be a finite number \(J\); got nan")),
    Case("energy", "EnergyDiscrepancy.predict 3-D positions", lambda: STATE_FORM.predict(np.ones((3, 3, 3)), ET), raises(ShapeError, r"q must be 2-D")),
    Case("energy", "EnergyDiscrepancy.score velocities of another width", lambda: STATE_FORM.score(np.ones((2000, 2)), ET, dq=DQ), raises(ShapeError, r"dq must have 2 columns")),
    Case("energy", "DissipationDiscrepancy.score start inf", lambda: DISSIPATION.score(Q, ET, dq=DQ, start=np.inf), raises(ParameterError, r"start must be a finite number")),
    Case("energy", "EnergyDiscrepancy.score exact", lambda: STATE_FORM.score(Q, ET, dq=DQ)["max_abs_percent_of_max"], returns(lambda e: e < 1e-6)),
    Case("energy", "identified_terms unfitted", lambda: state_form().identified_terms(), raises(NotFittedError, r"this EnergyDiscrepancy is not fitted yet")),
    Case("energy", "EnergyDiscrepancy.equation unfitted", lambda: state_form().equation(), raises(NotFittedError, r"not fitted yet")),
    Case("energy", "DissipationDiscrepancy.equation the law", lambda: DISSIPATION.equation(), returns(lambda text: text.startswith("P_loss = 0.1 [N m s] dq1^2"))),
    Case("energy", "EnergyDiscrepancy.check_is_fitted unfitted", lambda: state_form().check_is_fitted(), raises(NotFittedError, r"not fitted yet")),
    Case("energy", "DissipationDiscrepancy.check_is_fitted unfitted", lambda: dc.DissipationDiscrepancy(energy=H).check_is_fitted(), raises(NotFittedError, r"not fitted yet")),
    Case("energy", "EnergyDiscrepancy.set_params unknown", lambda: state_form().set_params(bogus=1), raises(ParameterError, r"EnergyDiscrepancy has no parameter 'bogus'")),
    Case("energy", "DissipationDiscrepancy.set_params unknown", lambda: dc.DissipationDiscrepancy(energy=H).set_params(bogus=1), raises(ParameterError, r"DissipationDiscrepancy has no parameter 'bogus'")),
    Case("energy", "EnergyDiscrepancy.get_params round trip", lambda: state_form().get_params()["energy"] is H_STATE, returns(lambda same: same)),
    Case("energy", "DissipationDiscrepancy.get_params round trip", lambda: dc.DissipationDiscrepancy(energy=H, max_terms=np.int64(2)).get_params()["max_terms"], returns(lambda n: n == 2)),
    Case("energy", "anchored times of another length", lambda: DISSIPATION.anchored(np.ones((5, 2)), ET), raises(ShapeError, r"t must be a step or a 1-D array of 5 times")),
    Case("energy", "anchored odd columns", lambda: DISSIPATION.anchored(np.ones((5, 3)), ET[:5]), raises(ShapeError, r"x must hold positions then velocities, \(m, 2k\); got shape \(5, 3\)")),
    Case("energy", "prepare odd columns", lambda: DISSIPATION.prepare(np.ones((5, 3)), ET[:5]), raises(ShapeError, r"x must hold positions then velocities")),
    Case("energy", "prepare times as text", lambda: DISSIPATION.prepare(SOL, "t"), raises(DataError, r"t must be a positive time step")),
    Case("energy", "fit_prepared stop 0", lambda: dc.DissipationDiscrepancy(energy=H).fit_prepared(DISSIPATION.prepare(SOL, ET), 0), raises(ParameterError, r"stop must be an integer in \[3, 2000\]")),
    Case("energy", "fit_prepared stop past the end", lambda: dc.DissipationDiscrepancy(energy=H).fit_prepared(DISSIPATION.prepare(SOL, ET), 10 ** 9), raises(ParameterError, r"stop must be an integer in \[3, 2000\]")),
    Case("energy", "fit_prepared a text record", lambda: dc.DissipationDiscrepancy(energy=H).fit_prepared("rec", 10), raises(ParameterError, r"record must be a PreparedRecording \(from prepare\); got str")),
    Case("energy", "fit_prepared numpy stop", lambda: dc.DissipationDiscrepancy(energy=H).fit_prepared(DISSIPATION.prepare(SOL, ET), np.int64(1500)).coef_, returns(equal([0.1], atol=1e-4))),
    Case("energy", "resampled_predictions of a text", lambda: DISSIPATION.resampled_predictions(Q, ET, "unc", dq=DQ), raises(ParameterError, r"uncertainty must be this model's bootstrap")),
    Case("energy", "DissipationDiscrepancy stores numpy arguments", lambda: dc.DissipationDiscrepancy(energy=H, max_terms=np.int64(2)), returns(lambda m: m.max_terms == 2 and m.energy is H)),
    Case("energy", "EnergyDiscrepancy stores its energy", lambda: dc.EnergyDiscrepancy(energy=H), returns(lambda m: m.energy is H)),
    Case("energy", "PreparedRecording of odd columns", lambda: energy.PreparedRecording(H, np.ones((5, 3)), ET[:5], (), ["q", "dq", "x"]), raises(ShapeError, r"x must hold positions then velocities \(m, 2k\)")),
    Case("energy", "PreparedRecording.window_start past the end", lambda: DISSIPATION.prepare(SOL, ET).window_start(10 ** 6, 1.0), raises(ParameterError, r"stop must be a sample count in \[1, 2000\]; got 1000000")),
    Case("energy", "PreparedRecording.window_start the last second", lambda: DISSIPATION.prepare(SOL, ET).window_start(np.int64(2000), 1.0), returns(lambda k: ET[k] == pytest.approx(ET[-1] - 1.0))),
    Case("energy", "BlindFit.forecast_band lengths differ", lambda: BLIND.forecast_band(np.zeros(10), ET[:5]), raises(ShapeError, r"prediction must have 5 rows")),
    Case("energy", "BlindFit.forecast_band empty", lambda: BLIND.forecast_band(np.zeros(0), np.zeros(0)), raises(ShapeError, r"t must hold at least one time")),
    Case("energy", "BlindFit.restricted unknown name", lambda: BLIND.restricted(["bogus"]), raises(ParameterError, r"bogus")),
    Case("energy", "DissipationUncertainty.interval level 2", lambda: UNCERTAINTY.interval(2.0), raises(ParameterError, r"level must be .*got 2.0")),
    Case("energy", "DissipationUncertainty.curves features of another width", lambda: UNCERTAINTY.curves(np.ones((5, 7)), continued=False), raises(ShapeError, r"features must have 1 columns; got shape \(5, 7\)")),
    Case("energy", "DissipationUncertainty.table negative precision", lambda: UNCERTAINTY.table(precision=-1), raises(ParameterError, r"precision must be .*got -1")),
    # records' methods
    Case("estimation", "FilterResult.state past the end", lambda: FILTERED.state(10 ** 6), raises(ParameterError, r"i must be a sample index in \[-100, 100\); got 1000000")),
    Case("estimation", "FilterResult.state numpy index", lambda: FILTERED.state(np.int64(0)).x, returns(equal([0.0, 1.0]))),
    Case("estimation", "FilterResult.normalised_innovations_squared", lambda: FILTERED.normalised_innovations_squared(), returns(lambda v: v.shape == (100,) and np.all(v >= 0))),
    Case("control", "Attempt.coefficients of a model", lambda: control.Attempt(1, False, FITTED, None, FITTED).coefficients(), returns(lambda c: c.keys() == {"x1", "x2"} and c["x1"] == pytest.approx({"x2": 1.0}) and c["x2"] == pytest.approx({"x1": -1.0}))),
    Case("control", "ClosedLoopRun.measured_trajectories until NaN", lambda: LOOP.measured_trajectories(until=NAN), raises(ParameterError, r"until must be a time \(s\) or None; got nan")),
    Case("control", "ClosedLoopRun.first_exit of a text", lambda: LOOP.first_exit("limits"), raises(ParameterError, r"limits must be a Limits; got str")),
    Case("control", "ClosedLoopRun.control_log holds the steps", lambda: len(LOOP.control_log()), returns(lambda n: n == 3)),
    Case("selection", "ForecastSelection.improvement", lambda: CHOSEN.forecast_selection_.improvement(), returns(lambda v: np.isfinite(v))),
    Case("selection", "ProcedureChoice.table", lambda: PROCEDURE.table(), returns(lambda text: "prior alone" in text)),
    Case("selection", "choose_procedure zero origins", lambda: dc.choose_procedure(fast(), X, T, n_origins=0), raises(ParameterError, r"n_origins")),
    Case("selection", "choose_procedure join not a bool", lambda: dc.choose_procedure(fast(), X, T, join="yes"), raises(ParameterError, r"join must be")),
    Case("selection", "choose_procedure numpy origins", lambda: dc.choose_procedure(dc.DiscrepancyModel(prior=lambda x, u: np.c_[x[:, 1], -x[:, 0]]), X, T, n_origins=np.int64(2), candidates={"linear": dc.PolynomialLibrary(1)}, progress=False).chosen, returns(lambda name: name == "prior alone")),
    Case("stream", "Chunk.rows past the end", lambda: dc.Chunk(X[:5], t=T[:5]).rows(10, 20), raises(ParameterError, r"start and stop must be row numbers up to 5")),
    Case("stream", "Chunk.rows numpy bounds", lambda: dc.Chunk(X[:5], t=T[:5]).rows(np.int64(1), np.int64(3)).x, returns(equal(X[1:3]))),
    # PDE components
    Case("pde", "PDELibrary negative derivative order", lambda: dc.PDELibrary(derivative_order=-1).fit(np.ones((5, 1))), raises(ParameterError, r"derivative_order")),
    Case("pde", "FieldWeakForm negative widths", lambda: dc.FieldWeakForm(widths=[-3]), returns(lambda m: m.widths == [-3])),
    Case("pde", "SpatialFiniteDifference order 0", lambda: dc.SpatialFiniteDifference(order=0).derivative(np.ones(8), 0, 1, 0.1, False), raises(ParameterError, r"order")),
    Case("pde", "SpatialSavitzkyGolay even window", lambda: dc.SpatialSavitzkyGolay(window_length=8).derivative(np.ones(20), 0, 1, 0.1, False), raises(ParameterError, r"window_length")),
    Case("pde", "SpatialSpectral negative cutoff", lambda: dc.SpatialSpectral(cutoff=-1.0).derivative(np.ones(16), 0, 1, 0.1, True), raises(ParameterError, r"cutoff")),
    Case("pde", "SpatialSpectral derivative of a sine", lambda: dc.SpatialSpectral().derivative(np.sin(GRID.coordinates[0]), 0, 1, GRID.coordinates[0][1], True), returns(equal(np.cos(GRID.coordinates[0]), atol=1e-8))),
    Case("optimizer", "PriorOnly learns nothing", lambda: dc.PriorOnly().fit(FEATURES, FEATURES[:, :1]).coef_, returns(lambda c: np.all(c == 0))),
    Case("optimizer", "PriorOnly of a text", lambda: dc.PriorOnly().fit("theta", FEATURES[:, :1]), raises(ShapeError, r"")),
    # DiscrepancyModel methods no other table reaches
    Case("model", "check_is_fitted unfitted", lambda: fast().check_is_fitted(), raises(NotFittedError, r"not fitted")),
    Case("model", "from_prior of a number", lambda: dc.DiscrepancyModel.from_prior(3), raises(DiscrepancyError, r"prior")),
    Case("model", "from_prior a decay simulates exp(-t)", lambda: dc.DiscrepancyModel.from_prior(lambda x, u: -x, state_names=["x"]).simulate([1.0], np.linspace(0, 1, 11))[-1, 0], returns(equal(np.exp(-1.0), rtol=1e-5))),
    Case("model", "get_feature_names unfitted", lambda: fast().get_feature_names(), raises(NotFittedError, r"not fitted")),
    Case("model", "get_feature_names of a linear library", lambda: FITTED.get_feature_names(), returns(lambda names: list(names) == ["1", "x1", "x2"])),
    Case("model", "get_params numpy argument kept", lambda: fast(feature_library=dc.PolynomialLibrary(np.int64(2))).get_params()["feature_library__degree"], returns(lambda d: d == 2)),
    Case("model", "set_params unknown", lambda: fast().set_params(bogus=1), raises(ParameterError, r"DiscrepancyModel has no parameter 'bogus'")),
    Case("model", "set_params a bad value", lambda: fast().set_params(selection="bogus").fit(X, T), raises(ParameterError, r"selection")),
    Case("model", "residual of a text", lambda: FITTED.residual("trajectory"), raises(ParameterError, r"trajectory must be a Trajectory .*got 'trajectory'")),
    Case("model", "residual of the training data", lambda: FITTED.residual(data.as_trajectories(X, T, x_dot=XD)[0])[1], returns(equal(XD))),
    Case("model", "to_state unfitted", lambda: fast().to_state(), raises(NotFittedError, r"not fitted")),
    Case("model", "to_state round trip", lambda: dc.DiscrepancyModel.from_state(FITTED.to_state()).coefficients(), returns(equal(FITTED.coefficients()))),
    Case("model", "get_metadata_routing", lambda: FITTED.get_metadata_routing(), returns(lambda r: r is not None)),
    # plots
    Case("plots", "selection_figure unfitted", lambda: selection_plots.selection_figure(fast()), raises(NotFittedError, r"fit")),
    Case("plots", "forecast_selection_figure without a selection", lambda: selection_plots.forecast_selection_figure(FITTED), raises(DiscrepancyError, r"select")),
    Case("plots", "procedure_figure of a text", lambda: selection_plots.procedure_figure("choice"), raises(ParameterError, r"choice must be what choose_procedure returns; got 'choice'")),
    Case("plots", "discrepancy_figure lengths differ", lambda: trajectory_plots.discrepancy_figure(T, X, XD[:5], XD, ["x1", "x2"]), raises(ShapeError, r"residual must be \(200, 2\) \(samples, states\); got shape \(5, 2\)")),
    Case("plots", "discrepancy_figure draws", lambda: trajectory_plots.discrepancy_figure(T, X, XD, XD, ["x1", "x2"]), returns(is_figure)),
    Case("plots", "validation_figure of a text", lambda: trajectory_plots.validation_figure(T, "runs", ["x1", "x2"]), raises(ParameterError, r"runs must be a non-empty mapping")),
    Case("plots", "validation_figure a run too short", lambda: trajectory_plots.validation_figure(T, {"true": X[:9]}, ["x1", "x2"]), raises(ShapeError, r"runs\['true'\] must be \(200, 2\)")),
    Case("plots", "validation_figure draws", lambda: trajectory_plots.validation_figure(T, {"truth": X}, ["x1", "x2"]), returns(is_figure)),
    Case("plots", "coefficient_spread_figure draws", lambda: trajectory_plots.coefficient_spread_figure({"poly": np.array([[1.0, 2.0], [1.1, 2.1]])}, {"x1": 1.0, "x2": 2.0}), returns(is_figure)),
    Case("plots", "uncertainty_figure of a text", lambda: uncertainty_plots.uncertainty_figure("unc"), raises(ParameterError, r"unc must be a model's bootstrap\(\) result; got 'unc'")),
]


def scalar_update():
    """One update of x ~ N(1, 4) by y = 3 with R = 1: mean 1 + 0.8 * 2, variance 0.8."""
    kf = estimation.KalmanFilter([sp.Integer(0)], outputs=["x1"], state_names=["x1"],
                                 process_noise=0.0, measurement_noise=1.0)
    state = kf.update(kf.start([1.0], [2.0]), [3.0])
    return [state.x[0], state.P[0, 0]]


def nested(depth):
    node = ["sym", "x1"]
    for _ in range(depth):
        node = ["add", node, ["num", 1, 1]]
    return node


@params(CASES)
def test_case(case, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)   # rows that save a model write in a fresh folder
    check(case)
