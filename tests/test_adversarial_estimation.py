"""Adversarial rows for the state estimators and the prediction-error fit (see
``adversarial.py``)."""
from __future__ import annotations

import numpy as np
import sympy as sp

import discrepancy as dc
from adversarial import Case, check, params, raises, returns
from discrepancy.errors import (
    ConvergenceError,
    DataError,
    NotFittedError,
    ParameterError,
    PriorError,
    ShapeError,
    UnknownNameError,
)
from discrepancy.estimation import ExtendedKalmanFilter, UnscentedKalmanFilter
from discrepancy.symbolic import symbol

X1, X2, U = symbol("x1"), symbol("x2"), symbol("u")
OSC = [X2, -X1]
T = np.arange(100) * 0.05
Y = np.sin(T)[:, None]


def ekf(model=OSC, cls=ExtendedKalmanFilter, **kw):
    settings = {"outputs": ["x1"], "process_noise": [0.0, 0.1], "measurement_noise": 0.05,
                "state_names": ["x1", "x2"], **kw}
    return cls(model, **settings)


EKF = ekf()
CONSTANT = ExtendedKalmanFilter([sp.Integer(0)], outputs=["x1"], state_names=["x1"],
                                process_noise=0.0, measurement_noise=1.0)
DRIVEN = ekf([X2, -X1 + U], input_names=["u"])
RUN = EKF.filter(Y, 0.05, x0=[0, 1], P0=[0.1, 0.1])


def running_mean(run):
    y = np.array([3.0, 1.0, 2.0, 6.0])
    return np.allclose(run.x[:, 0], np.cumsum(y) / np.arange(1, 5), atol=1e-6)


def scalar_update():
    """One update of x ~ N(1, 4) by y = 3 with R = 1: mean 1 + 0.8 * 2, variance 0.8."""
    state = CONSTANT.update(CONSTANT.start([1.0], [2.0]), [3.0])
    return np.allclose([state.x[0], state.P[0, 0]], [2.6, 0.8])


def pem_model(**kw):
    return dc.DiscrepancyModel(prior=[X2, -X1 + U], state_names=["x1", "x2"], input_names=["u"],
                               feature_library=dc.CustomLibrary([X2]), **kw)


def pem(y=Y, **kw):
    settings = {"outputs": ["x1"], "u": np.zeros((len(y), 1)), **kw}
    return pem_model().fit_prediction_error(y, 0.05, **settings)


CASES = [
    # --- constructing a filter
    Case("estimation", "process noise of 3 values for 2 states", lambda: ekf(process_noise=[1, 1, 1]), raises(ShapeError, r"^process_noise must be a number, 2 standard deviations \(2,\) or a covariance \(2, 2\) \(per second\)")),
    Case("estimation", "fit_prediction_error with substeps=0", lambda: pem(substeps=0), raises(ParameterError, r"^substeps must be an integer in \[1, 1000\].*got 0")),
    Case("estimation", "fit_prediction_error with 10**6 substeps", lambda: pem(substeps=10**6), raises(ParameterError, r"^substeps must be an integer in \[1, 1000\]")),
    Case("estimation", "a negative process noise", lambda: ekf(process_noise=[0, -1]), raises(DataError, r"^process_noise must be non-negative standard deviations")),
    Case("estimation", "an asymmetric process covariance", lambda: ekf(process_noise=[[1, 0.5], [0, 1]]), raises(DataError, r"^process_noise must be a symmetric covariance")),
    Case("estimation", "an indefinite process covariance", lambda: ekf(process_noise=[[1, 2], [2, 1]]), raises(DataError, r"^process_noise must be positive semidefinite; its smallest eigenvalue is -1")),
    Case("estimation", "process noise as text", lambda: ekf(process_noise="big"), raises(ShapeError, r"^process_noise must be a numeric array")),
    Case("estimation", "measurement noise 0", lambda: ekf(measurement_noise=0.0), raises(DataError, r"^measurement_noise must be positive standard deviations.*innovation covariance singular")),
    Case("estimation", "a singular measurement covariance", lambda: ekf(outputs=["x1", "x2"], measurement_noise=[[1, 1], [1, 1]]), raises(DataError, r"^measurement_noise must be positive definite")),
    Case("estimation", "measurement noise NaN", lambda: ekf(measurement_noise=np.nan), raises(DataError, r"^measurement_noise must be finite")),
    Case("estimation", "an output that is not a state", lambda: ekf(outputs=["z"]), raises(UnknownNameError, r"outputs\[0\] = 'z' is not a state")),
    Case("estimation", "no outputs", lambda: ekf(outputs=None), raises(ParameterError, r"outputs is required")),
    Case("estimation", "0 substeps", lambda: ekf(substeps=0), raises(ParameterError, r"substeps must be")),
    Case("estimation", "an unknown input hold", lambda: ekf(u_hold="cubic"), raises(ParameterError, r"u_hold must be one of 'linear', 'zoh', 'bandlimited'; got 'cubic'")),
    Case("estimation", "a model that is a number", lambda: ExtendedKalmanFilter(3, outputs=[0], process_noise=1, measurement_noise=1), raises(ParameterError, r"model must be a fitted DiscrepancyModel, a callable")),
    Case("estimation", "an unfitted model", lambda: ExtendedKalmanFilter(dc.DiscrepancyModel(), outputs=[0], process_noise=1, measurement_noise=1), raises(NotFittedError, r"not fitted yet")),
    Case("estimation", "a callable without its number of states", lambda: ExtendedKalmanFilter(lambda x, u: -x, outputs=[0], process_noise=1.0, measurement_noise=1), raises(ParameterError, r"needs state_names=")),
    Case("estimation", "an unknown backend", lambda: ekf(backend="jax"), raises(ParameterError, r"backend must be one of 'auto', 'casadi', 'numpy'; got 'jax'")),
    Case("estimation", "a disturbance on no state", lambda: ekf(disturbances=["x3"], process_noise=[0, 1, 1]), raises(UnknownNameError, r"disturbances\[0\] = 'x3' is not a state")),
    Case("estimation", "a disturbance named twice", lambda: ekf(disturbances=["x2", 1], process_noise=[0, 1, 1, 1]), raises(ParameterError, r"disturbances names an equation twice")),
    Case("estimation", "unscented alpha 0", lambda: ekf(cls=UnscentedKalmanFilter, alpha=0), raises(ParameterError, r"alpha must be")),
    Case("estimation", "state names clashing with inputs", lambda: ekf(input_names=["x1"]), raises(ParameterError, r"must not share names")),
    Case("estimation", "a prior returning the wrong shape", lambda: ekf(lambda x, u: x[:, :1], backend="numpy").filter(Y, 0.05), raises(PriorError, r"prior must return an array of shape")),
    # --- filtering a record
    Case("estimation", "y with 2 columns for 1 output", lambda: EKF.filter(np.zeros((10, 2)), 0.05), raises(ShapeError, r"^y must be \(m, 1\): one column per output \['x1'\]")),
    Case("estimation", "y with inf", lambda: EKF.filter(np.r_[Y[:5], [[np.inf]]], 0.05), raises(DataError, r"^y must be finite or NaN .* inf at row 5")),
    Case("estimation", "y of NaN only", lambda: EKF.filter(np.full((5, 1), np.nan), 0.05), raises(DataError, r"y holds no measurement")),
    Case("estimation", "no times for a continuous model", lambda: EKF.filter(Y), raises(DataError, r"^t is required")),
    Case("estimation", "times going back", lambda: EKF.filter(Y[:3], [0.0, 0.1, 0.05]), raises(DataError, r"^t must be strictly increasing")),
    Case("estimation", "no u for a model with inputs", lambda: DRIVEN.filter(Y, 0.05), raises(ShapeError, r"u is required: the model has 1 inputs \['u'\]")),
    Case("estimation", "u for a model without inputs", lambda: EKF.filter(Y, 0.05, u=np.zeros((100, 1))), raises(ShapeError, r"u was given but the model has no inputs")),
    Case("estimation", "u with NaN", lambda: DRIVEN.filter(Y, 0.05, u=np.full((100, 1), np.nan)), raises(DataError, r"^u must be finite")),
    Case("estimation", "x0 of 3 states", lambda: EKF.filter(Y, 0.05, x0=[0, 0, 0]), raises(ShapeError, r"^x0 must be 2 finite numbers")),
    Case("estimation", "a negative P0", lambda: EKF.filter(Y, 0.05, P0=[-1, 1]), raises(DataError, r"^P0 must be non-negative standard deviations")),
    Case("estimation", "a model that blows up", lambda: ekf([X1 ** 2, sp.Integer(0)]).filter(np.full((50, 1), 5.0), 0.5, x0=[5, 0]), raises(ConvergenceError, r"the filter failed at sample \d+ \(t = ")),
    Case("estimation", "smooth of something else", lambda: EKF.smooth(Y), raises(ParameterError, r"smooth takes the FilterResult of filter")),
    Case("estimation", "a constant is estimated by the running mean", lambda: CONSTANT.filter(np.array([[3.0], [1.0], [2.0], [6.0]]), 1.0, x0=[0.0], P0=[1e6]), returns(running_mean)),
    Case("estimation", "missing samples are filtered through", lambda: EKF.filter(np.r_[[[np.nan]], Y[1:]], 0.05, x0=[0, 1], P0=[0.1, 0.1]).x[1:], returns(lambda x: np.abs(x - RUN.x[1:]).max() < 0.05)),
    # --- online steps
    Case("estimation", "update with 2 values for 1 output", lambda: EKF.update(EKF.start([0, 1], [1, 1]), [1.0, 2.0]), raises(ShapeError, r"^y must be 1 numbers")),
    Case("estimation", "predict over 0 s", lambda: EKF.predict(EKF.start([0, 1], [1, 1]), dt=0.0), raises(DataError, r"^dt must be a positive number of seconds")),
    Case("estimation", "predict with a NaN input", lambda: DRIVEN.predict(DRIVEN.start([0, 1], [1, 1]), [np.nan], 0.1), raises(DataError, r"^u must be finite")),
    Case("estimation", "start with a covariance of the wrong size", lambda: EKF.start([0, 1], np.eye(3)), raises(ShapeError, r"^P0 must be a number, 2 standard deviations")),
    Case("estimation", "one scalar update by hand", scalar_update, returns(bool)),
    # --- prediction-error fits
    Case("estimation", "fit without outputs", lambda: pem(outputs=None), raises(ParameterError, r"outputs is required")),
    Case("estimation", "fit on a record too short", lambda: pem(Y[:50]), raises(DataError, r"too short for a prediction-error fit \(at least 80")),
    Case("estimation", "fit with holdout 0.9", lambda: pem(holdout=0.9), raises(ParameterError, r"holdout must be a fraction in \[0.05, 0.5\]")),
    Case("estimation", "fit with a process covariance", lambda: pem(process_noise=np.eye(2)), raises(ShapeError, r"process_noise must be 2 standard deviations \(one per channel, NaN for those to fit\) for a prediction-error fit")),
    Case("estimation", "fit with an unknown disturbance", lambda: pem(disturbances=["x9"]), raises(UnknownNameError, r"disturbances\[0\] = 'x9' is not a state")),
    Case("estimation", "fit with u positional", lambda: pem_model().fit_prediction_error(Y, 0.05, np.zeros((100, 1))), raises(ParameterError, r"fit_prediction_error: arguments after t .* must be passed by name")),
    Case("estimation", "fit of a discrete-time model", lambda: dc.DiscrepancyModel(discrete_time=True).fit_prediction_error(Y, outputs=[0]), raises(ParameterError, r"fit_prediction_error fits continuous-time models")),
    Case("estimation", "kalman_filter of an unknown kind", lambda: pem_model().fit(np.c_[Y, Y], 0.05, u=np.zeros((100, 1))).kalman_filter("pf"), raises(ParameterError, r"kind must be 'ekf' or 'ukf'; got 'pf'")),
    Case("estimation", "kalman_filter without noise levels", lambda: pem_model().fit(np.c_[Y, Y], 0.05, u=np.zeros((100, 1))).kalman_filter(), raises(NotFittedError, r"kalman_filter needs the noise levels of fit_prediction_error")),
]


@params(CASES)
def test_case(case):
    check(case)
