"""The prior alone as a fitted model: an optimizer that learns no correction."""
from __future__ import annotations

import numpy as np

from .base import Optimizer, register


@register("prior_only")
class PriorOnly(Optimizer):
    """No correction: every coefficient is zero, so the fitted model is the prior ``f_m``.

    ``DiscrepancyModel(prior=f_m, optimizer=PriorOnly()).fit(x, t)`` (or
    ``optimizer="prior_only"``) is the prior alone as a model like any other: simulate,
    score, export and save it, or compare it with a learned correction on the same data.
    (A huge STLSQ threshold gives the same zeros, with a warning that it eliminated every
    term.) :meth:`~discrepancy.DiscrepancyModel.from_prior` builds it without data.
    """

    def _solve(self, stats, scale):
        return np.zeros((stats.n, stats.p))
