"""Scores of a fitted model on data."""
from __future__ import annotations

import numpy as np

from ..data.trajectory import as_trajectories
from ..errors import ParameterError, ShapeError

METRICS = ("r2", "rmse", "trajectory")


def score(model, x, t=None, u=None, x_dot=None, *, metric="r2") -> float:
    """See :meth:`DiscrepancyModel.score`."""
    if not callable(metric) and metric not in METRICS:
        raise ParameterError(f"metric must be one of {', '.join(METRICS)} or a callable "
                             f"metric(truth, prediction) -> float; got {metric!r}")
    trajectories = as_trajectories(x, t, u, x_dot)
    if metric == "trajectory":
        if len(trajectories) != 1:
            raise ShapeError("metric='trajectory' scores one trajectory; got "
                             f"{len(trajectories)}")
        tr = trajectories[0]
        sim = model.simulate(tr.x[0], tr.t, u=tr.u)
        return float(np.linalg.norm(sim - tr.x) / np.linalg.norm(tr.x))
    truth, pred = [], []
    setup = model.setup_
    for tr in trajectories:  # derivatives (or, in the weak form, their integrals)
        z, y, signal = setup.rows(tr)
        truth.append(signal)
        pred.append(signal - y + setup.transform(z) @ model.coef_.T)
    truth, pred = np.vstack(truth), np.vstack(pred)
    if truth.size == 0:
        raise ShapeError("score needs at least one sample")
    if callable(metric):  # e.g. sklearn.metrics.mean_absolute_error, as PySINDy allows
        value = np.asarray(metric(truth, pred), dtype=float)
        if value.ndim != 0 or not np.isfinite(value):
            raise ParameterError(f"metric must return one finite number; got {value!r}")
        return float(value)
    if metric == "rmse":
        return float(np.sqrt(np.mean((truth - pred) ** 2)))
    ss_res = np.sum((truth - pred) ** 2, axis=0)
    ss_tot = np.sum((truth - truth.mean(axis=0)) ** 2, axis=0)
    return float(np.mean(1 - ss_res / np.where(ss_tot > 0, ss_tot, 1.0)))
