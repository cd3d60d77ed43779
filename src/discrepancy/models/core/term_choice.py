"""The select stage of a fit: which terms the model keeps, the prior alone included.

``selection="auto"`` (the default) chooses by forecasts when the optimizer chooses its own
sparsity (``STLSQ(threshold="auto")``, the default optimizer): the equation-error path
proposes supports and rolling-origin forecasts over held-out blocks of the training data
decide (:mod:`discrepancy.selection.choice`). A fixed threshold or another optimizer is
used as given. ``selection="forecast"`` also compares a given optimizer's answer with the
prior alone; ``selection="optimizer"`` keeps the optimizer's own choice (equation error).
"""
from __future__ import annotations

import warnings

import numpy as np

from ...errors import DataError, PriorOnlyWarning, SelectionWarning
from ...selection.choice import select_by_forecasts

SELECTIONS = ("auto", "forecast", "optimizer")


def by_forecasts(selection: str, optimizer) -> bool:
    """Whether ``selection`` asks for forecasts with this optimizer."""
    if selection == "forecast":
        return True
    return selection == "auto" and getattr(optimizer, "threshold", None) == "auto"


def choose_terms(model, setup, stats, optimizer):
    """``(coef (n, p), ForecastSelection or None)`` for a fitted ``optimizer``."""
    if not by_forecasts(model.selection, setup.optimizer):
        return np.asarray(optimizer.coef_, dtype=float), None
    chosen = select_by_forecasts(setup, stats, optimizer, stats.held_out)
    if chosen is None:
        if model.selection == "forecast":
            raise DataError("selection='forecast' needs forecast windows kept with the "
                            f"statistics (at least 4 segment starts of {stats.segment} rows; "
                            "make them with setup.new_statistics()); these statistics have "
                            "too few. Give more data or selection='optimizer'")
        return np.asarray(optimizer.coef_, dtype=float), None
    return chosen


def announce(model, selection) -> None:
    """Warn when the model is the prior alone, chosen by forecasts; and when forecasts were
    asked for but the data held too few windows to judge, so equation error's choice
    stands unchecked against the prior alone."""
    if selection is None:
        if by_forecasts(model.selection, model.setup_.optimizer):
            _unchecked(model)
        return
    if not selection.prior_only:
        return
    best = int(np.argmin(selection.score))
    margin = "" if selection.n_terms[best] == 0 else (
        f" (the best correction, {selection.n_terms[best]} terms, forecast "
        f"{100 * (1 - selection.score[best] / selection.score[selection.prior_index]):.2g} % "
        "better, within one standard error)")
    warnings.warn("no correction forecast better than the prior alone on held-out blocks of "
                  f"the training data{margin}: the model is the prior alone "
                  "(model.prior_only_ is True; model.forecast_selection_ has every "
                  "candidate's score)", PriorOnlyWarning, stacklevel=4)


def _unchecked(model) -> None:
    paths = getattr(model.optimizer_, "selection_", None) or [{}]
    if paths[0].get("criterion") == "BIC":
        return   # the short-record fallback to BIC has said so (ShortRecordWarning)
    why = ("the training data hold too few forecast windows, or windows too short beside "
           "the smoothing, to compare it with the prior alone")
    terms = int(np.count_nonzero(model.coef_))
    if terms:
        warnings.warn(f"the equation-error choice ({terms} terms) stands unchecked: {why} "
                      "(model.forecast_selection_ is None; a longer record lets forecasts "
                      "judge; check the model's simulation against the prior's)",
                      SelectionWarning, stacklevel=5)
    else:
        warnings.warn(f"equation error (the cross-validated threshold path) kept no term, "
                      f"and {why}: the model is the prior alone (model.prior_only_ is True; "
                      "model.optimizer_.selection_ has the path's scores; a longer record lets "
                      "forecasts judge)", PriorOnlyWarning, stacklevel=5)
