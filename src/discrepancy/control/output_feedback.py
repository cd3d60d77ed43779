"""Output feedback: a state-feedback law driven by a Kalman filter's estimate.

When the sensors measure only some states (a cart-pendulum's encoders give the angles and
the cart's position, not the velocities), a filter on the (hybrid) model estimates the
whole state from the measurements and the inputs applied, and the state-feedback law (an
MPC, a TVLQR tracker) acts on the estimate. :class:`OutputFeedback` is such a law for
:func:`~.closed_loop.closed_loop` with ``outputs=``: at each sample it updates the filter
with the measurement, asks the inner law for the input, and, told the input the actuator
applied, predicts the filter over the hold interval.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import ParameterError, ShapeError, describe


class OutputFeedback:
    """``law(k, y) -> u``: ``inner(k, x̂_k)`` with ``x̂_k`` the filter's estimate after ``y_k``.

    Args:
        law: a state-feedback law ``law(k, x) -> u`` (an :class:`~.mpc.MPCLaw`, a
            :class:`~.tracking.Tracker`); told the applied input if it has
            ``notify_applied``.
        estimator: a filter with ``start(x0, P0)``, ``update(state, y)`` and
            ``predict(state, u, dt)`` (e.g. ``discrepancy.estimation.ExtendedKalmanFilter``
            on the hybrid model, with the measured states as ``outputs``).
        x0: ``(n,)`` the belief about the initial state; P0: its std per state or
            covariance.
        dt: the control period (s): how far the filter predicts after each input.

    Attributes:
        estimates: ``(k+1, n)`` filtered states the law acted on, one per sample so far;
        stds: their standard deviations (the filter's own uncertainty);
        cpu_times: CPU time (s) per sample of the filter's update and prediction and the
            inner law together (what the controller computes per sample).
    """

    def __init__(self, law, estimator, *, x0, P0, dt: float):
        for name in ("start", "update", "predict"):
            if not callable(getattr(estimator, name, None)):
                raise ParameterError(f"estimator must have start, update and predict (a "
                                     f"Kalman filter); got {describe(estimator)}")
        if not callable(law):
            raise ParameterError(f"law must be callable law(k, x) -> u; got {describe(law)}")
        if not (np.isfinite(dt) and dt > 0):
            raise ParameterError(f"dt must be a positive control period (s); got {dt!r}")
        self.law, self.estimator, self.dt = law, estimator, float(dt)
        self.x0, self.P0 = np.asarray(x0, dtype=float).ravel(), P0
        self.reset()

    def reset(self) -> None:
        """Restart the filter from ``x0``, ``P0`` and the inner law (a new run)."""
        self._state = self.estimator.start(self.x0, self.P0)
        self._updated = False
        self._estimates, self._stds, self.cpu_times, self._cpu = [], [], [], 0.0
        if hasattr(self.law, "reset"):
            self.law.reset()

    def __call__(self, k: int, y) -> np.ndarray:
        if self._updated:
            raise ShapeError("OutputFeedback was called twice without notify_applied: run it "
                             "in closed_loop (which reports the applied input) or call "
                             "notify_applied(u) after each input")
        start = time.process_time()
        self._state = self.estimator.update(self._state, np.asarray(y, dtype=float).ravel())
        self._updated = True
        self._estimates.append(self._state.x.copy())
        self._stds.append(np.sqrt(np.clip(np.diag(self._state.P), 0, None)))
        u = self.law(k, self._state.x)
        self._cpu = time.process_time() - start
        return u

    def notify_applied(self, u) -> None:
        """The input the actuator applied: the inner law is told, the filter predicts."""
        start = time.process_time()
        u = np.asarray(u, dtype=float).ravel()
        if hasattr(self.law, "notify_applied"):
            self.law.notify_applied(u)
        self._state = self.estimator.predict(self._state, u, self.dt)
        self._updated = False
        self.cpu_times.append(self._cpu + time.process_time() - start)

    @property
    def estimates(self) -> np.ndarray:
        """``(k, n)``: the filtered states the law acted on, one row per sample so far (after
        each measurement update), in the units of the states."""
        return np.array(self._estimates)

    @property
    def stds(self) -> np.ndarray:
        """``(k, n)``: the filter's standard deviation of each estimate in :attr:`estimates`
        (square roots of the covariance's diagonal), same units."""
        return np.array(self._stds)

    def estimation_errors(self, run) -> dict:
        """RMS and largest error of the estimates against the run's true states at the
        control samples, per state index: ``{"rms": (n,), "max": (n,)}``."""
        est = self.estimates
        true = np.asarray(run.x)[:len(est)]
        if est.shape != true.shape:
            raise ShapeError(f"the run has states {true.shape} but the filter estimated "
                             f"{est.shape}: pass the run this law was used in")
        err = est - true
        return {"rms": np.sqrt(np.mean(err ** 2, axis=0)), "max": np.max(np.abs(err), axis=0)}
