"""``DiscrepancyModel.fit_outputs``: the output-error fit from data to a fitted model
(set-up, initial states, the path of supports, the choice, the final refit)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...constraints import Integral, Interval, Real, check_argument
from ...errors import ConvergenceError, ParameterError, ShapeError
from ...hybrid.outputs import OutputMap
from ...optimizers.selection import one_standard_error
from .initial_states import best_start, candidates, warn_if_poor
from .output_error import (
    NEGLIGIBLE,
    RIDGE,
    OutputErrorFit,
    check_identifiable,
    initial_states,
    n_states_of,
    records_of,
    signed_starts,
    split_rows,
    warn_if_not_converged,
)
from .output_error import x0_bounds as bounds_of
from .shooting import ShootingModel, worth_compiling

#: simulations allowed per support on the path (the final refit may use more)
PATH_EVALUATIONS = 200
#: samples of each record on which the prior's candidate initial states are compared
START_WINDOW = 2000


@dataclass
class SupportScore:
    """One support on the path: its terms ``(n, p)`` bool, coefficients fitted on the
    training part, the mean squared scaled forecast error on the held-out part and the
    standard error of that mean."""

    support: np.ndarray
    coef: np.ndarray
    heldout_mse: float
    heldout_se: float

    @property
    def n_terms(self) -> int:
        """Number of terms in the support."""
        return int(self.support.sum())

    @property
    def heldout_error(self) -> float:
        """RMS scaled forecast error on the held-out part."""
        return float(np.sqrt(self.heldout_mse))


def prepare(setup, records, *, outputs, x0, x0_bounds, substeps, free=None):
    """The fit's pieces for ``setup`` and the records: ``(fit, x0s, all rows of each)``.
    ``free`` ``(n, p)``: the coefficients that may be fitted (default: the allowed ones)."""
    r = 0 if records[0].u is None else records[0].u.shape[1]
    if r != setup.n_inputs:
        raise ShapeError(f"u has {r} input columns; the model has {setup.n_inputs}")
    out_map = OutputMap(outputs, setup.state_names)
    if records[0].y.shape[1] != out_map.k:
        raise ShapeError(f"y has {records[0].y.shape[1]} columns but outputs names "
                         f"{out_map.k} measured quantities {out_map.names}")
    x0s = initial_states(x0, records, out_map, setup.n_states)
    points = (x0s, None if not r else np.repeat(records[0].u[:1], len(x0s), axis=0))
    allowed = _allowed(setup)
    free = allowed if free is None else free
    shooting = ShootingModel(setup, substeps, check_points=points, free=free,
                             compile=worth_compiling(sum(rec.m - 1 for rec in records),
                                                     setup.n_states, int(free.sum())))
    fit = OutputErrorFit(setup, records, out_map, shooting, allowed)
    fit.bounds = bounds_of(x0_bounds, setup.n_states)
    check_identifiable(fit)
    return fit, x0s, [np.ones(rec.m, bool) for rec in records]


def fit_outputs(model, y, t, u, *, outputs, x0, x0_bounds, u_hold, substeps, max_terms,
                holdout, tolerance, progress):
    """See :meth:`DiscrepancyModel.fit_outputs`."""
    _check_options(max_terms, holdout, tolerance)
    n = n_states_of(model, x0)
    records, r = records_of(model, y, t, u, substeps, u_hold)
    setup = model.make_setup(n, r)
    fit, x0s, everything = prepare(setup, records, outputs=outputs, x0=x0,
                                   x0_bounds=x0_bounds, substeps=substeps)
    x0s = prior_x0s = _prior_start(fit, x0s, everything, guessed=x0 is None)
    fit.set_coef_scale(x0s)
    threshold = getattr(setup.optimizer, "threshold", "auto")
    if threshold == "auto":
        path, chosen = _path(fit, x0s, max_terms, holdout, tolerance, progress)
        support, coef = chosen.support, chosen.coef
    else:
        (support, coef), path = _thresholded(fit, x0s, float(threshold), max_terms,
                                             everything), []
    coef, x0s, _ = fit.solve(support, coef * support, x0s, everything, 0.0)
    coef[~support] = 0.0
    worse = _worse_than_prior(fit, coef, x0s, prior_x0s, everything)
    if worse:
        support, coef, x0s = np.zeros_like(support), np.zeros_like(coef), prior_x0s
    error = warn_if_not_converged(fit, coef, x0s, everything)
    fit.covariance = fit.coefficient_covariance(support, coef, x0s, everything)
    return setup, coef, x0s, fit, path, error, worse


def _worse_than_prior(fit, coef, x0s, prior_x0s, rows) -> str | None:
    """Why the chosen support, refitted on all the data, is not kept (its simulation
    diverges there, or fits the outputs worse than the prior alone from its own best
    initial states), or ``None``. A support is chosen on the training part; its refit on
    everything can leave that basin (on Van der Pol without its restoring term, measured
    by position only, an 18-term model diverged within 0.01 s of its own record)."""
    if not coef.any():
        return None
    error, prior = fit.error(coef, x0s, rows), fit.error(np.zeros_like(coef), prior_x0s, rows)
    if error <= prior:
        return None
    how = "diverges on them" if not np.isfinite(error) else \
        f"fits them worse than the prior alone (output error {error:.4g} against {prior:.4g})"
    return (f"the chosen support of {np.count_nonzero(coef)} terms, refitted on all the "
            f"data, {how}: the model is the prior alone (model.prior_only_ is True; "
            "model.output_selection_ has every support's score; a model fitted first on "
            "estimated states, e.g. velocities differentiated from measured positions, "
            "then refined by output error (refine), may find the correction)")


def _prior_start(fit, x0s, rows, *, guessed: bool):
    """Initial states that fit the outputs best with the prior alone. Without a guess the
    unmeasured states are tried at 0 and at plus and minus the outputs' typical size (a
    state at 0 can be a fixed point the fit cannot leave). The starts are compared on the
    first :data:`START_WINDOW` samples of each record and only the best is then fitted to
    all of them (an initial state shows in the first samples; on long records, fitting every
    start to everything costs seconds and picks the same one)."""
    none = np.zeros((fit.n, fit.p), bool)
    hidden = sorted(set(range(fit.n)) - fit.out_map.measured)
    starts = [x0s]
    if guessed and hidden:
        starts += [np.clip(s, *fit.bounds) for s in signed_starts(fit, x0s, hidden)]
    short = all(r.m <= START_WINDOW for r in fit.records)
    window = fit if short else fit.head(START_WINDOW)
    window_rows = rows if short else [w[:START_WINDOW] for w in rows]
    best = None
    for start in starts:
        _, x0s, cost = window.solve(none, fit.fixed, start, window_rows, 0.0)
        if best is None or cost < best[1]:
            best = (x0s, cost)
    return best[0] if short else fit.solve(none, fit.fixed, best[0], rows, 0.0)[1]


def _check_options(max_terms, holdout, tolerance):
    check_argument("max_terms", max_terms, None, Interval(Integral, 1))
    check_argument("holdout", holdout, Interval(Real, 0.05, 0.5))
    check_argument("tolerance", tolerance, None, Interval(Real, 0, 1))


def _allowed(setup) -> np.ndarray:
    """Terms each equation may use: the model's constraints (masks only), else all."""
    constraints = getattr(setup.optimizer, "constraints", None)
    if constraints is None:
        return np.ones((setup.n_states, setup.n_features), bool)
    if constraints.has_linear:
        raise ParameterError("output-error fits honour term masks (exact_equations, only) "
                             "but not linear equalities or inequalities")
    return constraints.allowed.copy()


def _first_support(fit, x0s, rows, max_terms):
    """The full allowed library fitted (with a small ridge), cut to ``max_terms``."""
    coef, x0s, _ = fit.solve(fit.allowed, np.zeros((fit.n, fit.p)), x0s, rows, RIDGE)
    support = fit.allowed.copy()
    if max_terms is not None and support.sum() > max_terms:
        order = np.argsort(-fit.importance(coef))
        keep = np.zeros(fit.n * fit.p, bool)
        keep[order[:max_terms]] = True
        support &= keep.reshape(support.shape)
        coef, x0s, _ = fit.solve(support, coef * support, x0s, rows, RIDGE)
    return support, coef, x0s


def _drop_least(fit, support, coef) -> np.ndarray:
    """The support without its least important term (and any negligible ones)."""
    size = np.where(support.ravel(), fit.importance(coef), np.inf)
    active = np.isfinite(size)
    drop = size <= NEGLIGIBLE * size[active].max()
    drop[np.argmin(size)] = True
    return support & ~drop.reshape(support.shape)


def _path(fit, x0s, max_terms, holdout, tolerance, progress):
    """Supports from the full library down to none, fitted on the training part of every
    record and scored on the held-out rest; the choice by :func:`choose`."""
    from tqdm.auto import tqdm

    train, test = split_rows(fit.records, holdout)
    zero = np.zeros((fit.n, fit.p))
    prior_x0s = x0s
    _, prior_train_x0s, prior_cost = fit.solve(zero.astype(bool), zero, x0s, train, 0.0)
    support, coef, x0s = _first_support(fit, x0s, train, max_terms)
    path = []
    bar = tqdm(total=int(support.sum()) + 1, desc="output-error path", unit="support",
               disable=None if progress is None else not progress)
    while True:
        path.append(SupportScore(support.copy(), coef.copy(),
                                 *fit.squared_errors(coef, x0s, test)))
        bar.update()
        if not support.any():
            break
        smaller = _drop_least(fit, support, coef)
        start = fit.compensated(coef, support & ~smaller, x0s)
        support = smaller
        coef, x0s, cost = fit.solve(support, start, x0s, train, RIDGE,
                                    max_evaluations=PATH_EVALUATIONS)
        if not cost <= prior_cost and not support.any():   # the prior alone, solved above
            coef, x0s = zero.copy(), prior_train_x0s
        elif not cost <= prior_cost:   # lost on the way: start again from the prior alone
            coef, x0s, _ = fit.solve(support, zero, prior_x0s, train, RIDGE,
                                     max_evaluations=PATH_EVALUATIONS)
    bar.close()
    return path, choose(path, tolerance)


def choose(path, tolerance):
    """The sparsest support whose held-out error is within one standard error of the best
    (``tolerance=None``), or within ``tolerance`` (relative, of the RMS) of it."""
    if tolerance is None:
        return path[one_standard_error([s.heldout_mse for s in path],
                                       [s.heldout_se for s in path],
                                       [s.n_terms for s in path])]
    best = min(path, key=lambda s: s.heldout_mse)
    bar = (1 + tolerance) * best.heldout_error
    return min((s for s in path if s.heldout_error <= bar), key=lambda s: s.n_terms)


def _thresholded(fit, x0s, threshold, max_terms, rows):
    """Sequential thresholding on the raw coefficients: refit, drop ``|ξ| < threshold``."""
    support, coef, x0s = _first_support(fit, x0s, rows, max_terms)
    for _ in range(support.size):
        keep = support & (np.abs(coef) >= threshold)
        if np.array_equal(keep, support):
            break
        support = keep
        coef, x0s, _ = fit.solve(support, coef * support, x0s, rows, RIDGE)
    return support, coef


def refit_outputs(model, y, t, u, *, outputs, x0, x0_bounds, u_hold, substeps, coefficients):
    """Output error of a fitted model on new data with its support kept: the nonzero
    coefficients refitted (``coefficients=True``) or all held (only initial states).
    Returns ``(coef, x0s, fit)``."""
    records, _ = records_of(model, y, t, u, substeps, u_hold)
    support = (model.coef_ != 0) if coefficients else np.zeros_like(model.coef_, bool)
    fit, x0s, everything = prepare(model.setup_, records, outputs=outputs, x0=x0,
                                   x0_bounds=x0_bounds, substeps=substeps, free=support)
    fit.fixed = model.coef_.copy()
    diverged = fit.set_coef_scale(x0s)
    if diverged:           # no slope to follow from a start whose simulation is not finite
        raise ConvergenceError(
            f"the model's simulation from its initial state diverges on record "
            f"{diverged[0]} of these data, and output error cannot start from a simulation "
            "that is not finite: start from a model (or x0=) whose simulation stays finite")
    coef, x0s, _ = fit.solve(support, model.coef_, x0s, everything, 0.0)
    if not np.all(np.isfinite(coef)) or not np.all(np.isfinite(x0s)):
        raise ConvergenceError("the output-error refit diverged on these data (its "
                               "coefficients or initial states are not finite): start from "
                               "a model (or x0=) closer to them")
    if coefficients:
        fit.covariance = fit.coefficient_covariance(support, coef, x0s, everything)
    return coef, x0s, fit


def sandwich_uncertainty(model, covariance, dof: int, *, draws: int = 1000, seed: int = 0):
    """The coefficients' uncertainty as draws from a multivariate Student t around ``coef_``
    with scale ``covariance`` and ``dof`` degrees of freedom (blocks minus one), as a
    :class:`~discrepancy.models.core.uncertainty.CoefficientUncertainty`, so ``print``,
    ``predict_interval`` and ``simulate_interval`` take it as they take a bootstrap."""
    from ..core.uncertainty import CoefficientUncertainty

    n, p = model.coef_.shape
    rng = np.random.default_rng(seed)
    values, vectors = np.linalg.eigh((covariance + covariance.T) / 2)
    root = vectors * np.sqrt(np.clip(values, 0, None))
    stretch = np.sqrt(dof / rng.chisquare(max(dof, 1), size=(draws, 1)))
    samples = model.coef_.ravel() + stretch * (rng.standard_normal((draws, n * p)) @ root.T)
    samples = samples.reshape(draws, n, p) * (model.coef_ != 0)
    return CoefficientUncertainty(model.coef_.copy(), samples, list(model.state_names_),
                                  model.get_feature_names(), 0)


def estimate_initial_states(model, y, t, u, *, outputs, x0, x0_bounds, u_hold, substeps):
    """Initial states ``(records, n)`` of a fitted model's records, its coefficients held:
    fitted from several starts (:func:`~.initial_states.candidates`), the best kept per
    record, with :class:`~discrepancy.errors.InitialStateWarning` when even that fits
    poorly."""
    records, _ = records_of(model, y, t, u, substeps, u_hold)
    fit, guess, everything = prepare(model.setup_, records, outputs=outputs, x0=x0,
                                     x0_bounds=x0_bounds, substeps=substeps,
                                     free=np.zeros_like(model.coef_, bool))
    starts = candidates(fit, model.coef_, given=None if x0 is None else guess)
    x0s, labels, rms = best_start(fit, model.coef_, everything, starts)
    warn_if_poor(rms, labels, fit.y_scale, len(starts))
    return x0s
