"""Selection by forecasts, the prior alone included: what ``DiscrepancyModel.fit`` does by
default.

1. The forecast windows kept with the statistics (:mod:`.held_out`) are prepared: origin
   states smoothed as the fit smoothed them, the raw samples after them as the truth.
2. The prior alone forecasts from every origin; the horizon is where its error saturates
   (:func:`~.horizon.choose_steps`), so a chaotic or unstable system is judged on the
   leads where forecasts still mean something.
3. Candidates (:mod:`.candidates`) are refitted without the fold each origin lies in and
   forecast ``horizon`` samples from it; a candidate's score at a window is its mean scaled
   squared error over leads 1..horizon (every k-step error up to the horizon), its score
   the mean over windows, with the standard error over windows.
4. The choice is the one-standard-error rule (the one of
   :mod:`discrepancy.optimizers.selection`): the fewest terms whose score is within one
   standard error of the best, or within :data:`TOLERANCE` of it when that is larger. The
   prior alone has no terms, so a correction is kept only when it forecasts better than
   the prior by more than that.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..fitting.held_out import MIN_WINDOWS
from ..optimizers.selection import one_standard_error
from . import candidates as cands
from .forecast import CAP, forecast_scores, prepare, refine_origins
from .horizon import choose_steps, sensitive_leads

#: rounds of the coordinate search over candidates
MAX_ROUNDS = 3
#: scores within this fraction of the best are ties whatever their standard error (a mean
#: squared error 5 % lower, 2.5 % in RMS, is not worth a term on its own)
TOLERANCE = 0.05


@dataclass
class ForecastSelection:
    """How a model was chosen by forecasts (``model.forecast_selection_``).

    Attributes:
        supports: every candidate's terms ``(n, p)`` bool, in the order scored (the
            equation-error choice first, then the prior alone).
        n_terms, score, score_se: per candidate: terms, mean scaled squared forecast error
            over the windows (the states scaled by their standard deviation; leads 1 to
            ``horizon``) and its standard error.
        window_scores: ``(candidates, windows)`` scores of every candidate at every window.
        labels: ``"equation error"``, ``"prior alone"`` or ``""`` per candidate.
        chosen: index of the chosen candidate; prior_only: whether it has no terms.
        horizon: forecast length in samples; horizon_time: in time units (median over
            windows); n_windows: forecast origins used; window_leads: the samples scored
            after each origin (shorter than the horizon where the reference model's
            sensitivity to its start saturates, :mod:`.horizon`).
        lead_rms: ``{"prior alone": (horizon,), "chosen": (horizon,)}``: RMS scaled error
            at each lead over the windows.
    """

    supports: list
    n_terms: list
    score: list
    score_se: list
    labels: list
    window_scores: np.ndarray = field(repr=False)
    chosen: int = 0
    horizon: int = 0
    horizon_time: float = 0.0
    n_windows: int = 0
    lead_rms: dict = field(default_factory=dict, repr=False)
    window_leads: list = field(default_factory=list, repr=False)

    @property
    def prior_only(self) -> bool:
        """True when the chosen candidate has no terms: the prior alone was chosen."""
        return self.n_terms[self.chosen] == 0

    @property
    def prior_index(self) -> int:
        """Index of the prior-alone candidate in the per-candidate lists."""
        return self.labels.index("prior alone")

    def improvement(self) -> float:
        """How much lower the chosen candidate's score is than the prior's (fraction)."""
        prior = self.score[self.prior_index]
        return float(1 - self.score[self.chosen] / prior) if prior > 0 else 0.0

    def summary(self) -> dict:
        """JSON-ready summary (what the model file keeps)."""
        return {"criterion": "rolling-origin forecasts", "prior_only": self.prior_only,
                "horizon_samples": self.horizon, "horizon_time": self.horizon_time,
                "n_windows": self.n_windows, "n_candidates": len(self.score),
                "chosen_terms": self.n_terms[self.chosen],
                "chosen_score": self.score[self.chosen],
                "prior_score": self.score[self.prior_index]}

    def table(self) -> str:
        """One line per candidate: terms, score ± standard error, label."""
        lines = [f"{'terms':>5}  {'forecast error':>14}  {'± s.e.':>9}"]
        for k in np.argsort(self.n_terms, kind="stable"):
            mark = "  <- chosen" if k == self.chosen else ""
            label = f"  ({self.labels[k]})" if self.labels[k] else ""
            lines.append(f"{self.n_terms[k]:>5}  {self.score[k]:>14.5g}  "
                         f"{self.score_se[k]:>9.2g}{label}{mark}")
        return "\n".join(lines)


def select_by_forecasts(setup, stats, optimizer, held_out):
    """``(coef (n, p), ForecastSelection)`` chosen by forecasts, or ``None`` when the
    statistics hold too few forecast windows (then the optimizer's choice stands)."""
    windows = [] if held_out is None else held_out.complete()
    if len(windows) < MIN_WINDOWS or not stats.usable_folds():
        return None
    derivatives = stats.signal / stats.count if stats.count else None
    origins = prepare(windows, setup,
                      mean_square_rate=None if setup.form.raw_origins else derivatives)
    everything = np.arange(origins.n_windows)
    coef, reference = _reference(setup, origins, optimizer)
    origins = sensitive_leads(origins, reference)
    reference.lead[np.isnan(origins.truth[:, :, 0])] = np.nan
    steps = choose_steps(reference.lead)
    if steps * origins.stride <= _halo(setup):
        return None   # forecasts that end inside the smoothing window test nothing it hides
    full = origins.steps_held() >= steps
    origins = origins.subset(full if full.sum() >= MIN_WINDOWS else everything, steps)
    origins = refine_origins(setup, origins, min(steps, _local_steps(setup, origins)), coef)
    search = _Search(setup, stats, optimizer, origins)
    search.run()
    mean = search.scores.mean(axis=1)
    margin = np.maximum(search.standard_errors(), TOLERANCE * mean.min())
    k = one_standard_error(mean, margin, search.n_terms)
    return search.final_coefficients(k), search.result(k)


def _reference(setup, origins, optimizer):
    """``(coef, Scores)`` of the model the horizon and the origins are judged with: the
    prior alone, or the equation-error choice when it forecasts the windows better (a prior
    that diverges would leave no horizon at all)."""
    W, n, p = origins.n_windows, setup.n_states, setup.n_features
    everything = np.arange(W)
    candidates = [np.zeros((n, p))]
    if np.any(optimizer.coef_):
        candidates.append(np.asarray(optimizer.coef_, dtype=float))
    runs = [forecast_scores(setup, origins, np.repeat(c[None], W, axis=0), everything,
                            origins.max_steps) for c in candidates]
    errors = [np.nanmean(np.minimum(run.lead, CAP)) for run in runs]
    k = int(np.argmin(errors))
    return candidates[k], runs[k]


def _halo(setup) -> int:
    """Samples on either side that the differentiation smooths an origin with (0 when it
    does not say)."""
    halo = getattr(setup.differentiation, "halo", None)
    return int(halo) if isinstance(halo, (int, np.integer)) else 0


def _local_steps(setup, origins) -> int:
    """Steps spanning the smoothing window (at least 8): the stretch the origin state is
    refined on."""
    return max(8, -(-(2 * _halo(setup) + 1) // origins.stride))


class _Search:
    """The candidates scored so far and the coordinate search over them."""

    def __init__(self, setup, stats, optimizer, origins):
        self.setup, self.stats, self.optimizer, self.origins = setup, stats, optimizer, origins
        constraints = getattr(setup.optimizer, "constraints", None)
        alpha = 0.0 if getattr(optimizer, "unbias", True) else getattr(optimizer, "alpha", 0.0)
        self.fits = cands.FoldFits(stats, constraints, alpha)
        n, p = setup.n_states, setup.n_features
        try:
            self.paths = cands.equation_paths(optimizer, n, p, stats,
                                              getattr(constraints, "allowed", None), alpha)
        except LookupError:   # an optimizer's own answer, not a path: it or the prior
            self.paths = None
        self.keys, self.supports, self.labels, self.rows, self.curves = [], [], [], [], []
        self.fixed = {}
        start = cands.start(optimizer, self.paths) if self.paths else "optimizer"
        self.start = start
        self._add(start, optimizer.coef_ != 0, "equation error")
        empty = cands.prior_only(self.paths) if self.paths else "prior"
        if empty == start:
            self.labels[0] = "prior alone"
        else:
            self._add(empty, np.zeros((n, p), bool), "prior alone")
        self.steps = origins.max_steps

    def _add(self, key, support, label):
        self.keys.append(key)
        self.supports.append(np.asarray(support, bool))
        self.labels.append(label)
        self.rows.append(None)
        self.curves.append(None)

    def run(self) -> None:
        if self.paths is None:
            self._score_pending()
            return
        centre = self.start
        for _ in range(MAX_ROUNDS):
            new = [c for c in cands.neighbours(centre, self.paths) if c not in self.keys]
            for c in new:
                self._add(c, cands.support_of(c, self.paths), "")
            self._score_pending()
            best = self.keys[int(np.argmin(self.scores.mean(axis=1)))]
            if best == centre or not isinstance(best, tuple):
                break
            centre = best

    def _score_pending(self) -> None:
        pending = [k for k, row in enumerate(self.rows) if row is None]
        if not pending:
            return
        W = self.origins.n_windows
        coef = np.array([self._fold_coef(k, f) for k in pending for f in self.origins.fold])
        window = np.tile(np.arange(W), len(pending))
        scored = forecast_scores(self.setup, self.origins, coef, window, self.steps)
        for i, k in enumerate(pending):
            self.rows[k] = scored.score[i * W:(i + 1) * W]
            lead = scored.lead[i * W:(i + 1) * W]
            seen = np.isfinite(lead)
            self.curves[k] = np.sqrt(np.where(seen, lead, 0).sum(axis=0) /
                                     np.maximum(seen.sum(axis=0), 1))

    def _fold_coef(self, k: int, fold: int) -> np.ndarray:
        if self.keys[k] == "optimizer":
            if not self.fixed:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    self.fixed = cands.optimizer_fold_fits(self.optimizer, self.stats)
            return self.fixed[fold]
        return self.fits.coefficients(self.supports[k], fold)

    @property
    def scores(self) -> np.ndarray:
        return np.array(self.rows)

    @property
    def n_terms(self) -> list[int]:
        return [int(s.sum()) for s in self.supports]

    def standard_errors(self) -> np.ndarray:
        scores = self.scores
        return scores.std(axis=1, ddof=1) / np.sqrt(scores.shape[1])

    def final_coefficients(self, k: int) -> np.ndarray:
        if self.keys[k] in (self.start, "optimizer") and self.labels[k] != "prior alone":
            return np.array(self.optimizer.coef_, dtype=float)   # exactly the optimizer's
        return self.fits.coefficients(self.supports[k], None)

    def result(self, k: int) -> ForecastSelection:
        scores, o = self.scores, self.origins
        lead_rms = {"prior alone": self.curves[self.labels.index("prior alone")],
                    "chosen": self.curves[k]}
        times = o.h.sum(axis=1) if not self.setup.discrete_time else \
            np.full(o.n_windows, float(self.steps))
        return ForecastSelection(
            supports=self.supports, n_terms=self.n_terms,
            score=scores.mean(axis=1).tolist(), score_se=self.standard_errors().tolist(),
            labels=self.labels, window_scores=scores, chosen=k,
            horizon=int(self.steps * o.stride), horizon_time=float(np.median(times)),
            n_windows=int(o.n_windows), lead_rms=lead_rms,
            window_leads=(o.steps_held() * o.stride).tolist())
