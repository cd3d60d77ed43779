"""Scores of a fitted model on data."""
from __future__ import annotations

import numpy as np

from ...errors import DataError, MissingDependencyError, ParameterError, ShapeError, describe
from ...fitting.accumulate import not_finite
from ...resources import check_memory, n_bytes
from .checks import model_data

METRICS = ("r2", "rmse", "trajectory")


def score(model, x, t=None, u=None, x_dot=None, *, metric="r2", metric_kws=None):
    """See :meth:`DiscrepancyModel.score`."""
    if not callable(metric) and not (isinstance(metric, str) and metric in METRICS):
        raise ParameterError(f"metric must be one of {', '.join(METRICS)} or a callable "
                             f"metric(truth, prediction) -> float; got {metric!r}")
    if metric_kws and metric == "r2":   # PySINDy's default metric, with its options
        metric = _sklearn_r2()
    elif metric_kws and not callable(metric):
        raise ParameterError(f"metric={metric!r} takes no options; got {sorted(metric_kws)} "
                             "(options go to a callable metric)")
    trajectories = model_data(model, x, t, u, x_dot)
    if metric == "trajectory":
        if len(trajectories) != 1:
            raise ShapeError("metric='trajectory' scores one trajectory; got "
                             f"{len(trajectories)}")
        tr = trajectories[0]
        size = np.linalg.norm(tr.x)
        if size == 0:
            raise DataError("metric='trajectory' divides by the norm of x, which is 0 here; "
                            "use metric='rmse'")
        sim = model.simulate(tr.x[0], tr.t, u=tr.u)
        return float(np.linalg.norm(sim - tr.x) / size)
    truth, pred = [], []
    setup = model.setup_
    p = setup.n_features
    for tr in trajectories:  # derivatives (or, in the weak form, their integrals)
        z, y, signal = setup.rows(tr)
        check_memory(f"Θ of {len(z)} samples and {p} columns", n_bytes((len(z), p)),
                     "Score the data in pieces (a list of shorter trajectories)")
        theta = setup.transform(z)
        if not np.all(np.isfinite(theta)):
            raise not_finite(theta.T, z, 0, p, setup.names)
        truth.append(signal)
        pred.append(signal - y + theta @ model.coef_.T)
    truth, pred = np.vstack(truth), np.vstack(pred)
    if truth.size == 0:
        raise ShapeError("score needs at least one sample")
    if callable(metric):  # e.g. sklearn.metrics.mean_absolute_error, as PySINDy allows
        return _called(metric, truth, pred, metric_kws or {})
    if metric == "rmse":
        return float(np.sqrt(np.mean((truth - pred) ** 2)))
    ss_res = np.sum((truth - pred) ** 2, axis=0)
    ss_tot = np.sum((truth - truth.mean(axis=0)) ** 2, axis=0)
    # a constant derivative scores 1 when predicted exactly, else 0 (scikit-learn's r2_score)
    r2 = np.where(ss_tot > 0, 1 - ss_res / np.where(ss_tot > 0, ss_tot, 1.0),
                  np.where(ss_res == 0, 1.0, 0.0))
    return float(np.mean(r2))


def _called(metric, truth, pred, metric_kws):
    """``metric(truth, pred, **metric_kws)``: a finite number, or finite numbers (e.g. one
    per state with ``multioutput="raw_values"``)."""
    try:
        value = metric(truth, pred, **metric_kws)
    except Exception as e:
        raise ParameterError(f"metric raised {type(e).__name__}: {e}") from e
    try:
        number = np.nan if isinstance(value, (str, bytes, bool)) else \
            np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        number = np.nan
    if not np.all(np.isfinite(number)) or np.size(number) == 0:
        raise ParameterError(f"metric must return a finite number (or finite numbers); got "
                             f"{describe(value)}")
    return float(number) if np.ndim(number) == 0 else number


def _sklearn_r2():
    try:
        from sklearn.metrics import r2_score
    except ImportError:
        raise MissingDependencyError("score(..., **metric_kws) with metric='r2' passes the "
                                     "options to sklearn.metrics.r2_score; install it with "
                                     "pip install scikit-learn") from None
    return r2_score
