"""The sparse regression of a PDE fit: the model's optimizer on the Gram statistics.

With STLSQ's automatic threshold (the default) the candidate supports are those of its
threshold path and of backward elimination (:mod:`discrepancy.optimizers.backward`), all
scored by the same blocked cross-validation. PDE libraries hold many collinear columns (a
cubic polynomial of two fields with non-zero means next to their products with
derivatives), on which the threshold path alone can miss the true support: a two-field
reaction fitted on clean data went from ``u`` and ``u v`` to ``u`` and ``u v²`` without
passing through the truth, which backward elimination reaches.
"""
from __future__ import annotations

import numpy as np

from ..errors import DataError
from ..optimizers import STLSQ, GramStatistics


def solve(optimizer, stats: GramStatistics):
    """Fit ``optimizer`` (a copy the caller owns) on ``stats``; returns it."""
    auto = isinstance(optimizer, STLSQ) and optimizer.threshold == "auto" and \
        optimizer.constraints is None and not optimizer.normalize_columns
    if not auto:
        return optimizer.fit_statistics(stats)
    from ..optimizers.backward import backward_path
    from ..optimizers.selection import select_thresholds

    optimizer._validate_params()
    if not all(np.all(np.isfinite(a)) for a in (stats.gram, stats.rhs, stats.yy)):
        raise DataError("the statistics hold non-finite values: the library or the targets "
                        "overflowed on these data (scale the fields or use a smaller library)")
    coef, thresholds, selection = select_thresholds(optimizer, stats, extra=backward_path)
    optimizer.coef_, optimizer.thresholds_, optimizer.selection_ = coef, thresholds, selection
    optimizer.ind_ = coef != 0
    return optimizer
