"""The blind protocol: choose a dissipation fit from training data alone, then validate once.

Each candidate procedure (a :class:`DissipationDiscrepancy` with its library, fit and term
selection) is fitted on ``[0, origin)`` and forecasts the next ``horizon`` seconds, from
several origins inside the training part (rolling origin; the last window ends where
training ends). The procedure with the lowest median forecast error is frozen and fitted on
the whole training part before the validation part is touched (near ties, within 2 %, go to
the first candidate, so the simpler procedure listed first). The spread of the chosen
procedure's own forecast errors, as a function of the lead time, is the error of the law's
form that a coefficient bootstrap does not see: :meth:`BlindFit.forecast_band` adds it.
Written here because no library does rolling-origin selection of constrained energy laws.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ..data.trajectory import as_2d, as_times
from ..errors import DataError, ParameterError
from .dissipation import without_stribeck
from .dissipation_model import DissipationDiscrepancy
from .metrics import error_summary


def clone(model: DissipationDiscrepancy) -> DissipationDiscrepancy:
    """An unfitted copy with the same parameters."""
    return type(model)(**model.get_params(deep=False))


#: fewest training seconds a forecast origin leaves for the fit, as a share of training
MIN_FIT_SHARE = 0.3


@dataclass(frozen=True)
class BlindFit:
    """Result of :func:`blind_fit`.

    Attributes:
        chosen: name of the chosen procedure.
        model: the chosen procedure fitted on the whole training part.
        procedures: per candidate, its forecast errors (% of each window's ``dH`` range)
            from every origin, their median and the terms it fits on the whole training part.
        origins: forecast origins (s); horizon: forecast length (s).
        lead_errors: per procedure, its forecast errors relative to each window's ``dH``
            range, ``(n_origins, n_lead)``, sampled at ``lead_times`` (s).
        models: every procedure fitted on the whole training part.
    """

    chosen: str
    procedures: dict
    origins: list
    horizon: float
    lead_times: np.ndarray = field(repr=False)
    lead_errors: dict = field(repr=False)
    models: dict = field(repr=False)

    @property
    def model(self) -> DissipationDiscrepancy:
        """The chosen procedure fitted on the whole training part."""
        return self.models[self.chosen]

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
        lead = np.asarray(t, float) - float(t[0])
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


def forecast_error(model: DissipationDiscrepancy, q, t, start: int, *, dq=None
                   ) -> tuple[np.ndarray, np.ndarray, dict]:
    """A fit on ``[0, start)`` continued over ``q[start:]``: ``(times, relative error, summary)``
    with the error relative to the window's ``dH`` range."""
    x, times = model.states(q, t, dq=dq)
    k = int(np.searchsorted(times, t[start]))
    dh, pred = model.anchored(x, times)
    scale = max(float(np.ptp(dh[k:])), 1e-300)
    return times[k:], (dh[k:] - pred[k:]) / scale, error_summary(dh[k:], pred[k:])


def _origins(t, split, horizon, n_origins) -> list[int]:
    last = t[split] - horizon
    first = t[0] + MIN_FIT_SHARE * (t[split] - t[0])
    if last <= first:
        raise DataError(f"the training part ({t[split] - t[0]:.4g} s) is too short to "
                        f"forecast {horizon:.4g} s from inside it; give a shorter horizon")
    spacing = min(horizon / 2, (last - first) / max(n_origins - 1, 1))
    times = [last - spacing * i for i in reversed(range(n_origins))]
    return [int(np.searchsorted(t, o, side="right")) - 1 for o in times]  # at or before o


def blind_fit(candidates, q, t, *, split: int, dq=None, horizon: float | None = None,
              n_origins: int = 5, progress=None) -> BlindFit:
    """Choose among ``candidates`` by rolling-origin forecasts inside ``q[:split]`` only.

    Args:
        candidates: ``{name: unfitted DissipationDiscrepancy}``, or one model whose
            :func:`default_procedures` are compared.
        q, t, dq: the recording's positions ``(m, k)``, times (s) and optional velocities.
        split: index of the first validation sample; nothing from ``split`` on is read.
        horizon: forecast length (s); default the validation part's length, at most a third
            of the training part.
        n_origins: forecast origins, spaced ``horizon / 2`` apart at most, the last window
            ending at ``split``.
        progress: a progress bar over the procedures (tqdm); ``None``: only on a terminal.
    """
    q = as_2d("q", q, allow_1d=True)
    t = as_times("t", t, len(q))
    if not isinstance(split, (int, np.integer)) or not 10 <= split < len(q):
        raise ParameterError(f"split must be a sample index in [10, {len(q)}); got {split!r}")
    if isinstance(candidates, DissipationDiscrepancy):
        candidates = default_procedures(candidates, float(t[split] - t[0]), q.shape[1])
    if not isinstance(candidates, Mapping) or not candidates or not all(
            isinstance(c, DissipationDiscrepancy) for c in candidates.values()):
        raise ParameterError("candidates must be a non-empty mapping of names to "
                             f"DissipationDiscrepancy; got {candidates!r:.80}")
    if not isinstance(n_origins, (int, np.integer)) or n_origins < 2:
        raise ParameterError(f"n_origins must be an integer >= 2; got {n_origins!r}")
    if dq is not None:
        dq = as_2d("dq", dq, n_rows=len(q), n_cols=q.shape[1], allow_1d=True)[:split]
    validation = float(t[-1] - t[split])
    q, t = q[:split], t[:split]
    training = float(t[-1] - t[0])
    if horizon is None:
        horizon = min(validation, training / 3)
    elif not isinstance(horizon, (int, float)) or not 0 < horizon < training:
        raise ParameterError(f"horizon must be a length in (0, {training:.4g}) s; got "
                             f"{horizon!r}")
    starts = _origins(t, len(t) - 1, float(horizon), n_origins)
    table, fitted, curves = {}, {}, {}
    for name, candidate in _progress(candidates.items(), progress):
        errors, leads = [], []
        for start in starts:
            stop = int(np.searchsorted(t, t[start] + horizon, side="right"))
            model = clone(candidate).fit(q[:start], t[:start],
                                         dq=None if dq is None else dq[:start])
            lead_t, rel, summary = forecast_error(model, q[:stop], t[:stop], start,
                                                  dq=None if dq is None else dq[:stop])
            errors.append(summary["max_abs_percent_of_range"])
            leads.append((lead_t - t[start], rel))
        final = clone(candidate).fit(q, t, dq=dq)
        table[name] = {"forecast_errors_percent_of_range": errors,
                       "forecast_median_percent_of_range": float(np.median(errors)),
                       "terms": [term.name for term in final.terms_]}
        fitted[name], curves[name] = final, leads
    chosen = _choose(table)
    lead_times = np.linspace(0.0, horizon, 200)
    lead_errors = {name: np.array([np.interp(lead_times, lt, rel) for lt, rel in leads])
                   for name, leads in curves.items()}
    return BlindFit(chosen, table, [float(t[s]) for s in starts], float(horizon), lead_times,
                    lead_errors, fitted)


#: procedures whose median forecast error is within this fraction of the best tie; the
#: first of them in the candidates' order (all data before windows, simpler fits first) wins
TIE = 0.02


def _choose(table: dict) -> str:
    best = min(row["forecast_median_percent_of_range"] for row in table.values())
    return next(name for name, row in table.items()
                if row["forecast_median_percent_of_range"] <= best * (1 + TIE))


def _progress(items, progress):
    from tqdm.auto import tqdm

    return tqdm(list(items), desc="procedures", disable=None if progress is None else
                not progress)
