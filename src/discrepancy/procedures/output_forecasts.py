"""Output forecasts of :func:`~discrepancy.choose_procedure`: candidates fitted
by output error (``fit_outputs``) on every record's first part, their simulation scored
after the origin to the record's end.

Cost: an output-error fit walks a path of supports, each a nonlinear least squares through
the simulation, and that is the whole cost. Each candidate's procedure (path and choice)
therefore runs once, on the data before the first origin (a part of every later training
part, so unseen by every forecast); at each later origin only the chosen support's
coefficients and initial states are refitted (one output-error solve, starting from that
fit; where the first fit's simulation diverges on the longer part, the whole procedure
runs there instead). A candidate's path thus costs one fit on half of the data instead of
one per origin (Silverbox's blind run with the same four candidates: 375 CPU seconds with a
path per origin, 234 with one). The winner's whole procedure runs again on all the data: a support
chosen on half of a short record can miss what only its second half shows (the Cascaded
Tanks' winner kept 24 terms chosen on the first half where its own path on all the data
keeps 6).
"""
from __future__ import annotations

import copy
import warnings

import numpy as np

from ..errors import ConvergenceError
from ..hybrid.inputs import DEFAULT_HOLD
from ..hybrid.outputs import OutputMap
from ..models.outputs.output_checks import simulate_quietly
from ..models.outputs.output_fit import refit_outputs
from .judges import WHOLE, Judge, as_given, head

#: how :meth:`OutputForecasts.final` made the chosen model when not by :data:`.judges.WHOLE`
SCORED = ("its scored support refined on all the data (the whole procedure's fit was worse "
          "there with as many terms or more)")


class OutputForecasts(Judge):
    """Fit by output error on each record's first part; the fitted simulation continues to
    the record's end, its outputs scored after the origin. A candidate's procedure runs
    once, at its first origin; later origins and the final fit refit that support
    (module doc)."""

    def __init__(self, records, outputs, fit_kws):
        super().__init__(records, fit_kws)
        self.outputs, self.proposed = outputs, {}

    def _fit(self, model, y, t, u):
        return model.fit_outputs(y, t=t, u=u, outputs=self.outputs, **self.fit_kws)

    def fit(self, template, fraction):
        """``template`` fitted on the first ``fraction`` of every record: its whole
        procedure at its first origin and on all the data, at the origins between only
        its support refitted (module doc)."""
        first = self.proposed.get(id(template))
        if first is None or first.prior_only_ or fraction >= 1:
            return super().fit(template, fraction)
        parts = [head(r, fraction) for r in self.records]
        try:
            return _refitted(first, *(as_given([getattr(p, k) for p in parts])
                                      for k in ("x", "t", "u")), self.outputs, self.fit_kws)
        except ConvergenceError:   # its first model diverges on these data: start afresh
            return super().fit(template, fraction)

    def final(self, template, supports=None):
        """``(model, route)``: ``template``'s whole procedure on all the data; or, when its
        scored support (the fit at the first origin) refined on all the data fits them
        better with no more terms, that (the whole procedure's search stopped in a poorer
        minimum: a procedure scored by one fit must not hand back a worse one)."""
        whole = self.fit(template, 1.0)
        first = self.proposed.get(id(template))
        if first is None or first.prior_only_:
            return whole, WHOLE
        y, t, u = (as_given([getattr(r, k) for r in self.records]) for k in ("x", "t", "u"))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                scored = copy.deepcopy(first).refine(y, t, u=u, outputs=self.outputs,
                                                     x0=first.x0_, **_refit_options(self.fit_kws))
            except ConvergenceError:
                return whole, WHOLE
        fewer = np.count_nonzero(scored.coef_) <= np.count_nonzero(whole.coef_)
        if fewer and scored.output_error_ < whole.output_error_:
            return scored, SCORED
        return whole, WHOLE

    def score(self, template, fraction) -> float:
        """Mean scaled squared output error of the fitted simulation after the origin at
        ``fraction`` of every record, to the record's end (``inf`` if it diverges)."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                self.last = model = self.fit(template, fraction)
            except ConvergenceError:
                self.last = None
                return float("inf")
        self.proposed.setdefault(id(template), model)
        out_map = OutputMap(self.outputs, model.state_names_)
        x0s = model.x0_ if isinstance(model.x0_, list) else [model.x0_]
        scaled = []
        for x0, rec in zip(x0s, self.records, strict=True):
            cut = int(round(rec.n_samples * fraction))
            try:
                sim = out_map(simulate_quietly(model, x0, rec, self.fit_kws.get("substeps", 4),
                                        self.fit_kws.get("u_hold", DEFAULT_HOLD)))
            except ConvergenceError:
                return float("inf")
            scaled.append(((sim - rec.x) / self.scale)[cut:])
        with np.errstate(over="ignore", invalid="ignore"):   # a forecast that diverged
            value = float(np.mean(np.vstack(scaled) ** 2))
        return value if np.isfinite(value) else float("inf")


def _refitted(first, y, t, u, outputs, fit_kws):
    """A copy of ``first`` (a model fitted by output error) with its support's
    coefficients and the initial states refitted on ``y`` by one output-error solve,
    starting from its own."""
    kw = {"x0_bounds": None, "u_hold": DEFAULT_HOLD, "substeps": 4, **_refit_options(fit_kws)}
    coef, x0s, _ = refit_outputs(first, y, t, u, outputs=outputs, x0=first.x0_,
                                 coefficients=True, **kw)
    model = first.with_coefficients(coef * (first.coef_ != 0))
    model.x0_ = as_given(list(x0s))
    return model


def _refit_options(fit_kws: dict) -> dict:
    """The fit settings a refit of the same support takes (initial-state bounds, input
    hold, RK4 substeps)."""
    return {k: v for k, v in fit_kws.items() if k in ("x0_bounds", "u_hold", "substeps")}
