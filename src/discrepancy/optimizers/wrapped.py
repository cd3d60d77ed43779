"""A scikit-learn regressor as a sparse regression solver (PySINDy's ``WrappedOptimizer``).

PySINDy accepts any regressor with ``fit`` and ``coef_`` (``sklearn.linear_model.Lasso``,
``ElasticNet``, ``LinearRegression``, ...) as a model's optimizer. Such a regressor needs the
rows of ``Θ``, not their Gram statistics, so a wrapped one fits in memory only (the solvers of
this package are the ones that stream). One regressor is fitted per target (a clone of the
given one, as scikit-learn's ``MultiOutputRegressor`` does); ``unbias`` refits the chosen
terms by least squares (PySINDy's ``WrappedOptimizer`` default; a bare regressor passed as a
model's optimizer is wrapped without it, as PySINDy uses a bare one).
"""
from __future__ import annotations

import numpy as np

from ..constraints import Predicate
from ..errors import ParameterError
from .base import Optimizer, is_regressor, refit_on_support, register

#: coefficients below this are taken as zero (the terms a regressor dropped)
ZERO = 1e-14
REGRESSOR = Predicate(is_regressor, "a scikit-learn regressor (with fit and coef_)")


@register("wrapped")
class WrappedOptimizer(Optimizer):
    """Fit ``optimizer`` (a scikit-learn regressor) per target on the rows of ``Θ``.

    Args:
        optimizer: the regressor (give it ``fit_intercept=False``: the library holds the
            constant term).
        normalize_columns: fit on unit-norm columns.
        unbias: least-squares refit of the terms it kept.
    """

    def __init__(self, optimizer, *, normalize_columns: bool = False, unbias: bool = True):
        self.optimizer = optimizer
        self.normalize_columns = normalize_columns
        self.unbias = unbias

    _parameter_constraints = {"optimizer": [REGRESSOR], "normalize_columns": [bool],
                              "unbias": [bool]}
    _rows_reason = "a scikit-learn regressor fits on the rows"

    @property
    def needs_rows(self) -> bool:
        return True

    def _solve(self, stats, scale):
        from sklearn.base import clone

        theta, y = stats.rows.weighted()
        coef = np.zeros((stats.n, stats.p))
        for i in range(stats.n):
            regressor = clone(self.optimizer)
            try:
                regressor.fit(theta, y[:, i])
                coef[i] = np.reshape(regressor.coef_, -1)
            except Exception as e:
                raise ParameterError(f"the wrapped {type(self.optimizer).__name__} failed on "
                                     f"target {i}: {type(e).__name__}: {e}") from e
            if np.any(getattr(regressor, "intercept_", 0) != 0):
                raise ParameterError(f"the wrapped {type(self.optimizer).__name__} fitted an "
                                     "intercept, which the model would lose: create it with "
                                     "fit_intercept=False (the library's constant term plays "
                                     "that part)")
        coef[np.abs(coef) <= ZERO] = 0.0
        if self.unbias:
            coef = refit_on_support(stats.gram, stats.rhs, coef != 0)
        return coef
