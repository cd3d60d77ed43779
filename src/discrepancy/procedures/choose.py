"""Libraries and procedures chosen by forecasts inside the training data.

:func:`choose_procedure` generalises the energy module's blind protocol to any
``DiscrepancyModel``: every candidate (a library, or a whole unfitted model: library,
smoothing, optimizer, constraints) and the prior alone is fitted on the first part of every
record and forecasts what follows, from several origins (rolling origin: the first part
grows, the last forecast ends where the data end). The candidates are entered in rounds:

1. the candidates given (default :func:`~discrepancy.selection.default_libraries`) and the
   prior alone;
2. (``join``) the union of the two libraries that forecast best, when both forecast better
   than the prior alone: a system may miss two kinds of physics at once (a tank's outflow
   law and its overflow), which no single family holds;
3. with outputs and inputs, when ``fit_kws`` leaves ``u_hold`` to the procedure, the best
   candidate so far simulated with each other input hold (how the input moves between
   samples is part of the procedure: a band-limited input between samples is neither a
   straight line nor a step).

The candidate with the best mean forecast over every round wins by the one-standard-error
rule over the origins, the fewest terms first among ties (the most that any origin's fit
kept), then the default input hold (another hold must forecast better by more than a
standard error), then the smaller library
(a union whose terms all come from one of its parts is that part), and its whole procedure
is run again on all the data. With states, when that keeps more terms than any fit the
forecasts scored, the scored support (of the fit on the largest part) is refitted on all the
data instead. With outputs, its scored support (the fit the forecasts scored) is also
refined on all the data, and taken instead when it fits them better with no more terms
(``final_route`` says which). Nothing but the data given is read, so a test record
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

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

from ..base import clone
from ..constraints import Integral, Interval, Options, Predicate, check_argument
from ..data.trajectory import as_trajectories
from ..errors import ConvergenceError, ParameterError, PriorOnlyWarning, describe
from ..fitting.setup import resolve_names
from ..hybrid.inputs import DEFAULT_HOLD, HOLDS
from ..hybrid.outputs import OutputMap
from ..libraries import FeatureLibrary
from ..models import DiscrepancyModel
from ..models.outputs.output_checks import prior_states, state_count
from ..optimizers.selection import one_standard_error
from ..selection.candidate_libraries import default_libraries
from ..selection.choice import TOLERANCE
from .judges import FIRST_ORIGIN, HORIZON_SHARE, WHOLE, StateForecasts
from .output_forecasts import OutputForecasts


@dataclass
class ProcedureChoice:
    """Result of :func:`choose_procedure`.

    Attributes:
        chosen: name of the chosen candidate; model: it, fitted on all the data.
        scores: per candidate ``{"forecast_errors": [per origin], "mean", "se", "n_terms"
            (fitted on the largest training part), "n_terms_per_origin", "library_size" (its
            candidate terms, states x features; 0 for the prior alone), "prior_only" (every
            origin's fit was the prior alone), "round"}``; errors are mean
            scaled squared errors (each state or output divided by its standard deviation);
            ``round`` says where the candidate came from (``"given"``, ``"joined"`` or
            ``"input hold"``, module doc).
        settings: the chosen procedure's fit keyword arguments (``fit_kws`` with the chosen
            ``u_hold``): simulate the model with the same ``u_hold`` and ``substeps``.
        origins: each origin as a share of the records; horizon: forecast length in samples
            (``None``: to each record's end).
        final_route: how ``model`` was fitted on all the data (module doc).
    """

    chosen: str
    model: object = field(repr=False)
    scores: dict = field(repr=False)
    settings: dict = field(default_factory=dict, repr=False)
    origins: list = field(default_factory=list)
    horizon: int | None = None
    final_route: str = WHOLE

    def table(self) -> str:
        """A text table, one line per candidate: its name, terms, mean forecast error (scaled
        squared error) and standard error over the origins, the chosen one marked; then
        how many terms the chosen model, fitted on all the data, kept, and how it was
        fitted."""
        lines = [f"{'candidate':<40} {'terms':>5} {'forecast error':>14} {'± s.e.':>9}"]
        for name, row in self.scores.items():
            mark = "  <- chosen" if name == self.chosen else ""
            lines.append(f"{name:<40} {row['n_terms']:>5} {row['mean']:>14.5g} "
                         f"{row['se']:>9.2g}{mark}")
        return "\n".join([*lines, f"the chosen model: {self.final_route}, "
                                  f"{self.model.complexity} terms (the table's are of the "
                                  "fit on the largest part)"])


#: forecast origins by default, as the energy blind fit's: the one-standard-error rule needs
#: a standard error, and three origins (the default before) gave it from two degrees of
#: freedom
N_ORIGINS = 5
#: the name of the candidate that is the prior alone (always entered, first)
PRIOR = "prior alone"
#: ``holds=``: a list of input holds
HOLD_LISTS = Predicate(lambda v: isinstance(v, (list, tuple)) and all(h in HOLDS for h in v),
                       "a list of them")


def choose_procedure(model, x, t=None, *, u=None, candidates=None, outputs=None,
                     n_origins: int = N_ORIGINS, horizon: int | None = None, fit_kws=None,
                     join: bool = True, holds=None,
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
        n_origins: forecast origins (at least 2), from half of every record on (default 5,
            as the energy blind fit's).
        horizon: forecast length in samples (state fits; default a quarter of the shortest
            record; each window is scored until the prior's sensitivity to its initial state
            says forecasts stop meaning anything, as in the model's own selection).
        fit_kws: further keyword arguments of ``fit`` or ``fit_outputs``. With outputs and
            inputs, a ``u_hold`` left out here is chosen too (module doc).
        join: also score the union of the two libraries that forecast best (module doc).
        holds: the input holds the last round may try (default every one of
            :data:`~discrepancy.hybrid.inputs.HOLDS`; the default hold, the candidates' own,
            is always scored); fewer save run time where a hold is known not to suit the
            data (e.g. a quick test).
    """
    records = as_trajectories(x, t, u, x_name="x" if outputs is None else "y")
    check_argument("n_origins", n_origins, Interval(Integral, 2))
    check_argument("join", join, bool)
    check_argument("holds", holds, None, Options(HOLDS), HOLD_LISTS)
    holds = HOLDS if holds is None else (holds,) if isinstance(holds, str) else holds
    fit_kws = dict(fit_kws or {})
    templates = _templates(model, candidates, records, outputs, fit_kws)
    shortest = min(r.n_samples for r in records)
    share = HORIZON_SHARE if outputs is not None or horizon is None else horizon / shortest
    if not 0 < share < 1 - FIRST_ORIGIN:
        raise ParameterError(f"horizon must be a number of samples below "
                             f"{int(shortest * (1 - FIRST_ORIGIN))}; got {horizon!r}")
    contest = _Contest(records, outputs, fit_kws, horizon,
                       np.linspace(FIRST_ORIGIN, 1 - share, n_origins), progress)
    contest.enter(templates, "given")
    if join:
        names = [n for group in _names(model, records, outputs) for n in group]
        contest.enter(_joined(templates, contest.scores, names), "joined")
    if outputs is not None and records[0].u is not None and "u_hold" not in fit_kws:
        pick = contest.pick()
        for hold in holds:
            if hold != DEFAULT_HOLD:
                contest.enter({f"{pick}, u_hold={hold}": contest.entries[pick][0]},
                              "input hold", {**fit_kws, "u_hold": hold})
    pick = contest.pick()
    template, settings = contest.entries[pick]
    final, route = contest.judge(settings).final(template, contest.supports[pick])
    if pick == PRIOR:
        warnings.warn("no candidate forecast better than the prior alone inside the data "
                      "given: the model is the prior alone (choice.model.prior_only_ is True; "
                      "choice.table() has every candidate's score)", PriorOnlyWarning,
                      stacklevel=2)
    return ProcedureChoice(pick, final, contest.scores, settings,
                           contest.fractions.tolist(), contest.judge(settings).horizon, route)


class _Contest:
    """Candidates entered in rounds, each fitted and scored from every origin by the judge
    of its fit settings; :meth:`pick` applies the one-standard-error rule to all of them."""

    def __init__(self, records, outputs, fit_kws, horizon, fractions, progress):
        self.records, self.outputs, self.fit_kws = records, outputs, fit_kws
        self.horizon, self.fractions = horizon, fractions
        self.disable = None if progress is None else not progress
        self.entries, self.scores, self.supports, self._judges = {}, {}, {}, {}

    def judge(self, settings):
        key = settings.get("u_hold")
        if key not in self._judges:
            self._judges[key] = (OutputForecasts(self.records, self.outputs, settings)
                                 if self.outputs is not None else
                                 StateForecasts(self.records, settings, self.horizon))
        return self._judges[key]

    def enter(self, templates, round_name, settings=None):
        """Score ``templates`` (name -> unfitted model), fitted with ``settings`` (default
        the ``fit_kws`` given)."""
        settings = self.fit_kws if settings is None else settings
        for name, template in tqdm(list(templates.items()), desc=f"procedures ({round_name})",
                                   disable=self.disable):
            judge, errors, fits = self.judge(settings), [], []
            for f in self.fractions:
                errors.append(judge.score(template, f))
                fits.append(judge.last)
            supports = [None if m is None else m.coef_ != 0 for m in fits]
            terms = [0 if s is None else int(s.sum()) for s in supports]
            corrected = [m for m in fits if m is not None and not m.prior_only_]
            self.scores[name] = {
                "forecast_errors": errors, "mean": float(np.mean(errors)),
                "se": float(np.std(errors, ddof=1) / np.sqrt(len(errors)))
                if np.isfinite(errors).all() else float("nan"),
                "n_terms": terms[-1], "n_terms_per_origin": terms,
                "library_size": int(corrected[0].coef_.size) if corrected else 0,
                "prior_only": not corrected, "round": round_name}
            self.entries[name] = (template, settings)
            self.supports[name] = supports

    def pick(self) -> str:
        names = list(self.scores)
        mean = np.array([self.scores[k]["mean"] for k in names])
        se = np.array([self.scores[k]["se"] for k in names])
        finite = np.isfinite(mean)
        if not finite.any():
            raise ConvergenceError("every candidate's forecasts diverged on these data")
        mean = np.where(finite, mean, np.inf)
        margin = np.maximum(np.nan_to_num(se, nan=0.0), TOLERANCE * mean[finite].min())
        # simplest first: fewest terms (the most any origin's fit kept: a candidate whose
        # last fit fell back to the prior alone but whose earlier ones corrected it is not
        # the prior alone), then the default input hold, then the smaller library (a union
        # that kept only one library's terms is that library), then the prior alone itself
        # (a candidate whose fits all fell back to it is no other model)
        sizes = [(max(self.scores[k]["n_terms_per_origin"]),
                  self.entries[k][1].get("u_hold", DEFAULT_HOLD) != DEFAULT_HOLD,
                  self.scores[k]["library_size"], k != PRIOR)
                 for k in names]
        return names[one_standard_error(mean, margin, sizes)]


def _joined(templates, scores, names) -> dict:
    """The union of the two candidates whose libraries forecast best, when both forecast
    better than the prior alone, with the better one's other settings; none when one
    library holds the other. Name: their names' parts, each once (of the polynomials only
    the highest degree, ``linear`` left out beside one). ``names``: the variables the
    libraries are made of."""
    prior = scores[PRIOR]["mean"]
    ranked = sorted((scores[k]["mean"], k) for k, m in templates.items()
                    if k != PRIOR and scores[k]["mean"] < prior
                    and isinstance(m.feature_library, FeatureLibrary))
    if len(ranked) < 2:
        return {}
    (_, a), (_, b) = ranked[:2]
    parts = list(dict.fromkeys([*a.split(" + "), *b.split(" + ")]))
    degrees = [p for p in parts if p.startswith("polynomial ")]
    if degrees:             # the highest degree holds the lower ones and the linear terms
        top = max(degrees, key=_degree)
        parts = [p for p in parts if p == top or (p != "linear" and p not in degrees)]
    first, second = templates[a].feature_library, templates[b].feature_library
    library = first + second
    if _width(library, names) == max(_width(first, names), _width(second, names)):
        return {}                                   # one library holds the other
    return {" + ".join(parts): clone(templates[a]).set_params(feature_library=library)}


def _degree(part: str) -> int:
    """The degree of a name part ``"polynomial <degree>"`` (0 when it names none)."""
    last = part.split()[-1]
    return int(last) if last.isdigit() else 0


def _width(library, names) -> int:
    """Number of terms ``library`` makes of the variables ``names``."""
    return len(clone(library).fit(names).get_feature_names())


def _templates(model, candidates, records, outputs, fit_kws) -> dict:
    if not isinstance(model, DiscrepancyModel) or hasattr(model, "coef_"):
        raise ParameterError(f"model must be an unfitted DiscrepancyModel; got "
                             f"{describe(model)}")
    if candidates is None:
        states, inputs = _names(model, records, outputs)
        x = _variables_with_data(model, records, states, outputs, fit_kws)
        u = None if records[0].u is None else np.vstack([rec.u for rec in records])
        candidates = default_libraries(states, inputs, x, u, prior=model.prior)
    if not isinstance(candidates, Mapping) or not candidates:
        raise ParameterError(f"candidates must be a non-empty mapping of names to libraries "
                             f"or unfitted DiscrepancyModels; got {describe(candidates)}")
    out = {PRIOR: clone(model).set_params(optimizer="prior_only", selection="auto")}
    for name, c in candidates.items():
        if isinstance(c, (FeatureLibrary, str)):
            out[str(name)] = clone(model).set_params(feature_library=c)
        elif isinstance(c, DiscrepancyModel) and not hasattr(c, "coef_"):
            out[str(name)] = clone(c)
        else:
            raise ParameterError(f"candidates[{name!r}] must be a FeatureLibrary, a library "
                                 f"spec or an unfitted DiscrepancyModel; got {describe(c)}")
    return out


def _names(model, records, outputs) -> tuple[list, list]:
    """The model's state and input names for these records (defaults where unset)."""
    first = records[0]
    r = 0 if first.u is None else first.u.shape[1]
    n = first.x.shape[1] if outputs is None else state_count(model)
    return (resolve_names("state_names", model.state_names, n, "x", one=None),
            resolve_names("input_names", model.input_names, r, "u", one="u"))


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
