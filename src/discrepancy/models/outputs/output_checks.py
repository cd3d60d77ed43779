"""Output-error fits judged by held-out forecasts: the region a fit's terms saw, and
``refine`` never worse than the model it started from.

An output-error fit does not see every state, so its region is the range of the states
along its own fitted simulation (and of the measured inputs). ``refine`` refits the
coefficients of a model by output error on all the data; here the same refit is made on
the first ``1 - HOLDOUT`` of every record and both models forecast the rest (each from the
initial state it fits on the first part): when the refit forecasts worse, ``refine`` keeps
the model's coefficients and says so.
"""
from __future__ import annotations

import warnings

import numpy as np

from ...base import clone
from ...data.trajectory import as_trajectories
from ...errors import ConvergenceError, ParameterError, SelectionWarning
from ...hybrid.outputs import OutputMap
from ..simulate.region import FittedRegion
from .output_fit import refit_outputs

#: the share of every record held out to judge a refit
HOLDOUT = 0.25


def state_count(model, x0=None) -> int:
    """The number of states of a model about to be fitted by output error: its state names,
    a sympy prior's length, or the initial state's."""

    names, prior = model.state_names, model.prior
    if names is not None:
        return 1 if isinstance(names, str) else len(names)
    if isinstance(prior, (list, tuple)):
        return len(prior)
    if x0 is not None:
        return int(np.shape(x0)[-1])
    raise ParameterError("the number of states is unknown: give state_names, a prior as a "
                         "list of sympy expressions, or x0")


def simulated_region(model, y, t, u, *, x0s, substeps: int, u_hold: str):
    """The range of the states along the model's simulation of every record (from its
    fitted initial states) and of the inputs: ``FittedRegion`` or None if it diverges."""
    records = as_trajectories(y, t, u, x_name="y")
    parts = []
    for x0, rec in zip(x0s, records, strict=True):
        try:
            states = simulate_quietly(model, x0, rec, substeps, u_hold)
        except ConvergenceError:
            return None
        parts.append(states if rec.u is None else np.hstack([states, rec.u]))
    z = np.vstack(parts)
    if not np.all(np.isfinite(z)):
        return None
    return FittedRegion(tuple(model.variable_names_), z.min(axis=0), z.max(axis=0))


def prior_states(model, y, t=None, u=None, *, outputs, **fit_kws) -> np.ndarray:
    """The states ``(m, n)`` (every record's, stacked) along the simulation of ``model``'s
    prior alone, its initial states fitted to the outputs ``y`` by output error: values
    for the states no output measures (where default candidate libraries place knots and
    scales, and see whether a state keeps one sign). ``fit_kws``: as for ``fit_outputs``
    (``x0``, ``x0_bounds``, ``u_hold``, ``substeps``). NaN where the simulation diverges."""
    prior = clone(model).set_params(optimizer="prior_only")
    keys = ("x0", "x0_bounds", "u_hold", "substeps")
    kw = {k: v for k, v in fit_kws.items() if k in keys}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        prior.fit_outputs(y, t=t, u=u, outputs=outputs, **kw)
    x0s = prior.x0_ if isinstance(prior.x0_, list) else [prior.x0_]
    parts = []
    for x0, rec in zip(x0s, as_trajectories(y, t, u, x_name="y"), strict=True):
        try:
            parts.append(simulate_quietly(prior, x0, rec, kw.get("substeps", 4),
                                          kw.get("u_hold", "linear")))
        except ConvergenceError:
            parts.append(np.full((rec.n_samples, len(x0)), np.nan))
    return np.vstack(parts)


def simulate_quietly(model, x0, record, substeps, u_hold):
    """``model.simulate`` of a record (RK4 at its samples) without the region's warning."""
    region, model.region_ = model.region_, None        # no warnings from our own check
    try:
        return model.simulate(x0, record.t, u=record.u, method="rk4", substeps=substeps,
                              u_hold=u_hold)
    finally:
        model.region_ = region


def check_refine(model, before: np.ndarray, y, t, u, *, outputs, x0, x0_bounds, u_hold,
                 substeps) -> dict:
    """Refit ``before`` (the coefficients ``refine`` started from) on the first part of
    every record and compare held-out forecasts with ``before``'s. Returns
    ``{"kept_original", "heldout_error_original", "heldout_error_refined"}`` (scaled RMS
    output errors on the held-out parts)."""

    records = as_trajectories(y, t, u, x_name="y")
    cut = [int(round(r.n_samples * (1 - HOLDOUT))) for r in records]
    if min(cut) < 4 or min(r.n_samples - c for r, c in zip(records, cut, strict=True)) < 2:
        return {"kept_original": False, "heldout_error_original": None,
                "heldout_error_refined": None}
    first = _parts(records, cut)
    original = model.with_coefficients(before)
    kw = dict(outputs=outputs, x0=x0, x0_bounds=x0_bounds, u_hold=u_hold, substeps=substeps)
    refit_coef, refit_x0s, _ = refit_outputs(original, *first, coefficients=True, **kw)
    _, original_x0s, _ = refit_outputs(original, *first, coefficients=False, **kw)
    out_map = OutputMap(outputs, model.state_names_)
    scale = _output_scale(records)
    errors = [_heldout_error(original.with_coefficients(coef), x0s, records, cut,
                             out_map, scale, substeps, u_hold)
              for coef, x0s in ((before, original_x0s), (refit_coef, refit_x0s))]
    kept = not errors[1] <= errors[0]
    if kept:
        warnings.warn(f"refine kept the model's coefficients: refitted on the first "
                      f"{1 - HOLDOUT:.0%} of every record, they forecast the rest worse "
                      f"(scaled RMS output error {errors[1]:.4g} against {errors[0]:.4g})",
                      SelectionWarning, stacklevel=4)
    return {"kept_original": bool(kept), "heldout_error_original": errors[0],
            "heldout_error_refined": errors[1]}


def _parts(records, cut):
    ys = [r.x[:c] for r, c in zip(records, cut, strict=True)]
    ts = [r.t[:c] for r, c in zip(records, cut, strict=True)]
    us = None if records[0].u is None else [r.u[:c] for r, c in zip(records, cut, strict=True)]
    return ys, ts, us


def _output_scale(records) -> np.ndarray:
    y = np.vstack([r.x for r in records])
    spread = y.std(axis=0)
    return np.where(spread > 0, spread, 1.0)


def _heldout_error(model, x0s, records, cut, out_map, scale, substeps, u_hold) -> float:
    squares = []
    for x0, rec, c in zip(x0s, records, cut, strict=True):
        try:
            sim = out_map(simulate_quietly(model, x0, rec, substeps, u_hold))
        except ConvergenceError:
            return float("inf")
        squares.append((((sim - rec.x) / scale)[c:]) ** 2)
    value = float(np.sqrt(np.mean(np.vstack(squares))))
    return value if np.isfinite(value) else float("inf")
