"""``DiscrepancyModel.fit_prediction_error``: from data to a fitted model and its noise
levels (set-up, noise of the prior alone, coefficient scales, the path of supports, the
choice, the final refit). The pieces are in :mod:`~discrepancy.estimation.prediction_error`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..data.validation import as_float_array
from ..errors import ParameterError, ShapeError
from .disturbances import disturbance_names, disturbed_equations
from .measurement import Measurement
from .noise import covariance
from .prediction_error import (
    RIDGE,
    PredictionErrorProblem,
    check_records,
    measurement_noise_guess,
    record_spec,
    rows_of,
)
from .records import FilterRecord, record_inputs
from .smoother import rts_smooth
from .support_path import SupportScore, choose, drop_least

#: factors of the outputs' spread tried as the first process-noise level
NOISE_SCAN = 10.0 ** np.arange(-3, 2)


@dataclass
class PredictionErrorFit:
    """What :func:`fit_prediction_error` found (the model stores it as
    ``prediction_error_``): coefficients ``(n, p)``; the process noise per state and
    disturbance (std per √s) and the measurement noise per output (std), by name; the
    names of the disturbance states; the scored path and the chosen support (``None``
    with a numeric threshold); the mean negative log-likelihood per sample of the final
    fit; the smoothed initial states; the filter settings."""

    coef: np.ndarray
    process_noise: dict
    measurement_noise: dict
    disturbances: list
    path: list = field(default_factory=list)
    chosen: SupportScore | None = None
    nll_per_sample: float = np.nan
    x0: list = field(default_factory=list)
    outputs: list = field(default_factory=list)
    substeps: int = 4
    u_hold: str = "linear"


def fit_prediction_error(model, y, t, u, *, outputs, disturbances, process_noise,
                         measurement_noise, x0, u_hold, substeps, max_terms, holdout,
                         tolerance, progress):
    """See :meth:`DiscrepancyModel.fit_prediction_error`; returns ``(setup, fit)``."""
    _check_path_options(max_terms, holdout, tolerance)
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or \
            not 1 <= substeps <= 1000:
        raise ParameterError(f"substeps must be an integer in [1, 1000] (RK4 steps per sample "
                             f"interval); got {substeps!r}")
    if model.discrete_time:
        raise ParameterError("fit_prediction_error fits continuous-time models; for a map, "
                             "fit the successors (fit(x, x_dot=x_next)) and filter with "
                             "ExtendedKalmanFilter(model, ...)")
    ys, ts, us = record_inputs(y, t, u)
    r = 0 if us[0] is None else (1 if np.ndim(us[0]) == 1 else int(np.shape(us[0])[1]))
    setup = model.make_setup(_n_states(model, x0), r)
    measurement = Measurement(outputs, list(setup.state_names))
    equations = disturbed_equations(disturbances, list(setup.state_names))
    problem = _problem(setup, measurement, equations, (ys, ts, us), process_noise,
                       measurement_noise, x0, u_hold, substeps)
    allowed = _allowed_terms(setup)
    train, test = rows_of(problem.records, holdout)
    everything, _ = rows_of(problem.records, None)
    none = np.zeros_like(allowed)
    noise = _prior_noise(problem, train)
    problem.set_coef_scale([rts_smooth(problem.filtered(none, 0 * allowed, noise, i))[0]
                            for i in range(len(problem.records))])
    threshold = getattr(setup.optimizer, "threshold", "auto")
    path, chosen = [], None
    if threshold == "auto":
        path = _path(problem, allowed, noise, train, test, max_terms, progress)
        chosen = choose(path, tolerance)
        support, coef, noise = chosen.support, chosen.coef, chosen.noise
    else:
        support, coef, noise = _thresholded(problem, allowed, noise, everything,
                                            float(threshold), max_terms)
    coef, noise, value = problem.solve(support, coef, noise, everything, 0.0)
    coef[~support] = 0.0
    return setup, _result(problem, support, coef, noise, value, path, chosen, u_hold,
                          substeps)


def _check_path_options(max_terms, holdout, tolerance):
    def number(value):
        return isinstance(value, (int, float, np.integer, np.floating)) and \
            not isinstance(value, bool)

    if max_terms is not None and not (number(max_terms) and int(max_terms) == max_terms >= 1):
        raise ParameterError(f"max_terms must be a positive integer or None; got {max_terms!r}")
    if not (number(holdout) and 0.05 <= holdout <= 0.5):
        raise ParameterError(f"holdout must be a fraction in [0.05, 0.5]; got {holdout!r}")
    if tolerance is not None and not (number(tolerance) and 0 <= tolerance <= 1):
        raise ParameterError(f"tolerance must be None (one standard error) or a relative "
                             f"excess in [0, 1]; got {tolerance!r}")


def _n_states(model, x0) -> int:
    """The model's number of states: its names, its symbolic prior or the given ``x0``."""
    names, prior = model.state_names, model.prior
    if names is not None:
        return len([names] if isinstance(names, str) else names)
    if isinstance(prior, (list, tuple)):
        return len(prior)
    if x0 is None:
        raise ParameterError("the number of states is unknown: give state_names, a prior as "
                             "a list of sympy expressions, or x0")
    return int(np.shape(x0)[-1])


def _allowed_terms(setup) -> np.ndarray:
    """``(n, p)`` bool: the terms the constraints allow in each equation (all without)."""
    constraints = getattr(setup.optimizer, "constraints", None)
    if constraints is not None and constraints.has_linear:
        raise ParameterError("prediction-error fits honour term masks (exact_equations, "
                             "only) but not linear equalities or inequalities")
    full = np.ones((setup.n_states, setup.n_features), bool)
    return full if constraints is None else constraints.allowed & full


def _problem(setup, measurement, equations, data, process_noise, measurement_noise,
             x0, u_hold, substeps) -> PredictionErrorProblem:
    from types import SimpleNamespace

    from ..hybrid.inputs import check_hold

    names = [*setup.state_names, *disturbance_names(list(setup.state_names), equations)]
    N, k = len(names), measurement.k
    dynamics = SimpleNamespace(n=N, r=setup.n_inputs, input_names=list(setup.input_names),
                               discrete_time=False, state_names=names)
    spec = record_spec(dynamics, measurement, substeps, check_hold(u_hold), np.ones(k))
    records = [FilterRecord(spec, *record) for record in zip(*data, strict=True)]
    check_records(records)
    r0, r_free = _levels("measurement_noise", measurement_noise, k, definite=True)
    r0 = np.where(r_free, measurement_noise_guess(records), r0)
    spec.R = np.diag(r0 ** 2)
    q0, q_free = _levels("process_noise", process_noise, N, definite=False)
    problem = PredictionErrorProblem(setup, measurement, equations, records, spec, q_free,
                                     r_free, q0, r0)
    if x0 is not None:
        _set_initial_states(problem, x0, setup.n_states)
    problem.names = names
    return problem


def _levels(name, value, size, *, definite) -> tuple[np.ndarray, np.ndarray]:
    """``(stds (size,), fitted (size,) bool)`` from ``None`` (fit all) or stds, NaN for
    those to fit (a fit takes no correlations)."""
    if value is None:
        return np.ones(size), np.ones(size, bool)
    arr = as_float_array(name, value)
    if arr.ndim == 2:
        raise ShapeError(f"{name} must be {size} standard deviations (one per channel, NaN "
                         "for those to fit) for a prediction-error fit; correlated noise is "
                         "not fitted")
    arr = np.broadcast_to(arr, (size,)) if arr.ndim == 0 else arr
    if arr.shape != (size,):
        covariance(name, arr, size, definite=definite)           # raises, naming the sizes
    fitted = np.isnan(arr)
    fixed = covariance(name, np.where(fitted, 1.0, arr), size, definite=definite)
    return np.sqrt(np.diag(fixed)), fitted


def _set_initial_states(problem, x0, n):
    x0s = np.asarray(x0, dtype=float).reshape(-1, n)
    if len(x0s) not in (1, len(problem.records)) or not np.all(np.isfinite(x0s)):
        raise ShapeError(f"x0 must be {n} finite numbers, or one such row per record; got "
                         f"shape {np.shape(x0)}")
    for i, (mean, P0) in enumerate(problem.beliefs):
        mean = mean.copy()
        mean[:n] = x0s[min(i, len(x0s) - 1)]
        problem.beliefs[i] = (mean, P0)


def _prior_noise(problem, rows):
    """Noise levels of the prior alone: the free process-noise levels tried at a few
    multiples of the outputs' spread, then all free levels fitted."""
    none = np.zeros((problem.n, problem.p), bool)
    zero = np.zeros((problem.n, problem.p))
    spread = max(float(np.std(np.concatenate([rec.y for rec in problem.records]))), 1e-12)
    best = None
    for factor in NOISE_SCAN:
        noise = problem.noise0.copy()
        noise[:problem.N][problem.q_free] = factor * spread
        value = problem.score(none, zero, noise, rows)[0]
        if best is None or value < best[0]:
            best = (value, noise)
    problem.noise0 = best[1]
    return problem.solve(none, zero, best[1], rows, 0.0)[1]


def _path(problem, allowed, noise, train, test, max_terms, progress) -> list[SupportScore]:
    """Supports from every allowed term down to none, each fitted on ``train`` (warm from
    the last) and scored on ``test``."""
    from tqdm.auto import tqdm

    support, coef = allowed.copy(), np.zeros((problem.n, problem.p))
    coef, noise, value = problem.solve(support, coef, noise, train, RIDGE)
    if max_terms is not None and support.sum() > max_terms:
        order = np.argsort(-problem.importance(coef), axis=None)[:max_terms]
        support = np.zeros_like(support)
        support.flat[order] = True
        coef, noise, value = problem.solve(support, coef * support, noise, train, RIDGE)
    bar = tqdm(total=int(support.sum()) + 1, desc="prediction-error path", unit="support",
               disable=None if progress is None else not progress)
    path = []
    while True:
        path.append(SupportScore(support.copy(), coef.copy(), noise.copy(),
                                 *problem.forecast_score(support, coef, noise, test),
                                 problem.score(support, coef, noise, test)[0], value))
        bar.update()
        if not support.any():
            break
        support = drop_least(support, problem.importance(coef))
        coef, noise, value = problem.solve(support, coef * support, noise, train, RIDGE)
    bar.close()
    return path


def _thresholded(problem, allowed, noise, rows, threshold, max_terms):
    """Fit every allowed term, drop those below ``threshold``, refit until none drops."""
    support, coef = allowed.copy(), np.zeros((problem.n, problem.p))
    for _ in range(int(allowed.sum()) + 1):
        coef, noise, _ = problem.solve(support, coef, noise, rows, 0.0)
        keep = support & (np.abs(coef) >= threshold)
        if max_terms is not None and keep.sum() > max_terms:
            order = np.argsort(-np.where(keep, problem.importance(coef), -1), axis=None)
            keep = np.zeros_like(keep)
            keep.flat[order[:max_terms]] = True
        if (keep == support).all():
            break
        support, coef = keep, coef * keep
    return support, coef, noise


def _result(problem, support, coef, noise, value, path, chosen, u_hold, substeps):
    q, r = problem.split(noise)
    starts = [rts_smooth(problem.filtered(support, coef, noise, i))[0][0, :problem.n]
              for i in range(len(problem.records))]
    if not np.isfinite(value):
        raise ParameterError("the prediction-error fit failed: the filter does not run "
                             "with the fitted model on these data")
    return PredictionErrorFit(
        coef, dict(zip(problem.names, q.tolist(), strict=True)),
        dict(zip(problem.measurement.names, r.tolist(), strict=True)),
        [problem.names[i] for i in problem.equations], path, chosen, value, starts,
        problem.measurement.names,
        substeps, u_hold)
