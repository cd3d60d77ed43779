"""``DiscrepancyModel.fit_outputs``, ``refine`` and ``estimate_initial_state``: the
output-error fits from data to a fitted model (set-up, initial states from several starts,
the path of supports with warm starts, the choice, the final refit)."""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError, ShapeError
from .initial_states import best_start, candidates, warn_if_poor
from .output_error import NEGLIGIBLE, RIDGE, OutputErrorFit
from .output_records import (
    check_identifiable,
    check_options,
    given_states,
    n_states_of,
    records_of,
    split_rows,
)
from .output_records import x0_bounds as bounds_of
from .outputs import OutputMap
from .shooting import ShootingModel

#: simulations allowed per support on the path (the final refit may use more)
PATH_EVALUATIONS = 200
#: passes over the data a fit expects (to decide whether compiling pays)
PASSES = {"fit": 60, "refine": 20, "initial state": 40}
#: samples from which the segments are run on two threads by default (``n_jobs=None``)
THREADED_SAMPLES = 20_000


@dataclass
class SupportScore:
    """One support on the path: its terms ``(n, p)`` bool, coefficients fitted on the
    training part, the mean squared scaled forecast error on the held-out part and the
    standard error of that mean (and the initial states of that fit)."""

    support: np.ndarray
    coef: np.ndarray
    heldout_mse: float
    heldout_se: float
    x0s: np.ndarray | None = None

    @property
    def n_terms(self) -> int:
        """Number of terms in the support."""
        return int(self.support.sum())

    @property
    def heldout_error(self) -> float:
        """RMS scaled forecast error on the held-out part."""
        return float(np.sqrt(self.heldout_mse))


def prepare(setup, records, *, outputs, x0, x0_bounds, substeps, allowed, structure,
            options, passes):
    """The fit's pieces: ``(fit, given x0s or None, all rows of each record)``.
    ``allowed``: the coefficients that may be fitted; ``structure``: the terms that may
    carry a state's influence (for the identifiability check)."""
    r = 0 if records[0].u is None else records[0].u.shape[1]
    if r != setup.n_inputs:
        raise ShapeError(f"u has {r} input columns; the model has {setup.n_inputs}")
    out_map = OutputMap(outputs, setup.state_names)
    if records[0].y.shape[1] != out_map.k:
        raise ShapeError(f"y has {records[0].y.shape[1]} columns but outputs names "
                         f"{out_map.k} measured quantities {out_map.names}")
    given = None if x0 is None else given_states(x0, len(records), setup.n_states)
    x0s = given if given is not None else \
        np.array([out_map.initial_guess(rec.y[0]) for rec in records])
    points = (x0s, None if not r else np.repeat(records[0].u[:1], len(x0s), axis=0))
    samples = sum(rec.m for rec in records)
    n_jobs = options.get("n_jobs")
    if n_jobs is None:
        n_jobs = min(2, os.cpu_count() or 1) if samples >= THREADED_SAMPLES else 1
    shooting = ShootingModel(setup, substeps, check_points=points, jit=options.get("jit", "auto"),
                             work=samples * passes, n_jobs=n_jobs)
    fit = OutputErrorFit(setup, records, out_map, shooting, allowed,
                         segment_length=options.get("segment_length", "auto"))
    fit.bounds = bounds_of(x0_bounds, setup.n_states)
    check_identifiable(fit, structure)
    return fit, given, [np.ones(rec.m, bool) for rec in records]


def fit_outputs(model, y, t, u, *, outputs, x0, x0_bounds, u_hold, substeps, max_terms,
                holdout, tolerance, progress, **options):
    """See :meth:`DiscrepancyModel.fit_outputs`."""
    check_options(max_terms=max_terms, holdout=holdout, tolerance=tolerance, **options)
    n = n_states_of(model, x0)
    records, r = records_of(y, t, u, substeps, u_hold)
    setup = model.make_setup(n, r)
    allowed = _allowed(setup)
    fit, given, everything = prepare(setup, records, outputs=outputs, x0=x0,
                                     x0_bounds=x0_bounds, substeps=substeps, allowed=allowed,
                                     structure=allowed, options=options,
                                     passes=PASSES["fit"])
    x0s, _, _ = best_start(fit, fit.fixed, everything, candidates(fit, fit.fixed, given=given))
    fit.set_coef_scale(x0s)
    threshold = getattr(setup.optimizer, "threshold", "auto")
    if threshold == "auto":
        path, chosen = _path(fit, x0s, max_terms, holdout, tolerance, progress)
        support, coef, x0s = chosen.support, chosen.coef, chosen.x0s
    else:
        (support, coef, x0s), path = _thresholded(fit, x0s, float(threshold), max_terms,
                                                  everything), []
    final = fit.solve(support, coef * support, x0s, everything, 0.0)
    coef, x0s = final.coef, final.x0s
    coef[~support] = 0.0
    error = warn_if_not_converged(fit, coef, x0s, everything)
    fit.covariance = fit.coefficient_covariance(support, coef, x0s, everything)
    return setup, coef, x0s, fit, path, error


def _allowed(setup) -> np.ndarray:
    """Terms each equation may use: the model's constraints (masks only), else all."""
    constraints = getattr(setup.optimizer, "constraints", None)
    if constraints is None:
        return np.ones((setup.n_states, setup.n_features), bool)
    if constraints.has_linear:
        raise ParameterError("output-error fits honour term masks (exact_equations, only) "
                             "but not linear equalities or inequalities")
    return constraints.allowed.copy()


def _first_support(fit, start, rows, max_terms):
    """The full allowed library fitted (with a small ridge), cut to ``max_terms``."""
    zero = np.zeros((fit.n, fit.p))
    solution = fit.solve(fit.allowed, zero, start.x0s, rows, RIDGE, starts="measured")
    support = fit.allowed.copy()
    if max_terms is not None and support.sum() > max_terms:
        order = np.argsort(-fit.importance(solution.coef))
        keep = np.zeros(fit.n * fit.p, bool)
        keep[order[:max_terms]] = True
        support &= keep.reshape(support.shape)
        solution = fit.solve(support, solution.coef * support, solution.x0s, rows, RIDGE,
                             starts=solution.starts)
    return support, solution


def _drop_least(fit, support, coef) -> np.ndarray:
    """The support without its least important term (and any negligible ones)."""
    size = np.where(support.ravel(), fit.importance(coef), np.inf)
    active = np.isfinite(size)
    drop = size <= NEGLIGIBLE * size[active].max()
    drop[np.argmin(size)] = True
    return support & ~drop.reshape(support.shape)


def _path(fit, x0s, max_terms, holdout, tolerance, progress):
    """Supports from the full library down to none, fitted on the training part of every
    record and scored on the held-out rest (each from the last: coefficients compensated
    for the dropped term, and the segment states); the choice by :func:`choose`."""
    from tqdm.auto import tqdm

    train, test = split_rows(fit.records, holdout)
    zero = np.zeros((fit.n, fit.p))
    prior = fit.solve(zero.astype(bool), zero, x0s, train, 0.0)
    support, solution = _first_support(fit, prior, train, max_terms)
    path = []
    bar = tqdm(total=int(support.sum()) + 1, desc="output-error path", unit="support",
               disable=None if progress is None else not progress)
    while True:
        path.append(SupportScore(support.copy(), solution.coef.copy(),
                                 *fit.squared_errors(solution.coef, solution.x0s, test),
                                 solution.x0s.copy()))
        bar.update()
        if not support.any():
            break
        smaller = _drop_least(fit, support, solution.coef)
        start = fit.compensated(solution.coef, support & ~smaller, solution.x0s)
        support = smaller
        solution = fit.solve(support, start, solution.x0s, train, RIDGE,
                             max_evaluations=PATH_EVALUATIONS, starts=solution.starts)
        if not solution.cost <= prior.cost:   # lost on the way: start again from the prior
            solution = fit.solve(support, zero, prior.x0s, train, RIDGE,
                                 max_evaluations=PATH_EVALUATIONS, starts=prior.starts)
    bar.close()
    return path, choose(path, tolerance)


def choose(path, tolerance):
    """The sparsest support whose held-out error is within one standard error of the best
    (``tolerance=None``), or within ``tolerance`` (relative, of the RMS) of it."""
    best = min(path, key=lambda s: s.heldout_mse)
    if tolerance is None:
        bar = best.heldout_mse + best.heldout_se
        return min((s for s in path if s.heldout_mse <= bar), key=lambda s: s.n_terms)
    bar = (1 + tolerance) * best.heldout_error
    return min((s for s in path if s.heldout_error <= bar), key=lambda s: s.n_terms)


def _thresholded(fit, x0s, threshold, max_terms, rows):
    """Sequential thresholding on the raw coefficients: refit, drop ``|ξ| < threshold``."""
    zero = np.zeros((fit.n, fit.p))
    prior = fit.solve(zero.astype(bool), zero, x0s, rows, 0.0)
    support, solution = _first_support(fit, prior, rows, max_terms)
    for _ in range(support.size):
        keep = support & (np.abs(solution.coef) >= threshold)
        if np.array_equal(keep, support):
            break
        support = keep
        solution = fit.solve(support, solution.coef * support, solution.x0s, rows, RIDGE,
                             starts=solution.starts)
    return support, solution.coef, solution.x0s


def refit_outputs(model, y, t, u, *, outputs, x0, x0_bounds, u_hold, substeps, coefficients,
                  **options):
    """Output error of a fitted model on new data with its support kept: the nonzero
    coefficients refitted (``coefficients=True``) or all held (only initial states, from
    several starts: :mod:`~discrepancy.models.initial_states`). Returns
    ``(coef, x0s, fit)``."""
    check_options(**options)
    records, _ = records_of(y, t, u, substeps, u_hold)
    support = (model.coef_ != 0) if coefficients else np.zeros_like(model.coef_, bool)
    fit, given, everything = prepare(
        model.setup_, records, outputs=outputs, x0=x0, x0_bounds=x0_bounds,
        substeps=substeps, allowed=support, structure=_allowed(model.setup_) | support,
        options=options, passes=PASSES["refine" if coefficients else "initial state"])
    fit.fixed = model.coef_.copy()
    starts = candidates(fit, model.coef_, given=given, previous=_previous(model, len(records)))
    x0s, labels, rms = best_start(fit, model.coef_, everything, starts)
    if not coefficients:
        warn_if_poor(rms, labels, _spread(model, fit), len(starts))
        return model.coef_.copy(), x0s, fit
    fit.set_coef_scale(x0s)
    solution = fit.solve(support, model.coef_, x0s, everything, 0.0)
    fit.covariance = fit.coefficient_covariance(support, solution.coef, solution.x0s,
                                                everything)
    return solution.coef, solution.x0s, fit


def _previous(model, n_records):
    """The model's own initial-state estimate as ``(records, n)``, if it has a usable one."""
    x0 = getattr(model, "x0_", None)
    if x0 is None:
        return None
    rows = np.atleast_2d(np.asarray(x0, dtype=float))
    if rows.shape[1] != model.n_states_ or len(rows) not in (1, n_records):
        return None
    return np.repeat(rows, n_records, axis=0) if len(rows) == 1 else rows


def _spread(model, fit) -> np.ndarray:
    """The outputs' spread: of the model's training outputs when it was fitted by output
    error on the same outputs, else of the outputs given."""
    scale = getattr(model, "output_scale_", None)
    if scale is not None and list(getattr(model, "output_names_", [])) == fit.out_map.names:
        return np.maximum(np.asarray(scale), fit.y_scale)
    return fit.y_scale


def warn_if_not_converged(fit, coef, x0s, rows):
    """The RMS scaled output error of ``coef`` and initial states ``x0s`` on ``rows``
    (:meth:`~discrepancy.models.output_error.OutputErrorFit.error`), with a
    ``UserWarning`` when it is not finite (the fitted model's simulation diverges)."""
    import warnings

    err = fit.error(coef, x0s, rows)
    if not np.isfinite(err):
        warnings.warn("the fitted model's simulation diverges on the data", stacklevel=4)
    return err


def sandwich_uncertainty(model, covariance, dof: int, *, draws: int = 1000, seed: int = 0):
    """The coefficients' uncertainty as draws from a multivariate Student t around ``coef_``
    with scale ``covariance`` and ``dof`` degrees of freedom (blocks minus one), as a
    :class:`~discrepancy.models.uncertainty.CoefficientUncertainty`, so ``print``,
    ``predict_interval`` and ``simulate_interval`` take it as they take a bootstrap."""
    from .uncertainty import CoefficientUncertainty

    n, p = model.coef_.shape
    rng = np.random.default_rng(seed)
    values, vectors = np.linalg.eigh((covariance + covariance.T) / 2)
    root = vectors * np.sqrt(np.clip(values, 0, None))
    stretch = np.sqrt(dof / rng.chisquare(max(dof, 1), size=(draws, 1)))
    samples = model.coef_.ravel() + stretch * (rng.standard_normal((draws, n * p)) @ root.T)
    samples = samples.reshape(draws, n, p) * (model.coef_ != 0)
    return CoefficientUncertainty(model.coef_.copy(), samples, list(model.state_names_),
                                  model.get_feature_names(), 0)
