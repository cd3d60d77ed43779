"""Extended and unscented Kalman filters over any hybrid model, with an RTS smoother.

::

    from discrepancy.estimation import ExtendedKalmanFilter
    ekf = ExtendedKalmanFilter(model, outputs=["phi1", "phi2", "s"], process_noise=q_std,
                               measurement_noise=r_std, substeps=4, u_hold="zoh")
    run = ekf.filter(y, t, u=u, x0=x0, P0=P0)        # a FilterResult
    xs, Ps = ekf.smooth(run)                          # Rauch–Tung–Striebel
    state = ekf.start(x0, P0)                         # online, in a control loop:
    state = ekf.update(state, y_k)                    #   after each measurement
    state = ekf.predict(state, u_k, dt)               #   with the input held over dt

``model``: a fitted :class:`~discrepancy.DiscrepancyModel` (continuous or discrete time), a
callable prior ``f(x (m, n), u (m, r)) -> (m, n)`` or a list of sympy expressions (then
``state_names=`` and ``input_names=``). ``outputs`` as in ``fit_outputs``: states (names or
indices) or sympy expressions of them. Noise: ``process_noise`` is the intensity of white
noise on ``x'`` (a std per state in units per √second, or a covariance ``(n, n)`` per
second; per step for a discrete-time model); ``measurement_noise`` a std per output (or a
covariance ``(k, k)``), which must be positive. ``disturbances``: states (names or indices)
whose equations also get an unmeasured random-walk force ``d_<name>``, estimated as an extra
state (its process noise is the last entries of ``process_noise``; see
:mod:`~discrepancy.estimation.disturbances`).

Between samples the model is stepped by RK4 (``substeps`` per interval) with the input held
as ``u_hold`` says (as in ``fit_outputs`` and ``simulate(method="rk4")``); the online
``predict`` holds ``u_k`` over ``dt`` (what a controller's output does). Missing outputs are
NaN in ``y``: that sample updates with the others only.

With CasADi installed (``[control]``) and a model it can express, every step is one call of
a CasADi Function with exact Jacobians, and whole records run ``BLOCK`` samples per call;
otherwise steps run in numpy with Jacobians by central differences (see
:mod:`~discrepancy.estimation.backends`; ``backend=`` forces either).
"""
from __future__ import annotations

import numpy as np

from ..constraints import Integral, Interval, Real, validate_params
from ..errors import ConvergenceError, DataError, ShapeError
from ..hybrid.inputs import check_hold
from . import kalman_math as km
from .backends import NumpyOps
from .disturbances import with_disturbances
from .dynamics import check_state, dynamics_of
from .measurement import Measurement
from .noise import covariance, initial_covariance
from .records import FilterRecord, assemble_result, record_inputs
from .results import FilterResult, FilterState
from .smoother import rts_smooth


class KalmanFilter:
    """Shared by :class:`ExtendedKalmanFilter` and :class:`UnscentedKalmanFilter` (see
    the module's docstring for the arguments); not used directly."""

    _kind = "ekf"

    def __init__(self, model, *, outputs, process_noise, measurement_noise, substeps: int = 4,
                 u_hold: str = "zoh", state_names=None, input_names=None, discrete_time=None,
                 disturbances=None, backend: str = "auto"):
        validate_params(type(self).__name__, {"substeps": substeps},
                        {"substeps": [Interval(Integral, 1, 1000)]})
        self.substeps, self.u_hold = int(substeps), check_hold(u_hold)
        size = _size(process_noise)
        n_disturbed = 0 if disturbances is None else \
            (1 if isinstance(disturbances, (str, int)) else len(disturbances))
        self.dynamics = with_disturbances(dynamics_of(
            model, state_names=state_names, input_names=input_names,
            discrete_time=discrete_time, backend=backend,
            n_states=None if size is None else size - n_disturbed), disturbances)
        n = self.dynamics.n
        self.measurement = Measurement(outputs, list(self.dynamics.state_names))
        unit = "per step" if self.dynamics.discrete_time else "per second"
        self.Q = covariance("process_noise", process_noise, n, definite=False, unit=unit)
        self.R = covariance("measurement_noise", measurement_noise, self.measurement.k,
                            definite=True)
        self._numpy = NumpyOps(self.dynamics.rhs, self.measurement, self.dynamics.r)
        self._weights = self._sigma_weights()
        self._compiled = None
        if self.dynamics.casadi is not None:
            from .compiled import CompiledSteps
            self._compiled = CompiledSteps(self._kind, self.dynamics, self.measurement,
                                           self.Q, self.R, self.substeps, self._weights)

    def _sigma_weights(self):
        return None

    @property
    def backend(self) -> str:
        """``"casadi"`` or ``"numpy"`` (why: ``dynamics.why_numpy``)."""
        return "numpy" if self._compiled is None else "casadi"

    @property
    def state_names(self) -> list[str]:
        """Names of the ``n`` states, the order of the state vector ``x``."""
        return list(self.dynamics.state_names)

    @property
    def output_names(self) -> list[str]:
        """Names of the measured outputs, the order of a measurement ``y``."""
        return list(self.measurement.names)

    # ------------------------------------------------------------------ online
    def start(self, x0, P0) -> FilterState:
        """The belief before the first measurement: mean ``x0`` ``(n,)`` and covariance
        ``P0`` (a std per state or a covariance ``(n, n)``)."""
        n = self.dynamics.n
        return FilterState(check_state("x0", x0, n), initial_covariance(P0, n))

    def update(self, state: FilterState, y) -> FilterState:
        """The belief after measuring ``y`` ``(k,)`` (NaN for an output not measured now)."""
        y = _vector("y", y, self.measurement.k)
        w = np.isfinite(y).astype(float)
        y = np.where(w > 0, y, 0.0)
        if self._compiled is not None:
            n, k = self.dynamics.n, self.measurement.k
            out = self._compiled.update(np.concatenate([state.x, state.P.ravel(order="F"), y,
                                                        w]))
            x, P = out[:n], out[n:n + n * n].reshape(n, n, order="F")
            e, S = out[n + n * n:n + n * n + k], out[n + n * n + k:-1].reshape(k, k, order="F")
            nll = out[-1]
        else:
            x, P, e, S, nll = self._numpy_update(state.x, state.P, y, w)
        if not np.isfinite(nll):
            raise ConvergenceError(f"the filter's update failed (innovation covariance not "
                                   f"positive definite, or a state that is not finite: x = "
                                   f"{state.x})")
        return FilterState(x, P, e, S, state.log_likelihood - float(nll))

    def predict(self, state: FilterState, u=None, dt=None) -> FilterState:
        """The belief one interval ``dt`` later (s; ignored for a discrete-time model, one
        step of its map), the input ``u`` ``(r,)`` held over it."""
        r = self.dynamics.r
        if r:
            u = _vector("u", u, r)
            if not np.all(np.isfinite(u)):
                raise DataError(f"u must be finite; got {u}")
        elif u is not None:
            raise ShapeError("u was given but the model has no inputs")
        h = 1.0 if self.dynamics.discrete_time else _step(dt)
        width = 2 * self.substeps + 1
        if self._compiled is not None:
            n = self.dynamics.n
            stages = np.repeat(u, width) if r else np.zeros(0)
            out = self._compiled.predict(np.concatenate([state.x, state.P.ravel(order="F"),
                                                         stages, [h]]))
            x, P = out[:n], out[n:n + n * n].reshape(n, n, order="F")
        else:
            stages = np.repeat(u[None, :], width, 0) if r else None
            x, P, _ = self._numpy_predict(state.x, state.P, stages, h)
        if not np.all(np.isfinite(x)):
            raise ConvergenceError(f"the filter's prediction diverged from x = {state.x}")
        return FilterState(x, P, state.innovation, state.innovation_cov, state.log_likelihood)

    # --------------------------------------------------------------- records
    def filter(self, y, t=None, u=None, *, x0=None, P0=None) -> FilterResult:
        """Filter a whole record: ``y`` ``(m, k)`` (NaN where not measured), ``t`` a step or
        times ``(m,)`` (not needed for a discrete-time model), ``u`` ``(m, r)``.

        ``x0``, ``P0``: the belief before ``y[0]``; by default measured states start at
        ``y[0]`` and the others at 0, with a broad ``P0`` (the variance of ``R`` for
        measured states, 100 times the largest output variance for the others): give your
        own for unmeasured states of other units. Returns a :class:`FilterResult`; a list of
        records (``y``, ``t``, ``u`` lists) gives a list."""
        if isinstance(y, (list, tuple)):
            return [self.filter(yi, ti, ui, x0=x0, P0=P0) for yi, ti, ui in
                    zip(*record_inputs(y, t, u), strict=True)]
        record = FilterRecord(self, y, t, u)
        x0, P0 = record.initial_belief(self, x0, P0)
        if self._compiled is not None:
            out, carries = self._compiled.run(x0, P0, record.data())
        else:
            out, carries = self._numpy_run(record, x0, P0)
        return assemble_result((self.state_names, self.output_names), record, x0, P0, out,
                               carries)

    def smooth(self, result: FilterResult) -> tuple[np.ndarray, np.ndarray]:
        """Rauch–Tung–Striebel smoothed means ``(m, n)`` and covariances ``(m, n, n)`` of a
        :meth:`filter` result (each uses the whole record)."""
        return rts_smooth(result)

    # ------------------------------------------------------------------ numpy
    def _numpy_predict(self, x, P, stages, h):
        return km.ekf_predict(self._numpy, x, P, stages, h, self.Q, self.substeps,
                              self.dynamics.discrete_time)

    def _numpy_update(self, x, P, y, w):
        try:
            return km.ekf_update(self._numpy, x, P, y, w, self.R)
        except np.linalg.LinAlgError:
            return x, P, y, np.eye(len(y)), np.nan

    def _numpy_run(self, record, x0, P0):
        """The step outputs and predictions as the compiled run gives them."""
        n, k = self.dynamics.n, self.measurement.k
        m = record.m
        out = np.full((m, n + n * n + k + k * k + 1 + n * n), np.nan)
        carries = np.full((m, n + n * n), np.nan)
        x, P = x0, P0
        for i in range(m):
            x, P, e, S, nll = self._numpy_update(x, P, record.y[i], record.w[i])
            if i + 1 < m:
                stages = record.stages[i] if record.stages is not None else None
                x_next, P_next, C = self._numpy_predict(x, P, stages, record.h[i])
            else:
                x_next, P_next, C = x, P, np.zeros((n, n))
            out[i] = np.concatenate([x, P.ravel(order="F"), e, S.ravel(order="F"), [nll],
                                     C.ravel(order="F")])
            carries[i] = np.concatenate([x_next, P_next.ravel(order="F")])
            if not (np.isfinite(nll) and np.all(np.isfinite(x_next))):
                break
            x, P = x_next, P_next
        return out, carries


class ExtendedKalmanFilter(KalmanFilter):
    """Extended Kalman filter: the model and output map linearised at the current mean
    (exact Jacobians with CasADi). Cheapest; right when the model is close to linear over
    one sample interval and the state's uncertainty (see the module's docstring)."""

    _kind = "ekf"


class UnscentedKalmanFilter(KalmanFilter):
    """Unscented Kalman filter: ``2n + 1`` sigma points through the model and the output
    map (no Jacobians of ``f`` for the mean; the process noise is integrated along the mean
    as in the EKF, so the two agree exactly on linear models). Better than the EKF when
    the model bends over the state's uncertainty (large angles, saturations).

    ``alpha``, ``beta``, ``kappa``: the sigma-point spread and weights (defaults 1, 2, 0:
    points at ``x ± √n`` standard deviations, no negative mean weight)."""

    _kind = "ukf"

    def __init__(self, model, *, outputs, process_noise, measurement_noise, substeps: int = 4,
                 u_hold: str = "zoh", state_names=None, input_names=None, discrete_time=None,
                 disturbances=None, backend: str = "auto", alpha: float = 1.0,
                 beta: float = 2.0, kappa: float = 0.0):
        validate_params("UnscentedKalmanFilter", {"alpha": alpha, "beta": beta, "kappa": kappa},
                        {"alpha": [Interval(Real, 0, 10, closed="right")],
                         "beta": [Interval(Real, 0, 10)], "kappa": [Interval(Real, 0, 100)]})
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)
        super().__init__(model, outputs=outputs, process_noise=process_noise,
                         measurement_noise=measurement_noise, substeps=substeps, u_hold=u_hold,
                         state_names=state_names, input_names=input_names,
                         discrete_time=discrete_time, disturbances=disturbances,
                         backend=backend)

    def _sigma_weights(self):
        return km.unscented_weights(self.dynamics.n, self.alpha, self.beta, self.kappa)

    def _numpy_predict(self, x, P, stages, h):
        return km.ukf_predict(self._numpy, x, P, stages, h, self.Q, self.substeps,
                              self.dynamics.discrete_time, self._weights)

    def _numpy_update(self, x, P, y, w):
        try:
            return km.ukf_update(self._numpy, x, P, y, w, self.R, self._weights)
        except np.linalg.LinAlgError:
            return x, P, y, np.eye(len(y)), np.nan


def _size(value) -> int | None:
    """Leading size of a noise level (the number of states of a callable model), if any."""
    try:
        return np.shape(value)[0] if np.ndim(value) else None
    except ValueError:                      # ragged: the noise check names it later
        return None


def _vector(name, value, size) -> np.ndarray:
    """``(size,)`` floats, cheaply (the online hot path); NaN allowed (checked by callers)."""
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (size,) or np.any(np.isinf(arr)):
        from ..errors import describe
        raise ShapeError(f"{name} must be {size} numbers (finite, or NaN for a missing "
                         f"output); got {describe(value)}")
    return arr


def _step(dt) -> float:
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.integer, np.floating)) \
            or not np.isfinite(dt) or dt <= 0:
        raise DataError(f"dt must be a positive number of seconds (the interval to predict "
                        f"over); got {dt!r:.40}")
    return float(dt)
