"""The blind protocol: choose a dissipation fit from training data alone, then validate once.

Each candidate procedure (a :class:`DissipationDiscrepancy` with its library, fit and term
selection) is fitted on ``[0, origin)`` and forecasts the next ``horizon`` seconds, from
several origins inside the training part (rolling origin; the last window ends where
training ends). The procedure whose largest forecast error over the origins is lowest is
frozen and fitted on the whole training part before the validation part is touched (near
ties, within 2 %, go to the first candidate, so the simpler procedure listed first). The
largest error, not the median, decides: on the measured double pendulum the median chose a
law that forecast well from the three earliest origins and missed by 40-48 % from the two
latest, and then missed validation by 33 %; on simulated recordings both rules chose equally
well (see the energy-systems experiment). The spread of the chosen
procedure's own forecast errors, as a function of the lead time, is the error of the law's
form that a coefficient bootstrap does not see: :meth:`BlindFit.forecast_band` adds it.
Written here because no library does rolling-origin selection of constrained energy laws.
"""
from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..base import clone
from ..constraints import Integral, Interval, Real, check_argument
from ..data.trajectory import as_2d, as_times
from ..data.validation import check_array
from ..differentiation import SavitzkyGolay
from ..errors import ConvergenceError, DataError, ParameterError, SelectionWarning, ShapeError
from .dissipation import without_stribeck
from .dissipation_model import DissipationDiscrepancy
from .metrics import error_summary
from .record import PreparedRecording
from .smoothing import smoothing_scores

#: fewest training seconds a forecast origin leaves for the fit, as a share of training
MIN_FIT_SHARE = 0.3


@dataclass(frozen=True)
class BlindFit:
    """Result of :func:`blind_fit`.

    Attributes:
        chosen: name of the chosen procedure.
        model: the chosen procedure fitted on the whole training part.
        procedures: per candidate, its forecast errors (% of each window's ``dH`` range)
            from every origin, their median and largest (the score of the choice), the terms
            it fits on the whole training part,
            whether that law is sound and which constraints hold it at its bound.
        origins: forecast origins (s); horizon: forecast length (s).
        lead_errors: per procedure, its forecast errors relative to each window's ``dH``
            range, ``(n_origins, n_lead)``, sampled at ``lead_times`` (s).
        models: every procedure fitted on the whole training part.
        smoothing: when the smoothing was chosen from the training part
            (:func:`~discrepancy.energy.smoothing.choose_smoothing`), its window and degree
            and every candidate's score; ``None`` when the candidates brought their own.
        rest_from: the time (s) from which the training part is at rest (its energy stays
            put): the forecasts end there and the laws are fitted on the part before it,
            bounded by the whole training part; ``None`` when it moves to its end.
    """

    chosen: str
    procedures: dict
    origins: list
    horizon: float
    lead_times: np.ndarray = field(repr=False)
    lead_errors: dict = field(repr=False)
    models: dict = field(repr=False)
    smoothing: dict | None = None
    rest_from: float | None = None

    @property
    def model(self) -> DissipationDiscrepancy:
        """The chosen procedure fitted on the whole training part."""
        return self.models[self.chosen]

    @property
    def soundness(self) -> dict:
        """The chosen law checked on the training part: per joint, its largest torque over
        the limit and over the holding torque at the turning points, and the constraints
        active in its fit (``soundness_`` of :class:`~discrepancy.DissipationDiscrepancy`)."""
        return self.model.soundness_

    def restricted(self, names) -> BlindFit:
        """The same comparison with only the procedures ``names`` (e.g. without a library
        one wants to report beside the others): the choice among them, by the same rule."""
        names = list(names)
        unknown = set(names) - set(self.procedures)
        if not names or unknown:
            raise ParameterError(f"names must be procedures of this comparison; unknown: "
                                 f"{sorted(unknown) or 'none given'}")
        chosen = _choose({n: self.procedures[n] for n in names})
        return replace(self, chosen=chosen,
                       procedures={n: self.procedures[n] for n in names},
                       lead_errors={n: self.lead_errors[n] for n in names},
                       models={n: self.models[n] for n in names})

    def forecast_band(self, prediction: np.ndarray, t: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` around a forecast ``prediction`` (J) at times ``t`` (s, from the
        forecast's origin): the largest relative error the procedure made at each lead time
        from the origins inside training, scaled by the forecast's own ``dH`` range. With
        ``n`` origins it is a band of nominal level ``(n - 1) / (n + 1)``; check its coverage
        (the law's form error is not random noise)."""
        t = check_array("t", t, ndim=1)
        prediction = check_array("prediction", prediction, ndim=1, n_rows=len(t))
        if len(t) == 0:
            raise ShapeError("t must hold at least one time; got an empty array")
        lead = t - t[0]
        worst = np.max(np.abs(self.lead_errors[self.chosen]), axis=0)
        width = np.interp(lead, self.lead_times, worst, right=worst[-1]) * np.ptp(prediction)
        return prediction - width, prediction + width


#: fit windows compared by default, as shares of the training part (None: all of it)
WINDOWS = (None, 0.5, 0.3)


def default_procedures(model: DissipationDiscrepancy, training_seconds: float,
                       n_positions: int, *, libraries: Mapping | None = None
                       ) -> dict[str, DissipationDiscrepancy]:
    """The procedures compared by default, for the given model (its energy, smoothing and
    torque limit): each library of ``libraries`` (``{name: friction terms}``; default the
    model's library with and without its Stribeck terms) x the data fitted (all of it, or
    the most recent half or 30 %: the regime a forecast continues) x cumulative or
    per-block energy loss (blocks of 1/32 of the training part) x terms chosen by the elbow
    of the training error or by forecasting its last 20 %."""
    check_argument("training_seconds", training_seconds, Interval(Real, 0, None, closed="neither"))
    if libraries is None:
        terms = model._terms(n_positions)
        libraries = {"full library": terms, "no Stribeck": without_stribeck(terms)}
    block = training_seconds / 32
    out = {}
    for library, terms in libraries.items():
        for share in WINDOWS:
            window = "all data" if share is None else f"last {100 * share:g} %"
            for fit, seconds in (("cumulative", None), (f"{block:.3g} s blocks", block)):
                for selection, holdout in (("elbow", 0.0), ("hold-out 20 %", 0.2)):
                    out[f"{library}, {window}, {fit}, {selection}"] = clone(model).set_params(
                        block_seconds=seconds, holdout=holdout, friction_terms=list(terms),
                        fit_window=None if share is None else share * training_seconds)
    return out


def forecast_error(record, model: DissipationDiscrepancy, start: int, stop: int
                   ) -> tuple[np.ndarray, np.ndarray, dict]:
    """A model fitted on the prepared ``record`` continued over its samples ``[start, stop)``,
    anchored where its fitted data begin (as :meth:`DissipationDiscrepancy.anchored`):
    ``(times, error relative to the window's dH range, summary)``."""
    k0 = int(np.searchsorted(record.t, model.fit_start_))
    columns = [record.terms.index(term) for term in model.terms_]
    window = slice(start, stop)
    dh = record.delta_h[window] - record.delta_h[k0]
    pred = model.offset_ + (record.features[window][:, columns]
                            - record.features[k0, columns]) @ model.coef_
    scale = max(float(np.ptp(dh)), 1e-300)
    return record.t[window], (dh - pred) / scale, error_summary(dh, pred)


#: most forecast origins of a blind fit (each is one fit of every candidate)
MAX_ORIGINS = 100


def _origins(t, split, horizon, n_origins) -> list[int]:
    last = t[split] - horizon
    first = t[0] + MIN_FIT_SHARE * (t[split] - t[0])
    if last <= first:
        raise DataError(f"the training part ({t[split] - t[0]:.4g} s) is too short to "
                        f"forecast {horizon:.4g} s from inside it; give a shorter horizon")
    spacing = min(horizon / 2, (last - first) / max(n_origins - 1, 1))
    times = [last - spacing * i for i in reversed(range(n_origins))]
    return [int(np.searchsorted(t, o, side="right")) - 1 for o in times]  # at or before o


def _prepared(candidates, q, t, dq) -> dict:
    """One prepared recording per group of candidates that differentiate and measure energy
    alike (the library the union of theirs): ``{name: (record, edge)}``."""
    groups: dict = {}
    for name, model in candidates.items():
        key = (id(model.energy), id(model.differentiation_method),
               tuple(model.position_names or ()))
        groups.setdefault(key, []).append(name)
    out = {}
    for names in groups.values():
        first = candidates[names[0]]
        x, times = first.states(q, t, dq=dq)
        k = x.shape[1] // 2
        library = list(dict.fromkeys(term for n in names for term in candidates[n]._terms(k)))
        record = PreparedRecording(first._energy, x, times, library, first.variable_names(k))
        edge = int(np.searchsorted(t, times[0]))
        out.update({n: (record, edge) for n in names})
    return out


def blind_fit(candidates, q, t, *, split: int, dq=None, horizon: float | None = None,
              n_origins: int = 5, progress=None) -> BlindFit:
    """Choose among ``candidates`` by rolling-origin forecasts inside ``q[:split]`` only.

    Args:
        candidates: ``{name: unfitted DissipationDiscrepancy}``, or one model whose
            :func:`default_procedures` are compared (with, when that model leaves
            ``differentiation_method`` unset, the smoothing chosen on the training part by
            :func:`~discrepancy.energy.smoothing.choose_smoothing`).
        q, t, dq: the recording's positions ``(m, k)``, times (s) and optional velocities.
        split: index of the first validation sample; nothing from ``split`` on is read.
        horizon: forecast length (s); default the validation part's length, at most a third
            of the training part (of its moving part, when it comes to rest: ``rest_from``).
        n_origins: forecast origins, spaced ``horizon / 2`` apart at most, the last window
            ending at ``split`` (or where the training part comes to rest).
        progress: a progress bar over the procedures (tqdm); ``None``: only on a terminal.

    The training part is differentiated once and prepared once per group of candidates
    sharing energy and smoothing (:class:`~discrepancy.energy.PreparedRecording`); a fit
    from an origin uses the states of the samples before it, less the smoother's edge (with
    a global smoother such as ``Dequantised`` those states are smoothed with the whole
    training part, never with validation). Only procedures whose law is sound on the
    training part (``soundness_`` of :class:`~discrepancy.DissipationDiscrepancy`) can be
    chosen.
    """
    q = as_2d("q", q, allow_1d=True)
    t = as_times("t", t, len(q))
    check_argument("split", split, Interval(Integral, 10, len(q), closed="left"))
    if isinstance(n_origins, bool) or not isinstance(n_origins, (int, np.integer)) or \
            not 2 <= n_origins <= min(MAX_ORIGINS, split // 2):
        raise ParameterError(f"n_origins must be an integer in [2, "
                             f"{min(MAX_ORIGINS, split // 2)}] (one fit per origin and "
                             f"candidate, at most one origin per two training samples); got "
                             f"{n_origins!r}")
    if dq is not None:
        dq = as_2d("dq", dq, n_rows=len(q), n_cols=q.shape[1], allow_1d=True)[:split]
    validation, until_split = float(t[-1] - t[split]), float(t[split] - t[0])
    q, t = q[:split], t[:split]
    smoothing, base = None, None     # base: the model whose default procedures compete
    if isinstance(candidates, DissipationDiscrepancy):
        base = candidates
        if base.differentiation_method is None:
            base, smoothing = _with_smoothing(base, q, t)
    elif not isinstance(candidates, Mapping) or not candidates or not all(
            isinstance(c, DissipationDiscrepancy) for c in candidates.values()):
        raise ParameterError("candidates must be a non-empty mapping of names to "
                             f"DissipationDiscrepancy; got {candidates!r:.80}")
    moving = _moving_part(base if base is not None else next(iter(candidates.values())), q,
                          t, dq)
    training = float(t[moving - 1] - t[0])
    if base is not None:             # windows and blocks: shares of the training part
        candidates = default_procedures(base, until_split if moving == len(t) else training,
                                        q.shape[1])
    if horizon is None:
        horizon = min(validation, training / 3)
    else:
        check_argument("horizon (s)", horizon, Interval(Real, 0, training, closed="neither"))
    for candidate in candidates.values():
        candidate._validate_params()
    starts = _origins(t, moving - 1, float(horizon), n_origins)
    prepared = _prepared(candidates, q, t, dq)
    table, fitted, curves = {}, {}, {}
    for name, candidate in _progress(candidates.items(), progress):
        record, edge = prepared[name]
        errors, leads = [], []
        for start in starts:
            stop = int(np.searchsorted(t, t[start] + horizon, side="right"))
            model = clone(candidate).fit_prepared(record, start - 2 * edge, check=False)
            lead_t, rel, summary = forecast_error(
                record, model, int(np.searchsorted(record.t, t[start])),
                min(stop - 2 * edge, len(record.t)))
            errors.append(summary["max_abs_percent_of_range"])
            leads.append((lead_t - t[start], rel))
        final = clone(candidate).fit_prepared(
            record, int(np.searchsorted(record.t, t[moving - 1], side="right")),
            constrain_to=len(record.t))
        table[name] = {"forecast_errors_percent_of_range": errors,
                       "forecast_median_percent_of_range": float(np.median(errors)),
                       "forecast_worst_percent_of_range": float(np.max(errors)),
                       "terms": [term.name for term in final.terms_],
                       "sound": final.soundness_["sound"],
                       "active_constraints": final.soundness_["active_constraints"]}
        fitted[name], curves[name] = final, leads
    chosen = _choose(table)
    lead_times = np.linspace(0.0, horizon, 200)
    lead_errors = {name: np.array([np.interp(lead_times, lt, rel) for lt, rel in leads])
                   for name, leads in curves.items()}
    return BlindFit(chosen, table, [float(t[s]) for s in starts], float(horizon), lead_times,
                    lead_errors, fitted, smoothing,
                    None if moving == len(t) else float(t[moving - 1]))


#: the recording is at rest once ``H_m`` stays within this share of its training range of
#: its last value ...
REST_BAND = 1e-3
#: ... for at least this share of the training part (shorter stretches are not trimmed)
REST_SHARE = 0.1


def _moving_part(model: DissipationDiscrepancy, q, t, dq) -> int:
    """Samples of the training part ``q, t`` up to where it comes to rest (all of them when
    it moves on to the end): forecasts from where it rests score noise relative to a range
    of noise, and a fit on the last share of a record at rest fits no loss at all (on a
    pendulum held by friction from 8.6 s of 20 s, every procedure scored 120-50,000 % and
    the chosen law was 5 times too small). The states are smoothed again when the
    candidates' recordings are prepared (one smoothing pass; the candidates' windows
    depend on this answer)."""
    model._validate_params()
    x, times = model.states(q, t, dq=dq)
    h = model._energy(x)
    away = np.flatnonzero(np.abs(h - h[-1]) > REST_BAND * np.ptp(h))
    if not len(away) or times[-1] - times[away[-1]] < REST_SHARE * (t[-1] - t[0]):
        return len(t)
    end = int(np.searchsorted(t, times[away[-1]], side="right")) + 1
    warnings.warn(f"the training part is at rest from {t[end - 1]:.4g} s of "
                  f"{t[-1] - t[0]:.4g} s (its energy stays within {100 * REST_BAND:g} % of its "
                  "range): the forecasts and the fitted data end there; the whole training "
                  "part still bounds the laws", SelectionWarning, stacklevel=3)
    return end


def _with_smoothing(model, q, t):
    """``model`` with the smoothing chosen on ``q, t`` (the training part) and its record."""
    model._validate_params()
    scores = smoothing_scores(model._energy, q, t)
    if not scores:
        return model, None
    window, degree = min(scores, key=scores.get)
    chosen = SavitzkyGolay(window_length=window, polyorder=degree)
    return clone(model).set_params(differentiation_method=chosen), {
        "window_length": window, "polyorder": degree,
        "chosen_by": "least RMS wiggle of dH about its 1 s moving average (training part)",
        "wiggle_J": {f"{w}/{d}": v for (w, d), v in scores.items()}}


#: the score a procedure is chosen by (its largest forecast error over the origins)
SCORE = "forecast_worst_percent_of_range"
#: procedures whose score is within this fraction of the best tie; the
#: first of them in the candidates' order (all data before windows, simpler fits first) wins
TIE = 0.02


def _choose(table: dict) -> str:
    """The procedure of lowest ``SCORE`` among those with a sound law (ties:
    the first); :class:`~discrepancy.errors.ConvergenceError` if no law is sound."""
    sound = {name: row for name, row in table.items() if row["sound"]}
    if not sound:
        raise ConvergenceError(f"no candidate procedure gave a sound law (each exceeds the "
                               f"torque limit or the holding torque at a turning point): "
                               f"{sorted(table)[:3]}...; keep torque_limit='auto' and "
                               "turning_points=True")
    best = min(row[SCORE] for row in sound.values())
    return next(name for name, row in sound.items() if row[SCORE] <= best * (1 + TIE))


def _progress(items, progress):
    from tqdm.auto import tqdm

    return tqdm(list(items), desc="procedures", disable=None if progress is None else
                not progress)
