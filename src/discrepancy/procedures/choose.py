"""Libraries and procedures chosen by forecasts inside the training data.

:func:`choose_procedure` generalises the energy module's blind protocol to any
``DiscrepancyModel``: every candidate (a library, or a whole unfitted model: library,
smoothing, optimizer, constraints) and the prior alone is fitted on the first part of every
record and forecasts what follows, from several origins (rolling origin: the first part
grows, the last forecast ends where the data end). The candidate with the best mean
forecast wins by the one-standard-error rule over the origins, the fewest terms first among
ties, and is fitted on all the data. Nothing but the data given is read, so a test record
kept apart stays unseen.

Forecasts: with every state measured (``fit``), from the state at the origin over the
horizon (a quarter of the shortest record unless given), scored as the model's own
selection scores them (the initial state fitted to the window, each window until the
prior's sensitivity to its start saturates, :mod:`discrepancy.selection.forecast`).
With outputs (``fit_outputs``), the fitted simulation continues past the origin and its
outputs are scored to the end of each record (as the benchmarks score a model).

Cost of output fits: each candidate's output-error path runs once, before the first
origin (:mod:`.output_forecasts`).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from ..base import clone
from ..constraints import Integral, Interval, check_argument
from ..data.trajectory import as_trajectories
from ..errors import ConvergenceError, ParameterError, describe
from ..fitting.setup import resolve_names
from ..hybrid.outputs import OutputMap
from ..libraries import FeatureLibrary
from ..models import DiscrepancyModel
from ..models.outputs.output_checks import prior_states, state_count
from ..optimizers.selection import one_standard_error
from ..selection.candidate_libraries import default_libraries
from ..selection.choice import TOLERANCE
from .judges import FIRST_ORIGIN, HORIZON_SHARE, StateForecasts
from .output_forecasts import OutputForecasts


@dataclass
class ProcedureChoice:
    """Result of :func:`choose_procedure`.

    Attributes:
        chosen: name of the chosen candidate; model: it, fitted on all the data.
        scores: per candidate ``{"forecast_errors": [per origin], "mean", "se", "n_terms"
            (fitted on the largest training part), "prior_only"}``; errors are mean scaled
            squared errors (each state or output divided by its standard deviation).
        origins: each origin as a share of the records; horizon: forecast length in samples
            (``None``: to each record's end).
    """

    chosen: str
    model: object = field(repr=False)
    scores: dict = field(repr=False)
    origins: list = field(default_factory=list)
    horizon: int | None = None

    def table(self) -> str:
        """A text table, one line per candidate: its name, terms, mean forecast error (scaled
        squared error) and standard error over the origins, the chosen one marked."""
        lines = [f"{'candidate':<32} {'terms':>5} {'forecast error':>14} {'± s.e.':>9}"]
        for name, row in self.scores.items():
            mark = "  <- chosen" if name == self.chosen else ""
            lines.append(f"{name:<32} {row['n_terms']:>5} {row['mean']:>14.5g} "
                         f"{row['se']:>9.2g}{mark}")
        return "\n".join(lines)


def choose_procedure(model, x, t=None, *, u=None, candidates=None, outputs=None,
                     n_origins: int = 3, horizon: int | None = None, fit_kws=None,
                     progress: bool | None = None) -> ProcedureChoice:
    """Choose a library or procedure for ``model`` by forecasts inside ``x``.

    Args:
        model: an unfitted :class:`~discrepancy.DiscrepancyModel` (its prior and the
            parameters candidates do not set).
        x: states ``(m, n)``, or outputs when ``outputs`` is given; or a list of records.
        t, u: as for ``fit``.
        candidates: ``{name: FeatureLibrary, library spec or unfitted DiscrepancyModel}``;
            default :func:`~discrepancy.selection.default_libraries` of the data and prior.
            The prior alone is always added (``"prior alone"``).
        outputs: what ``x`` measures (then every candidate is fitted by ``fit_outputs``).
        n_origins: forecast origins (at least 2), from half of every record on.
        horizon: forecast length in samples (state fits; default a quarter of the shortest
            record; each window is scored until the prior's sensitivity to its initial state
            says forecasts stop meaning anything, as in the model's own selection).
        fit_kws: further keyword arguments of ``fit`` or ``fit_outputs``.
    """
    records = as_trajectories(x, t, u, x_name="x" if outputs is None else "y")
    check_argument("n_origins", n_origins, Interval(Integral, 2))
    fit_kws = dict(fit_kws or {})
    templates = _templates(model, candidates, records, outputs, fit_kws)
    shortest = min(r.n_samples for r in records)
    share = HORIZON_SHARE if outputs is not None or horizon is None else horizon / shortest
    if not 0 < share < 1 - FIRST_ORIGIN:
        raise ParameterError(f"horizon must be a number of samples below "
                             f"{int(shortest * (1 - FIRST_ORIGIN))}; got {horizon!r}")
    fractions = np.linspace(FIRST_ORIGIN, 1 - share, n_origins)
    judge = OutputForecasts(records, outputs, fit_kws) if outputs is not None else \
        StateForecasts(records, fit_kws, horizon)
    scores, fitted = {}, {}
    for name, template in tqdm(list(templates.items()), desc="procedures",
                               disable=None if progress is None else not progress):
        errors, last = [], None
        for f in fractions:
            errors.append(judge.score(template, f))
            last = judge.last
        scores[name] = {"forecast_errors": errors, "mean": float(np.mean(errors)),
                        "se": float(np.std(errors, ddof=1) / np.sqrt(len(errors))),
                        "n_terms": 0 if last is None else int(np.count_nonzero(last.coef_)),
                        "prior_only": last is None or bool(last.prior_only_)}
        fitted[name] = template
    names = list(scores)
    mean = np.array([scores[k]["mean"] for k in names])
    se = np.array([scores[k]["se"] for k in names])
    finite = np.isfinite(mean)
    if not finite.any():
        raise ConvergenceError("every candidate's forecasts diverged on these data")
    mean = np.where(finite, mean, np.inf)
    margin = np.maximum(np.nan_to_num(se, nan=0.0), TOLERANCE * mean[finite].min())
    pick = names[one_standard_error(mean, margin, [scores[k]["n_terms"] for k in names])]
    final = judge.fit(fitted[pick], 1.0)
    return ProcedureChoice(pick, final, scores, fractions.tolist(), judge.horizon)


def _templates(model, candidates, records, outputs, fit_kws) -> dict:
    if not isinstance(model, DiscrepancyModel) or hasattr(model, "coef_"):
        raise ParameterError(f"model must be an unfitted DiscrepancyModel; got "
                             f"{describe(model)}")
    if candidates is None:
        first = records[0]
        r = 0 if first.u is None else first.u.shape[1]
        n = first.x.shape[1] if outputs is None else state_count(model)
        states = resolve_names("state_names", model.state_names, n, "x", one=None)
        inputs = resolve_names("input_names", model.input_names, r, "u", one="u")
        x = _variables_with_data(model, records, states, outputs, fit_kws)
        u = None if first.u is None else np.vstack([rec.u for rec in records])
        candidates = default_libraries(states, inputs, x, u, prior=model.prior)
    if not isinstance(candidates, Mapping) or not candidates:
        raise ParameterError(f"candidates must be a non-empty mapping of names to libraries "
                             f"or unfitted DiscrepancyModels; got {describe(candidates)}")
    out = {"prior alone": clone(model).set_params(optimizer="prior_only", selection="auto")}
    for name, c in candidates.items():
        if isinstance(c, (FeatureLibrary, str)):
            out[str(name)] = clone(model).set_params(feature_library=c)
        elif isinstance(c, DiscrepancyModel) and not hasattr(c, "coef_"):
            out[str(name)] = clone(c)
        else:
            raise ParameterError(f"candidates[{name!r}] must be a FeatureLibrary, a library "
                                 f"spec or an unfitted DiscrepancyModel; got {describe(c)}")
    return out


def _variables_with_data(model, records, states, outputs, fit_kws):
    """States ``(m, n)``: measured, or (output fits) the measured ones where an output is
    a state and the others along the prior's simulation (:func:`prior_states`)."""
    if outputs is None:
        return np.vstack([r.x for r in records])
    y = [r.x for r in records]
    x = prior_states(model, y, [r.t for r in records],
                     None if records[0].u is None else [r.u for r in records],
                     outputs=outputs, **{**fit_kws, "x0": _per_record(fit_kws, records)})
    out_map = OutputMap(outputs, states)
    if out_map.selected is not None:
        for k, i in enumerate(out_map.selected):
            x[:, i] = np.concatenate([rec[:, k] for rec in y])
    return x


def _per_record(fit_kws, records):
    x0 = fit_kws.get("x0")
    if x0 is None or np.ndim(x0) != 1:
        return x0
    return [np.asarray(x0, float)] * len(records)
