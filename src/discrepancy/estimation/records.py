"""One record for a filter: checked outputs, times and inputs, the inputs at the RK4 stage
times, and the filter's outputs turned into a :class:`FilterResult`."""
from __future__ import annotations

import numpy as np

from ..data.trajectory import one_per_trajectory
from ..data.validation import as_float_array, check_array, check_times
from ..errors import ConvergenceError, DataError, ShapeError
from ..hybrid.casadi_form import stage_columns
from ..hybrid.inputs import stage_inputs
from ..resources import check_memory, n_bytes
from .dynamics import check_state
from .noise import initial_covariance
from .results import FilterResult

#: default prior variance of unmeasured states, relative to the largest output variance
BROAD = 100.0


def record_inputs(y, t, u) -> tuple[list, list, list]:
    """``(ys, ts, us)`` lists for one record or a list of records (a step ``t`` and a
    missing ``u`` are shared)."""
    if not isinstance(y, (list, tuple)):
        return [y], [t], [u]
    if not y:
        raise ShapeError("y must hold at least one record; got an empty list")
    k = len(y)
    ts = one_per_trajectory("t", t, k,
                            broadcast=not isinstance(t, (list, tuple)) and np.ndim(t) == 0)
    return list(y), ts, one_per_trajectory("u", u, k, broadcast=u is None)


class FilterRecord:
    """``y`` ``(m, k)`` with its mask ``w``, times, step lengths ``h`` ``(m - 1,)``, inputs
    ``u`` and their values at the stage times ``(m - 1, 2S + 1, r)`` (``None`` without
    inputs). ``kalman``: a filter, or anything with its ``dynamics``, ``measurement``,
    ``substeps``, ``u_hold`` and ``R`` (a prediction-error fit's settings)."""

    def __init__(self, kalman, y, t, u):
        dyn, k = kalman.dynamics, kalman.measurement.k
        y = as_float_array("y", y)
        if y.ndim == 1 and k == 1:
            y = y[:, None]
        if y.ndim != 2 or y.shape[1] != k or y.shape[0] < 1:
            raise ShapeError(f"y must be ({'m'}, {k}): one column per output "
                             f"{kalman.measurement.names}; got shape {y.shape}")
        if np.any(np.isinf(y)):
            raise DataError("y must be finite or NaN (NaN marks an output not measured at "
                            f"that sample); found inf at row {int(np.argwhere(np.isinf(y))[0][0])}")
        self.w = np.isfinite(y).astype(float)
        if not self.w.any():
            raise DataError("y holds no measurement (every value is NaN)")
        self.y, self.m = np.where(self.w > 0, y, 0.0), y.shape[0]
        n = dyn.n
        check_memory(f"the filter's covariances ({self.m} samples x {n} x {n} states)",
                     4 * n_bytes((self.m, n, n)), "Filter the record in pieces, each "
                     "starting from the last state of the one before (result.state())")
        if dyn.discrete_time:
            self.t = np.arange(self.m, dtype=float) if t is None else check_times("t", t, self.m)
            self.h = np.ones(self.m - 1)
        else:
            if t is None:
                raise DataError("t is required: a time step or the times of the samples (s)")
            self.t = check_times("t", t, self.m)
            self.h = np.diff(self.t)
        self.stages = self._stages(kalman, u)
        self.substeps, self.r, self.k = kalman.substeps, dyn.r, k

    def _stages(self, kalman, u):
        r = kalman.dynamics.r
        self.u = None
        if not r:
            if u is not None:
                raise ShapeError("u was given but the model has no inputs")
            return None
        if u is None:
            raise ShapeError(f"u is required: the model has {r} inputs "
                             f"{list(kalman.dynamics.input_names)}")
        u = self.u = check_array("u", u, n_rows=self.m, n_cols=r, allow_1d=True)
        if self.m < 2:
            return np.zeros((0, 2 * kalman.substeps + 1, r))
        return stage_inputs(u, self.t, r, kalman.substeps, hold=kalman.u_hold)

    def data(self) -> np.ndarray:
        """Rows ``[y; w; U; h]`` per sample (the last one predicts over ``h = 0``)."""
        width = self.r * (2 * self.substeps + 1)
        stages = np.zeros((self.m, width))
        if self.r and self.m > 1:
            stages[:-1] = stage_columns(self.stages).T
        h = np.zeros((self.m, 1))
        h[:-1, 0] = self.h
        return np.hstack([self.y, self.w, stages, h])

    def initial_belief(self, kalman, x0, P0):
        """``(x0, P0)`` given or by default (see ``KalmanFilter.filter``)."""
        n, meas = kalman.dynamics.n, kalman.measurement
        if x0 is None:
            x0 = np.zeros(n)
            first = np.argmax(self.w > 0, axis=0)
            if meas.selected is not None:
                x0[meas.selected] = self.y[first, np.arange(meas.k)]
        x0 = check_state("x0", x0, n)
        if P0 is None:
            spread = float(np.max([np.var(self.y[self.w[:, j] > 0, j])
                                   for j in range(meas.k)] or [1.0])) or 1.0
            variances = np.full(n, BROAD * spread)
            if meas.selected is not None:
                variances[meas.selected] = np.diag(kalman.R)
            return x0, np.diag(variances)
        return x0, initial_covariance(P0, n)


def assemble_result(names, record, x0, P0, out, carries) -> FilterResult:
    """The :class:`FilterResult` of the flat step outputs ``(m, out)`` and the predictions
    that followed each step ``(m, n + n²)``; ``names``: ``(state names, output names)``;
    ``record``: has ``t`` and the mask ``w``. A filter that failed (non-finite values)
    raises ConvergenceError naming the sample."""
    n, k = len(names[0]), len(names[1])
    bad = ~np.all(np.isfinite(out[:, :n + n * n + k + k * k + 1]), axis=1)
    bad[:-1] |= ~np.all(np.isfinite(carries[:-1]), axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise ConvergenceError(
            f"the filter failed at sample {i} (t = {record.t[i]:.6g}): the state or its "
            "covariance is not finite, or the innovation covariance is not positive definite "
            "(the model diverges there, or the noise levels do not fit the data)")
    cut = np.cumsum([n, n * n, k, k * k, 1])
    x, P, e, S, nll, C = np.split(out, cut, axis=1)
    x_pred = np.vstack([x0, carries[:-1, :n]])
    P_pred = np.concatenate([P0[None], _matrices(carries[:-1, n:], n)])
    return FilterResult(record.t, x, _matrices(P, n), x_pred, P_pred, e, _matrices(S, k),
                        float(-nll.sum()), _matrices(C, n)[:-1], record.w > 0,
                        list(names[0]), list(names[1]), -nll[:, 0])


def _matrices(flat: np.ndarray, n: int) -> np.ndarray:
    """Rows of column-major ``vec`` s ``(m, n²)`` as matrices ``(m, n, n)``."""
    return flat.reshape(len(flat), n, n).transpose(0, 2, 1)
