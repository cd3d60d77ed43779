"""Adversarial rows for the energy models and the control tools (see ``adversarial.py``)."""
from __future__ import annotations

import casadi as ca
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import discrepancy as dc
from adversarial import Case, check, params, raises, returns
from discrepancy.control import (
    MPC,
    OutputFeedback,
    SmoothedLogUpdater,
    as_casadi,
    closed_loop,
    plan_trajectory,
    replay,
    rk4_step,
    stationary_lqr,
    swing_up_errors,
    tvlqr,
)
from discrepancy.errors import (
    DataError,
    InfeasibleError,
    NotFittedError,
    ParameterError,
    PriorError,
    ResourceError,
    ShapeError,
)
from discrepancy.hybrid.codegen import compiled

# a damped oscillator q'' = -q - 0.1 q': H = (q^2 + dq^2) / 2 loses 0.1 dq^2 per second
T = np.arange(2000) * 0.01
SOL = solve_ivp(lambda t, s: [s[1], -s[0] - 0.1 * s[1]], (0, T[-1]), [1.0, 0.0], t_eval=T,
                rtol=1e-11, atol=1e-12).y.T
Q, DQ = SOL[:, :1], SOL[:, 1:]


def H(x):
    return 0.5 * (x[:, 0] ** 2 + x[:, 1] ** 2)


def dissipation(**kw):
    return dc.DissipationDiscrepancy(**{"energy": H, **kw})


def whole_law_torque(model) -> float:
    """The largest torque of the learned law over the recorded speeds DQ, term by term from
    its textbook form (viscous k|w|, Coulomb F, air drag c w^2, Stribeck F_s exp(-(w/v)^2))."""
    w = np.abs(DQ[:, 0])
    total = np.zeros_like(w)
    for term, c in zip(model.terms_, model.coef_, strict=True):
        kind = term.name.split(" ")[0]
        speed = float(term.name.split("(")[1].split(" ")[0]) if "rad/s" in term.name else 0.1
        total += c * {"viscous": w, "Coulomb": np.ones_like(w), "air": w ** 2,
                      "Stribeck": np.exp(-(w / speed) ** 2)}[kind]
    return float(np.max(total))


def state_form(**kw):
    return dc.EnergyDiscrepancy(**{"energy": H, "feature_library": dc.PolynomialLibrary(2),
                                   "optimizer": dc.STLSQ(threshold=0.01), **kw})


FITTED = dissipation().fit(Q, T, dq=DQ)
_x, _u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
DOUBLE = ca.Function("f", [_x, _u], [ca.vertcat(_x[1], _u)])   # a double integrator
PLAN = plan_trajectory(DOUBLE, x0=[0, 0], xf=[1, 0], T=1.0, n_intervals=10)
DECAY = lambda x, u: -x  # noqa: E731  (x' = -x, for replays)
# a unit spring from T and V (q'' = -q), and one driven by an input force u
_q, _dq, _u_sym = sp.symbols("q dq u")
SPRING = dc.systems.LagrangianSystem(_dq ** 2 / 2, _q ** 2 / 2, ["q"])
DRIVEN = dc.systems.LagrangianSystem(_dq ** 2 / 2, _q ** 2 / 2, ["q"], forces=[_u_sym],
                                     input_names=["u"])


def plan(**kw):
    return plan_trajectory(DOUBLE, **{"x0": [0, 0], "xf": [1, 0], "T": 1.0, "n_intervals": 10,
                                      **kw})


CASES = [
    # --- energy
    Case("energy", "energy not callable", lambda: dissipation(energy=3).fit(Q, T, dq=DQ), raises(ParameterError, r"energy must be a callable")),
    Case("energy", "energy returning NaN", lambda: dissipation(energy=lambda x: x[:, 0] * np.nan).fit(Q, T, dq=DQ), raises(ShapeError, r"energy\(x\) returned a non-finite value at row 0")),
    Case("energy", "energy returning complex", lambda: dissipation(energy=lambda x: H(x) + 0j).fit(Q, T, dq=DQ), raises(PriorError, r"energy\(x\) must return real values")),
    Case("energy", "energy raising", lambda: dissipation(energy=lambda x: 1 / 0).fit(Q, T, dq=DQ), raises(PriorError, r"energy\(x\) raised ZeroDivisionError")),
    Case("energy", "energy returning a word", lambda: dissipation(energy=lambda x: "J").fit(Q, T, dq=DQ), raises(PriorError, r"energy\(x\) must return")),
    Case("energy", "energy of the wrong length", lambda: dissipation(energy=lambda x: H(x)[:5]).fit(Q, T, dq=DQ), raises(ShapeError, r"energy\(x\) must return \(2000,\)")),
    Case("energy", "negative kinetic energy", lambda: dc.systems.LagrangianSystem(-_dq ** 2 / 2, _q ** 2 / 2, ["q"]), raises(ParameterError, r"kinetic energy must be positive: the mass of coordinate 'q' \(∂²T/∂dq²\) is -1")),
    Case("energy", "kinetic energy without a coordinate's rate", lambda: dc.systems.LagrangianSystem(_dq ** 2 / 2, _q ** 2 / 2, ["q", "p"]), raises(ParameterError, r"the mass of coordinate 'p' \(∂²T/∂dp²\) is 0")),
    Case("energy", "indefinite kinetic energy", lambda: dc.systems.LagrangianSystem(_dq ** 2 / 2 + sp.Symbol("dp") ** 2 / 2 + 2 * _dq * sp.Symbol("dp"), _q ** 2 / 2, ["q", "p"]), raises(ParameterError, r"mass matrix M = ∂²T/∂q̇² is not positive definite")),
    Case("energy", "mass matrix singular at a sample", lambda: dc.systems.LagrangianSystem((sp.Symbol("dx") ** 2 + _dq ** 2) / 2 + sp.Symbol("dx") * _dq * sp.cos(_q), 0 * _q, ["x", "q"]).rhs([0.0, 0.0, 0.0, 0.0]), raises(DataError, r"mass matrix M\(q\) is singular at sample 0 \(x=0, q=0, dx=0, dq=0\)")),
    Case("energy", "q with NaN", lambda: dissipation().fit(np.where(T[:, None] > 5, np.nan, Q), T, dq=DQ), raises(DataError, r"^q must be finite")),
    Case("energy", "dq with other rows", lambda: dissipation().fit(Q, T, dq=DQ[:10]), raises(ShapeError, r"^dq must have 2000 rows")),
    Case("energy", "t decreasing", lambda: dissipation().fit(Q, -T, dq=DQ), raises(DataError, r"^t must be strictly increasing")),
    Case("energy", "position_names of the wrong count", lambda: dissipation(position_names=["a", "b"]).fit(Q, T, dq=DQ), raises(ShapeError, r"q has 1 columns; position_names has 2")),
    Case("energy", "position_names not identifiers", lambda: dissipation(position_names=["a b"]).fit(Q, T, dq=DQ), raises(ParameterError, r"position_names must be")),
    Case("energy", "max_terms 0", lambda: dissipation(max_terms=0).fit(Q, T, dq=DQ), raises(ParameterError, r"max_terms must be an integer >= 1")),
    Case("energy", "holdout 0.95", lambda: dissipation(holdout=0.95).fit(Q, T, dq=DQ), raises(ParameterError, r"holdout must be")),
    Case("energy", "block_seconds 0", lambda: dissipation(block_seconds=0).fit(Q, T, dq=DQ), raises(ParameterError, r"block_seconds must be")),
    Case("energy", "friction terms of text", lambda: dissipation(friction_terms=["viscous"]).fit(Q, T, dq=DQ), raises(ParameterError, r"friction_terms must be")),
    Case("energy", "friction library of no names", lambda: dc.energy.default_friction_library([]), raises(ParameterError, r"velocity_names must be a non-empty list")),
    Case("energy", "friction joint of an unknown speed", lambda: dc.energy.default_friction_library(["dq1"], joints={"j": "dq9"}), raises(ParameterError, r"joints\['j'\] must be a velocity name")),
    Case("energy", "negative Stribeck speed", lambda: dc.energy.default_friction_library(["dq1"], stribeck_speed=-1), raises(ParameterError, r"stribeck_speed must be > 0")),
    Case("energy", "blocks longer than the record", lambda: dissipation(block_seconds=15).fit(Q, T, dq=DQ), raises(ParameterError, r"block_seconds = 15 s leaves 1 blocks of a 19.99 s record; the fit needs at least 3")),
    Case("energy", "a step so large the times overflow", lambda: dissipation().fit(Q, 1e308, dq=DQ), raises(DataError, r"^t as a time step of 1e\+308")),
    Case("energy", "bootstrap of 1 resample", lambda: FITTED.bootstrap(Q, T, dq=DQ, n_resamples=1), raises(ParameterError, r"n_resamples must be an integer >= 2")),
    Case("energy", "bootstrap blocks of 0 s", lambda: FITTED.bootstrap(Q, T, dq=DQ, block_seconds=0), raises(ParameterError, r"block_seconds must be > 0 s")),
    Case("energy", "bootstrap seed a word", lambda: FITTED.bootstrap(Q, T, dq=DQ, seed="a"), raises(ParameterError, r"seed must be")),
    Case("energy", "interval of a number", lambda: FITTED.predict_interval(Q, T, 3, dq=DQ), raises(ParameterError, r"uncertainty must be this model's bootstrap")),
    Case("energy", "predict before fit", lambda: dissipation().predict(Q, T, dq=DQ), raises(NotFittedError, r"fit\(q, t\)")),
    Case("energy", "state form without a library", lambda: dc.EnergyDiscrepancy(energy=H, optimizer=dc.STLSQ()).fit(Q, T, dq=DQ), raises(ParameterError, r"feature_library must be a feature library")),
    Case("energy", "viscous friction recovered", lambda: FITTED.identified_terms(), returns(lambda terms: len(terms) == 1 and terms[0]["name"] == "viscous joint 1" and abs(terms[0]["coefficient"] - 0.1) < 1e-4)),
    Case("energy", "torque_limit negative", lambda: dissipation(torque_limit=-1.0).fit(Q, T, dq=DQ), raises(ParameterError, r"torque_limit must be")),
    Case("energy", "torque_limit of text", lambda: dissipation(torque_limit="large").fit(Q, T, dq=DQ), raises(ParameterError, r"torque_limit must be")),
    Case("energy", "torque_limit binds the whole law", lambda: dissipation(torque_limit=0.01).fit(Q, T, dq=DQ), returns(lambda m: whole_law_torque(m) <= 0.01 * (1 + 1e-9))),
    Case("energy", "fit_window 0", lambda: dissipation(fit_window=0).fit(Q, T, dq=DQ), raises(ParameterError, r"fit_window must be")),
    Case("energy", "fit_window longer than the record", lambda: dissipation(fit_window=1e6).fit(Q, T, dq=DQ).coef_, returns(lambda c: np.allclose(c, FITTED.coef_, rtol=1e-12))),
    Case("energy", "blind_fit split past the data", lambda: dc.energy.blind_fit(dissipation(), Q, T, split=5000), raises(ParameterError, r"split must be an integer >= 10 and < 2000; got 5000")),
    Case("energy", "blind_fit candidates of numbers", lambda: dc.energy.blind_fit({"a": 1}, Q, T, split=1600), raises(ParameterError, r"candidates must be a non-empty mapping")),
    Case("energy", "blind_fit one origin", lambda: dc.energy.blind_fit(dissipation(), Q, T, split=1600, n_origins=1), raises(ParameterError, r"n_origins must be an integer in \[2, 100\]")),
    Case("energy", "blind_fit a billion origins", lambda: dc.energy.blind_fit(dissipation(), Q, T, split=1600, n_origins=10**9), raises(ParameterError, r"n_origins must be an integer in \[2, 100\].*got 1000000000")),
    Case("energy", "blind_fit horizon longer than training", lambda: dc.energy.blind_fit(dissipation(), Q, T, split=1600, horizon=100.0), raises(ParameterError, r"horizon \(s\) must be a finite number > 0 and < 15.99")),
    Case("energy", "blind_fit horizon too long for origins", lambda: dc.energy.blind_fit(dissipation(), Q, T, split=1600, horizon=12.0), raises(DataError, r"too short to forecast 12 s")),
    Case("energy", "system with an unknown symbol", lambda: dc.systems.LagrangianSystem(sp.Symbol("m") * sp.Symbol("dq") ** 2, sp.Symbol("q") ** 2, ["q"]), raises(ParameterError, r"kinetic uses \['m'\]")),
    Case("energy", "system with too few rates", lambda: dc.systems.LagrangianSystem(sp.Symbol("dq") ** 2, sp.Symbol("q") ** 2, ["q", "p"], rates=["dq"]), raises(ParameterError, r"rates must name one rate per coordinate \(2\)")),
    Case("energy", "system forces of the wrong count", lambda: dc.systems.LagrangianSystem(sp.Symbol("dq") ** 2, sp.Symbol("q") ** 2, ["q"], forces=[0, 0]), raises(ParameterError, r"forces must be a list of 1 expressions")),
    Case("energy", "system state of the wrong width", lambda: SPRING.rhs(np.zeros((3, 3))), raises(ShapeError, r"x must be \(m, 2\) = \['q', 'dq'\]")),
    Case("energy", "system input missing", lambda: DRIVEN.rhs(np.zeros((3, 2))), raises(ShapeError, r"u is required")),
    Case("energy", "system equations of a spring", lambda: SPRING.rhs(np.array([[0.3, 0.2]])), returns(lambda f: np.allclose(f, [[0.2, -0.3]], rtol=1e-14))),
    Case("energy", "from_system of a system without joints", lambda: dc.DissipationDiscrepancy.from_system(dc.systems.VanDerPol()), raises(ParameterError, r"system must have energy, position_names and joints\(\)")),
    # --- control
    Case("control", "model a number", lambda: as_casadi(3), raises(ParameterError, r"model must be a casadi.Function")),
    Case("control", "model a discrete-time map", lambda: MPC(dc.DiscrepancyModel.from_prior([0.9 * sp.Symbol("x")], state_names=["x"], discrete_time=True), dt=0.1), raises(ParameterError, r"model is discrete-time")),
    Case("control", "dynamics without inputs", lambda: as_casadi(ca.Function("f", [_x], [_x])), raises(ShapeError, r"dynamics must map \(x \(n,1\), u \(r,1\)\)")),
    Case("control", "unknown cost", lambda: plan(cost="time"), raises(ParameterError, r"cost must be one of \('tracking', 'effort'\); got 'time'")),
    Case("control", "negative horizon", lambda: plan(T=-1), raises(ParameterError, r"plan_trajectory: T must be a finite number > 0; got -1")),
    Case("control", "horizon a word", lambda: plan(T="long"), raises(ParameterError, r"T must be")),
    Case("control", "1 interval", lambda: plan(n_intervals=1), raises(ParameterError, r"plan_trajectory: n_intervals must be an integer >= 2; got 1")),
    Case("control", "substeps 0", lambda: plan(substeps=0), raises(ParameterError, r"substeps must be")),
    Case("control", "x0 of 3 states", lambda: plan(x0=[0, 0, 0]), raises(ShapeError, r"x0 must have 2 entries")),
    Case("control", "xf with NaN", lambda: plan(xf=[np.nan, 0]), raises(ParameterError, r"xf must be finite")),
    Case("control", "Q of the wrong size", lambda: plan(Q=[1, 2, 3]), raises(ShapeError, r"Q must have 2 entries")),
    Case("control", "bounds upside down", lambda: plan(u_bounds=[[1, -1]]), raises(ShapeError, r"u_bounds must be \(\w, 2\) rows of \(lower, upper\) with lower <= upper")),
    Case("control", "unreachable in time", lambda: plan(u_bounds=[[-0.01, 0.01]]), raises(InfeasibleError, r"T = 1 s is too short to reach xf .* misses xf by")),
    Case("control", "plan of the double integrator", lambda: PLAN.x[-1], returns(lambda x: np.allclose(x, [1, 0], atol=1e-8))),
    Case("control", "rk4 step of 0 substeps", lambda: rk4_step(DOUBLE, 0.1, 0), raises(ParameterError, r"substeps must be an integer >= 1 and <= 1000; got 0")),
    Case("control", "tvlqr R of the wrong shape", lambda: tvlqr(DOUBLE, PLAN, R=np.ones((3, 3))), raises(ShapeError, r"R must be a scalar, \(1,\) diagonal or \(1, 1\)")),
    Case("control", "replay with NaN in t", lambda: replay(DECAY, [1.0], [0, np.nan, 2], np.zeros((2, 1))), raises(DataError, r"^t must be finite")),
    Case("control", "replay with 10**10 samples", lambda: replay(DECAY, [1.0], [0, 1, 2], np.zeros((2, 1)), samples=10**10), raises(ResourceError, r"replay's dense output")),
    Case("control", "replay with 0 samples", lambda: replay(DECAY, [1.0], [0, 1, 2], np.zeros((2, 1)), samples=0), raises(ParameterError, r"replay: samples must be an integer >= 1")),
    Case("control", "replay with a negative tolerance", lambda: replay(DECAY, [1.0], [0, 1, 2], np.zeros((2, 1)), rtol=-1), raises(ParameterError, r"replay: rtol must be")),
    Case("control", "replay with x0 NaN", lambda: replay(DECAY, [np.nan], [0, 1, 2], np.zeros((2, 1))), raises(DataError, r"^x0 must be finite")),
    Case("control", "replay with a law of the wrong length", lambda: replay(DECAY, [1.0], [0, 1, 2], np.zeros((5, 1))), raises(ShapeError, r"law must have one input row per interval \(2\)")),
    Case("control", "replay on a non-uniform grid", lambda: replay(DECAY, [1.0], [0, 1, 3], np.zeros((2, 1))), raises(ParameterError, r"t must be uniformly spaced")),
    Case("control", "replay of a feedback law raising", lambda: replay(DECAY, [1.0], [0, 1, 2], lambda k, x: 1 / 0), raises(ParameterError, r"law raised ZeroDivisionError")),
    Case("control", "replay of x' = -x is exact", lambda: replay(DECAY, [1.0], [0, 1, 2], np.zeros((2, 1))).x[:, 0], returns(lambda x: np.allclose(x, np.exp(-np.arange(3.0)), rtol=1e-9))),
    Case("control", "swing-up errors of a missing index", lambda: swing_up_errors([0.0, 0.0], angles=[5], rates=[1]), raises(ShapeError, r"angles")),
    # --- control: real-time MPC, output feedback, re-identification from control logs
    Case("control", "MPC solver unknown", lambda: MPC(DOUBLE, dt=0.1, solver="acados"), raises(ParameterError, r"MPC: solver must be one of 'ipopt', 'rti'; got 'acados'")),
    Case("control", "MPC qp_solver unknown", lambda: MPC(DOUBLE, dt=0.1, solver="rti", qp_solver="gurobi2"), raises(ParameterError, r"qp_solver must be a CasADi QP solver available here .* got 'gurobi2'")),
    Case("control", "MPC max_iter 0", lambda: MPC(DOUBLE, dt=0.1, solver="rti", max_iter=0), raises(ParameterError, r"MPC: max_iter must be None or an integer >= 1 and <= 100000; got 0")),
    Case("control", "MPC max_iter True", lambda: MPC(DOUBLE, dt=0.1, solver="rti", max_iter=True), raises(ParameterError, r"MPC: max_iter must be None or an integer >= 1 .*; got True")),
    Case("control", "MPC compile a word", lambda: MPC(DOUBLE, dt=0.1, solver="rti", compile="yes"), raises(ParameterError, r"compile must be True or False; got 'yes'")),
    Case("control", "MPC soft_penalty 0", lambda: MPC(DOUBLE, dt=0.1, solver="rti", soft_penalty=0.0), raises(ParameterError, r"MPC: soft_penalty must be a finite number > 0; got 0.0")),
    Case("control", "stationary_lqr with diagonal weights as a list", lambda: stationary_lqr(DOUBLE, [0, 0], [0], dt=0.1, substeps=np.int64(2), Q=[1, 1], R=1)[0].shape, returns(lambda v: v == (1, 2))),
    Case("control", "stationary_lqr with a negative weight", lambda: stationary_lqr(DOUBLE, [0, 0], [0], dt=0.1, substeps=2, Q=[-1, 1], R=1), raises(ParameterError, r"Q must be positive semidefinite weights \(>= 0\); diagonal entries \[0\] are negative")),
    Case("control", "MPC negative state weights", lambda: MPC(DOUBLE, dt=0.1, Q=[-1, -1]), raises(ParameterError, r"Q must be positive semidefinite weights \(>= 0\); diagonal entries \[0, 1\] are negative")),
    Case("control", "MPC indefinite state weights", lambda: MPC(DOUBLE, dt=0.1, Q=[[1, 2], [2, 1]]), raises(ParameterError, r"Q must be positive semidefinite .*smallest eigenvalue is -1")),
    Case("control", "MPC negative soft_penalty", lambda: MPC(DOUBLE, dt=0.1, soft_penalty=-5.0), raises(ParameterError, r"MPC: soft_penalty must be a finite number > 0; got -5")),
    Case("control", "MPC horizon of a billion", lambda: MPC(DOUBLE, dt=0.1, horizon=10**9), raises(ParameterError, r"MPC: horizon must be an integer >= 2 and <= 10000; got 1000000000")),
    Case("control", "MPC np.int64 horizon", lambda: MPC(DOUBLE, dt=0.1, horizon=np.int64(5), substeps=np.int64(2)).horizon, returns(lambda v: v == 5 and type(v) is int)),
    Case("control", "closed_loop np.int64 steps", lambda: len(closed_loop(DOUBLE, lambda k, x: np.zeros(1), [0.0, 0.0], dt=0.1, steps=np.int64(3)).t), returns(lambda v: v == 4)),
    Case("control", "closed_loop of 10**12 steps", lambda: closed_loop(DOUBLE, lambda k, x: np.zeros(1), [0.0, 0.0], dt=0.1, steps=10**12), raises(ResourceError, r"the log of 1000000000000 steps x 1 samples of 2 states would need")),
    Case("control", "MPC soft_penalty NaN", lambda: MPC(DOUBLE, dt=0.1, solver="rti", soft_penalty=np.nan), raises(ParameterError, r"MPC: soft_penalty must be a finite number > 0; got nan")),
    Case("control", "RTI state of the wrong size", lambda: MPC(DOUBLE, dt=0.1, horizon=4, solver="rti").solve(np.zeros(3), np.zeros((5, 2)), np.zeros((4, 1))), raises(ShapeError, r"x must be the measured state \(2,\); got shape \(3,\)")),
    Case("control", "RTI reference of the wrong shape", lambda: MPC(DOUBLE, dt=0.1, horizon=4, solver="rti").solve(np.zeros(2), np.zeros((4, 2)), np.zeros((4, 1))), raises(ShapeError, r"x_ref must be \(5, 2\) and u_ref \(4, 1\)")),
    Case("control", "RTI one step on a linear system is exact", lambda: MPC(DOUBLE, dt=0.1, horizon=4, solver="rti").solve(np.array([1.0, 0.0]), np.zeros((5, 2)), np.zeros((4, 1))).x[1], returns(lambda x: np.allclose(x, [1.0, 0.0] + np.array([0.005, 0.1]) * RTI_U0, atol=1e-12))),
    Case("control", "RTI with an input already past its bound and rate", lambda: MPC(DOUBLE, dt=0.1, horizon=4, solver="rti", limits=dc.control.Limits(u_bounds=[[-1, 1]], du_max=[1.0])).solve(np.zeros(2), np.zeros((5, 2)), np.zeros((4, 1)), u_prev=[5.0]).success, returns(lambda ok: ok is False)),
    Case("control", "RTI warm start of NaN", lambda: MPC(DOUBLE, dt=0.1, horizon=4, solver="rti").solve(np.array([1.0, 0.0]), np.zeros((5, 2)), np.zeros((4, 1)), warm=NAN_WARM).u[0], returns(lambda u: np.allclose(u, RTI_U0, atol=1e-9))),
    Case("control", "compiled with enabled a string", lambda: compiled(DOUBLE, enabled="no"), raises(ParameterError, r"compile must be True or False; got 'no'")),
    Case("control", "closed loop outputs out of range", lambda: closed_loop(DOUBLE, lambda k, y: np.zeros(1), [0.0, 0.0], dt=0.1, steps=2, outputs=[2]), raises(ParameterError, r"outputs must be distinct indices of the 2 states")),
    Case("control", "closed loop outputs repeated", lambda: closed_loop(DOUBLE, lambda k, y: np.zeros(1), [0.0, 0.0], dt=0.1, steps=2, outputs=[0, 0]), raises(ParameterError, r"outputs must be distinct indices")),
    Case("control", "closed loop outputs by name", lambda: closed_loop(DOUBLE, lambda k, y: np.zeros(1), [0.0, 0.0], dt=0.1, steps=2, outputs=["p"]), raises(ParameterError, r"outputs must be distinct indices")),
    Case("control", "closed loop outputs empty", lambda: closed_loop(DOUBLE, lambda k, y: np.zeros(1), [0.0, 0.0], dt=0.1, steps=2, outputs=[]), raises(ParameterError, r"outputs must be distinct indices of the 2 states \(at least one\)")),
    Case("control", "closed loop gives the law only the outputs", lambda: closed_loop(DOUBLE, SEEN.append_zero, [3.0, 4.0], dt=0.1, steps=1, outputs=[1]) and SEEN.last, returns(lambda y: np.array_equal(y, [4.0]))),
    Case("control", "output feedback without a filter", lambda: OutputFeedback(lambda k, x: np.zeros(1), object(), x0=[0, 0], P0=1.0, dt=0.1), raises(ParameterError, r"estimator must have start, update and predict")),
    Case("control", "output feedback dt 0", lambda: OutputFeedback(lambda k, x: np.zeros(1), EKF, x0=[0, 0], P0=1.0, dt=0), raises(ParameterError, r"dt must be a positive control period")),
    Case("control", "output feedback law a number", lambda: OutputFeedback(3, EKF, x0=[0, 0], P0=1.0, dt=0.1), raises(ParameterError, r"law must be callable")),
    Case("control", "output feedback called twice", lambda: _twice(), raises(ShapeError, r"called twice without notify_applied")),
    Case("control", "output feedback errors of another run", lambda: OutputFeedback(lambda k, x: np.zeros(1), EKF, x0=[0, 0], P0=1.0, dt=0.1).estimation_errors(closed_loop(DOUBLE, lambda k, y: np.zeros(1), [0.0, 0.0], dt=0.1, steps=3)), raises(ShapeError, r"the run has states \(0, 2\)|the run has states")),
    Case("control", "log updater outputs a string", lambda: updater(outputs="p").update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"outputs must be a list of distinct state names; got 'p'")),
    Case("control", "log updater outputs repeated", lambda: updater(outputs=["p", "p"]).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"outputs must be a list of distinct state names")),
    Case("control", "log updater unknown output", lambda: updater(outputs=["angle"]).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"outputs and kinematics name unknown states \['angle'\]")),
    Case("control", "log updater kinematics a list", lambda: updater(kinematics=["p", "v"]).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"kinematics must be a dict")),
    Case("control", "log updater kinematics unknown rate", lambda: updater(kinematics={"p": "speed"}).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"unknown states \['speed'\]")),
    Case("control", "log updater substeps 0", lambda: updater(substeps=0).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"substeps must be an integer >= 1; got 0")),
    Case("control", "log updater passes 0", lambda: updater(passes=0).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"passes must be an integer >= 1; got 0")),
    Case("control", "log updater process noise a word", lambda: updater(process_noise="high").update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"process_noise must be 'auto' or a std per state; got 'high'")),
    Case("control", "log updater callable prior", lambda: SmoothedLogUpdater(dc.DiscrepancyModel(prior=lambda x, u: x), outputs=["x1"], measurement_noise=[0.1]).update(LOG_Y, 0.1, u=LOG_U), raises(ParameterError, r"model must be an unfitted DiscrepancyModel with a sympy prior")),
    Case("control", "log updater period negative", lambda: updater().update(LOG_Y, -0.1, u=LOG_U), raises(ParameterError, r"t must be the control period \(s\) of the log; got -0.1")),
    Case("control", "log updater inputs of the wrong length", lambda: updater().update(LOG_Y, 0.1, u=LOG_U[:-1]), raises(ShapeError, r"y must be \(m, 1\) and u \(m, 1\)")),
    Case("control", "log updater of two samples", lambda: updater().update(LOG_Y[:2], 0.1, u=LOG_U[:2]), raises(ShapeError, r"a log needs at least 3 samples; got 2")),
    Case("control", "log updater finds a missing force", lambda: updater().update(LOG_Y, 0.1, u=LOG_U).coefficients(), returns(lambda c: np.count_nonzero(c) == 1 and abs(c[1, 2] + 0.5) < 0.01)),
]


def _rti_u0():
    """The first input of the double integrator's unconstrained MPC from (1, 0), horizon 4,
    Q = I, R = 1, terminal weight Q: the exact QP solved by numpy."""
    A, B = np.array([[1, 0.1], [0, 1]]), np.array([[0.005], [0.1]])
    G = np.zeros((8, 4))
    for k in range(4):
        for j in range(k + 1):
            G[2 * k:2 * k + 2, j] = (np.linalg.matrix_power(A, k - j) @ B).ravel()
    free = np.concatenate([np.linalg.matrix_power(A, k + 1) @ [1.0, 0.0] for k in range(4)])
    return np.linalg.solve(G.T @ G + np.eye(4), -G.T @ free)[0]


class _Seen(list):
    last = None

    def append_zero(self, k, y):
        _Seen.last = np.asarray(y)
        return np.zeros(1)


def _twice():
    law = OutputFeedback(lambda k, x: np.zeros(1), EKF, x0=[0, 0], P0=1.0, dt=0.1)
    law(0, [0.0])
    law(1, [0.0])


def updater(**kw):
    """Re-identification of x'' = u - 0.5 x' whose prior misses the friction, position measured."""
    p, v, u = (dc.symbolic.symbol(n) for n in ("p", "v", "u"))
    model = dc.DiscrepancyModel(prior=[v, u], feature_library=dc.PolynomialLibrary(1),
                                state_names=["p", "v"], input_names=["u"])
    options = {"outputs": ["p"], "measurement_noise": [1e-4], "kinematics": {"p": "v"},
               "optimizer": dc.STLSQ(threshold="auto", normalize_columns=True), **kw}
    return SmoothedLogUpdater(model, **options)


def _log():
    """Position of x'' = u - 0.5 x' sampled every 0.1 s with u held, noise 1e-4 (seed 0)."""
    rng = np.random.default_rng(0)
    u = np.repeat(rng.uniform(-1, 1, 20), 5)[:, None]
    A = np.array([[0.0, 1.0], [0.0, -0.5]])
    from scipy.linalg import expm
    M = np.zeros((3, 3))
    M[:2, :2], M[1, 2] = A, 1.0
    M = expm(M * 0.1)
    x, ys = np.zeros(2), []
    for k in range(100):
        ys.append(x[0] + 1e-4 * rng.standard_normal())
        x = M[:2, :2] @ x + M[:2, 2] * u[k, 0]
    return np.array(ys)[:, None], u


RTI_U0 = _rti_u0()
NAN_WARM = MPC(DOUBLE, dt=0.1, horizon=4, solver="rti").solve(
    np.array([1.0, 0.0]), np.zeros((5, 2)), np.zeros((4, 1)))
NAN_WARM = type(NAN_WARM)(**{**NAN_WARM.__dict__, "x": NAN_WARM.x * np.nan})
SEEN = _Seen()
EKF = __import__("discrepancy.estimation", fromlist=["x"]).ExtendedKalmanFilter(
    [dc.symbolic.symbol("v"), dc.symbolic.symbol("u")], outputs=["p"], process_noise=[0.0, 0.0],
    measurement_noise=[0.01], state_names=["p", "v"], input_names=["u"])
LOG_Y, LOG_U = _log()


@params(CASES)
def test_case(case):
    check(case)
