"""How :func:`~discrepancy.choose_procedure` fits a candidate on the first part of every
record and scores its forecasts of the rest (state forecasts here; output forecasts in
:mod:`.output_forecasts`)."""
from __future__ import annotations

import warnings

import numpy as np

from ..base import clone
from ..data.trajectory import Trajectory
from ..errors import DataError
from ..fitting.held_out import Window
from ..selection.forecast import forecast_scores, prepare
from ..selection.horizon import sensitive_leads

#: where the first origin lies, as a share of each record
FIRST_ORIGIN = 0.5
#: the forecast length of output fits, and the most of a record a state forecast takes
HORIZON_SHARE = 0.25
#: how :meth:`Judge.final` fits the chosen candidate on all the data
WHOLE = "its whole procedure on all the data"
#: how :meth:`StateForecasts.final` made the chosen model when not by :data:`WHOLE`
SCORED_SUPPORT = ("its scored support (the fit on the largest part) refitted on all the "
                  "data: the whole procedure kept more terms than any fit the forecasts "
                  "scored")


class Judge:
    """Fits a candidate on each record's first part (``fraction``); every measured signal
    scaled by its standard deviation over all the data."""

    horizon = None

    def __init__(self, records, fit_kws):
        self.records, self.fit_kws, self.last = records, fit_kws, None
        data = np.vstack([r.x for r in records])
        self.scale = np.where(data.std(axis=0) > 0, data.std(axis=0), 1.0)

    def final(self, template, supports=None):
        """``(model, route)``: ``template`` fitted on all the data, and how (``supports``:
        the scored fits' supports, one per origin, ``None`` where there was none)."""
        return self.fit(template, 1.0), WHOLE

    def fit(self, template, fraction):
        """A clone of ``template`` fitted on the first ``fraction`` of every record."""
        parts = [head(r, fraction) for r in self.records]
        return self._fit(clone(template), *(as_given([getattr(p, k) for p in parts])
                                            for k in ("x", "t", "u")))


class StateForecasts(Judge):
    """Forecast from the state at the origin (initial state fitted to the window, as the
    model's own selection scores), each window scored until the prior's sensitivity to
    its start reaches the selection's limit."""

    def __init__(self, records, fit_kws, horizon):
        super().__init__(records, fit_kws)
        shortest = min(r.n_samples for r in records)
        self.horizon = int(HORIZON_SHARE * shortest) if horizon is None else int(horizon)

    def _fit(self, model, x, t, u):
        return model.fit(x, t=t, u=u, **self.fit_kws)

    def final(self, template, supports=None):
        """``(model, route)``: ``template``'s whole procedure on all the data; or, when that
        kept more terms than any fit the forecasts scored (``supports``, one per origin),
        the support of the fit on the largest part refitted on all the data: a procedure
        scored by sparse fits must not hand back terms nobody scored (a union of libraries
        whose fits kept one sine each came back with five terms, powers of an angle among
        them)."""
        whole = self.fit(template, 1.0)
        kept = [s for s in supports or [] if s is not None]
        if not kept or np.count_nonzero(whole.coef_) <= max(map(np.count_nonzero, kept)):
            return whole, WHOLE
        refitted = _refitted_on(whole, kept[-1])
        return (whole, WHOLE) if refitted is None else (refitted, SCORED_SUPPORT)

    def score(self, template, fraction) -> float:
        """Mean scaled squared forecast error of ``template`` fitted up to the origin at
        ``fraction`` of every record (the fitted model kept in ``self.last``)."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.last = model = self.fit(template, fraction)
        setup = model.setup_
        origins = prepare(self._windows(setup, fraction), setup, scale=self.scale)
        W, everything = origins.n_windows, np.arange(origins.n_windows)
        coef = np.repeat(model.coef_[None], W, axis=0)
        steps = max(1, min(self.horizon // origins.stride, origins.max_steps))
        origins = origins.subset(everything, steps)
        prior = forecast_scores(setup, origins, np.zeros_like(coef), everything, steps)
        origins = sensitive_leads(origins, prior)
        return float(np.mean(forecast_scores(setup, origins, coef, everything, steps).score))

    def _windows(self, setup, fraction):
        pre, windows = setup.new_held_out().pre, []
        for rec in self.records:
            cut = int(round(rec.n_samples * fraction))
            lo, hi = max(0, cut - pre), min(rec.n_samples, cut + self.horizon + 1)
            window = Window(0, cut - lo, hi - lo)
            window.append(rec.t[lo:hi], rec.x[lo:hi], None if rec.u is None else rec.u[lo:hi])
            if window.lead >= 2:
                windows.append(window)
        if not windows:
            raise DataError("the records are too short to forecast from the origins")
        return windows


def _refitted_on(model, support):
    """``model`` with the coefficients of ``support`` ``(n, p)`` fitted on its own data
    (its statistics, constraints and ridge; ``None`` when it kept no statistics)."""
    from ..selection.candidates import FoldFits

    stats = model.statistics_
    if stats is None or np.shape(support) != model.coef_.shape:
        return None
    optimizer = model.optimizer_
    alpha = 0.0 if getattr(optimizer, "unbias", True) else getattr(optimizer, "alpha", 0.0)
    constraints = getattr(model.setup_.optimizer, "constraints", None)
    return model.with_coefficients(FoldFits(stats, constraints, alpha).coefficients(
        np.asarray(support, bool), None))


def head(record, fraction):
    """The first ``fraction`` of ``record`` (all of it at ``fraction >= 1``)."""
    k = record.n_samples if fraction >= 1 else int(round(record.n_samples * fraction))
    return Trajectory(record.t[:k], record.x[:k], None if record.u is None else record.u[:k])


def as_given(per_record: list):
    """One record's value alone (as a user gives one record), else the list; ``None`` for
    records without inputs."""
    if per_record[0] is None:
        return None
    return per_record[0] if len(per_record) == 1 else per_record
