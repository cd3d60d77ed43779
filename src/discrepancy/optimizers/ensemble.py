"""Ensembles of sparse regressions: bagging over samples and over library terms.

PySINDy's ``EnsembleOptimizer``: ``n_models`` fits of an inner optimizer, each on the samples
drawn with (or without) replacement (``bagging``) and/or on the library without
``n_candidates_to_drop`` random terms (``library_ensemble``); the coefficients are
aggregated (the median by default) and how often each term was kept is its inclusion
probability. Every fit is a resampled :class:`GramStatistics` (the machinery the model's
bootstrap uses, :mod:`discrepancy.optimizers.resampling`): dropping terms takes rows and
columns of ``ΘᵀΘ`` (so library ensembles stream), and a bag of samples is ``Θᵀ diag(c) Θ``
for the draw counts ``c`` (which needs the rows, kept in memory for it). The folds come
along, so an inner ``STLSQ(threshold="auto")`` cross-validates in every member.

Draws follow PySINDy's, one model after the other (the samples, then the terms, each with
``choice``): ``random_state=None`` uses numpy's global generator as PySINDy does (after
``np.random.seed(s)`` both libraries draw the same ensembles), an integer seeds a
``RandomState`` that draws the same.
"""
from __future__ import annotations

import copy
import warnings
from collections.abc import Callable, Mapping

import numpy as np

from ..constraints import InstanceOf, Integral, Interval, Predicate
from ..errors import ParameterError, ShapeError, describe
from .base import Optimizer, get_optimizer, register
from .resampling import restricted

_SEED = [None, Interval(Integral, 0, None),
         InstanceOf((np.random.RandomState, np.random.Generator), "a numpy random generator")]


@register("ensemble")
class EnsembleOptimizer(Optimizer):
    """Median (or ``ensemble_aggregator``) of ``n_models`` fits of ``opt`` on resamples.

    Args:
        opt: the inner optimizer (default: ``STLSQ(threshold="auto")``).
        bagging: draw ``n_subset`` samples per model (with replacement when ``replace``;
            default ``n_subset``: all samples with replacement, 60 % without).
        library_ensemble: leave ``n_candidates_to_drop`` random terms out of each model.
        n_models: models in the ensemble.
        ensemble_aggregator: ``f(list of (n, p) arrays) -> (n, p)`` (default: median).
        random_state: None (numpy's global generator, as PySINDy), a seed or a generator.

    After fitting: ``coef_list_`` ``(n_models, n, p)`` (``coef_list``, PySINDy's name),
    ``inclusion_probability_`` ``(n, p)`` (the fraction of models keeping each term).
    Bagging needs the samples (in-memory fits); library ensembles stream.
    """

    def __init__(self, opt: Optimizer | None = None, *, bagging: bool = False,
                 library_ensemble: bool = False, n_models: int = 20, n_subset: int | None = None,
                 n_candidates_to_drop: int = 1, replace: bool = True,
                 ensemble_aggregator: Callable | None = None, random_state=None):
        self.opt = opt
        self.bagging = bagging
        self.library_ensemble = library_ensemble
        self.n_models = n_models
        self.n_subset = n_subset
        self.n_candidates_to_drop = n_candidates_to_drop
        self.replace = replace
        self.ensemble_aggregator = ensemble_aggregator
        self.random_state = random_state

    _parameter_constraints = {
        "opt": [None, InstanceOf(Optimizer, "an Optimizer"),
                Predicate(lambda v: isinstance(v, (str, Mapping)), "an optimizer spec")],
        "bagging": [bool],
        "library_ensemble": [bool], "n_models": [Interval(Integral, 1, None)],
        "n_subset": [None, Interval(Integral, 1, None)],
        "n_candidates_to_drop": [Interval(Integral, 1, None)], "replace": [bool],
        "ensemble_aggregator": [None, Predicate(callable, "a callable")],
        "random_state": _SEED}
    _rows_reason = "bagging draws samples"

    def _check_params(self):
        if not (self.bagging or self.library_ensemble):
            raise ParameterError("EnsembleOptimizer: set bagging=True and/or "
                                 "library_ensemble=True (otherwise use the inner optimizer)")
        if self.library_ensemble and \
                getattr(get_optimizer(self.opt), "constraints", None) is not None:
            raise ParameterError("EnsembleOptimizer: library_ensemble drops terms, which "
                                 "constraints on the full library cannot follow")

    @property
    def needs_rows(self) -> bool:
        return bool(self.bagging)

    @property
    def coef_list(self) -> np.ndarray:
        """PySINDy's name of ``coef_list_``."""
        self.check_is_fitted()
        return self.coef_list_

    def _draws(self):
        if self.random_state is None:
            return np.random.mtrand._rand            # numpy's global generator (PySINDy's)
        if isinstance(self.random_state, (np.random.RandomState, np.random.Generator)):
            return self.random_state
        return np.random.RandomState(self.random_state)

    def _sizes(self, stats) -> tuple[int | None, int]:
        m = stats.rows.n_rows if self.bagging else None
        n_subset = self.n_subset
        if self.bagging and n_subset is None:
            n_subset = m if self.replace else int(0.6 * m)
        if self.bagging and not self.replace and n_subset > m:
            warnings.warn(f"n_subset={n_subset} is more than the {m} samples, which cannot be "
                          "drawn without replacement; all samples are used", stacklevel=5)
            n_subset = m
        drop = self.n_candidates_to_drop if self.library_ensemble else 0
        if drop > stats.p:
            warnings.warn(f"n_candidates_to_drop={drop} is more than the {stats.p} terms; the "
                          "library is not ensembled", stacklevel=5)
            drop = 0
        return n_subset, drop

    def _solve(self, stats, scale):
        from tqdm.auto import tqdm

        inner_template = get_optimizer(self.opt)
        draws, (n_subset, drop) = self._draws(), self._sizes(stats)
        models = np.zeros((self.n_models, stats.n, stats.p))
        for k in tqdm(range(self.n_models), desc="ensemble", disable=None, leave=False):
            counts = None
            if self.bagging:
                picked = draws.choice(stats.rows.n_rows, n_subset, replace=self.replace)
                counts = np.bincount(picked, minlength=stats.rows.n_rows).astype(float)
            keep = np.sort(draws.choice(stats.p, stats.p - drop, replace=False)) \
                if self.library_ensemble else np.arange(stats.p)
            member = stats.rows.statistics(counts, stats, keep) if self.bagging else \
                restricted(stats, keep)
            inner = copy.deepcopy(inner_template)
            models[k][:, keep] = inner.fit_statistics(member).coef_
        self.coef_list_ = models * scale[None, None, :]
        self.inclusion_probability_ = np.mean(models != 0, axis=0)
        return self._aggregate(models)

    def _aggregate(self, models: np.ndarray) -> np.ndarray:
        if self.ensemble_aggregator is None:
            return np.median(models, axis=0)
        try:
            coef = np.asarray(self.ensemble_aggregator(list(models)), dtype=float)
        except Exception as e:
            raise ParameterError(f"ensemble_aggregator raised {type(e).__name__}: {e}") from e
        if coef.shape != models.shape[1:]:
            raise ShapeError(f"ensemble_aggregator must return an array {models.shape[1:]} "
                             f"(targets, terms); got {describe(coef)}")
        return coef
