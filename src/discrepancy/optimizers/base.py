"""Base of the sparse regression solvers: everything is solved on the p×p system."""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
import scipy.linalg
from scipy.linalg import lapack

from ..base import Estimator
from ..constraints import Integral, Interval
from ..errors import ConvergenceError, DataError, ParameterError, ShapeError, describe
from ..registry import Registry
from .gram import GramStatistics


def solve_normal(gram: np.ndarray, rhs: np.ndarray, alpha: float = 0.0) -> np.ndarray:
    """Solve ``(G + αI) ξ = b`` accurately.

    The system is equilibrated by the column norms first (``D G D``), which leaves
    the solution unchanged but makes the Cholesky factorisation usable for
    polynomial libraries whose columns differ by many orders of magnitude.
    Falls back to a minimum-norm least-squares solve when ``G + αI`` is singular or so
    ill-conditioned that scipy would warn (dense candidate supports often are).
    """
    gram, rhs = np.asarray(gram, dtype=float), np.asarray(rhs, dtype=float)
    if gram.ndim != 2 or gram.shape[0] != gram.shape[1] or rhs.shape[:1] != gram.shape[:1] \
            or rhs.ndim > 2:
        raise ShapeError(f"gram must be square (p, p) and rhs (p,) or (p, k); got shapes "
                         f"{gram.shape} and {rhs.shape}")
    if not (np.isfinite(gram).all() and np.isfinite(rhs).all() and np.isfinite(alpha)):
        raise DataError("gram, rhs and alpha must be finite; found a NaN or infinity")
    a = gram + alpha * np.eye(gram.shape[0])
    d = np.sqrt(np.diag(a))
    d[d == 0] = 1.0
    scaled = a / np.outer(d, d)
    b = rhs / (d[:, None] if rhs.ndim == 2 else d)
    z = _cholesky_solve(scaled, b)
    if z is None or not np.all(np.isfinite(z)):
        z = scipy.linalg.lstsq(scaled, b, check_finite=False)[0]  # singular or nearly
    return z / (d[:, None] if rhs.ndim == 2 else d)


#: below this reciprocal condition number ``scipy.linalg.solve`` warns that the result may
#: not be accurate; :func:`solve_normal` then takes the least-squares solve instead
_RCOND = np.finfo(float).eps


def _cholesky_solve(a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """``a⁻¹ b`` for a symmetric positive definite ``a`` ``(p, p)``, or None when ``a`` is
    singular, not positive definite, or its reciprocal condition number is below
    :data:`_RCOND`.

    Written by hand on LAPACK (``potrf``, ``pocon``, ``potrs``): these are the calls and the
    threshold of ``scipy.linalg.solve(a, b, assume_a="pos")`` (a 1 x 1 system divides), and
    the answers and the refusals were the same on 20,000 random systems of up to 24
    unknowns, many singular or nearly; without scipy's checks, broadcasting and warning
    machinery a 10 x 10 solve takes 13 µs instead of 38 (its refusal test included), and
    the selection paths solve hundreds of thousands of such systems."""
    if a.shape[0] == 0:
        return b.copy()
    if a.shape[0] == 1:
        return None if a[0, 0] == 0 else b / a[0, 0]
    factor, info = lapack.dpotrf(a, lower=0, clean=0)
    if info != 0:
        return None
    rcond, info = lapack.dpocon(factor, lapack.dlange("1", a))
    if info != 0 or not rcond >= _RCOND:
        return None
    return lapack.dpotrs(factor, b, lower=0)[0]


def refit_on_support(gram: np.ndarray, rhs: np.ndarray, support: np.ndarray,
                     alpha: float = 0.0, *, minimum_norm: bool = False) -> np.ndarray:
    """Least squares (ridge ``alpha``) of each target on its own terms, from the sums alone.

    ``gram`` ``(p, p)``, ``rhs`` ``(p, n)`` and ``support`` ``(n, p)`` bool give coefficients
    ``(n, p)`` (zero off the support); one target's ``rhs`` ``(p,)`` and ``support`` ``(p,)``
    give ``(p,)``. The unbiased refit of every solver and the refits of model selection.
    ``minimum_norm``: solve each support by numpy's minimum-norm least squares (SVD)
    instead of :func:`solve_normal`'s equilibrated Cholesky (the re-identification's
    fixed point, :mod:`discrepancy.control.one_step`, whose figures were made with it).
    """
    if rhs.ndim == 1:
        return refit_on_support(gram, rhs[:, None], support[None, :], alpha,
                                minimum_norm=minimum_norm)[0]
    coef = np.zeros(support.shape)
    for i, s in enumerate(support):
        if s.any():
            block = gram[np.ix_(s, s)]
            coef[i, s] = _minimum_norm(block, rhs[s, i], alpha) if minimum_norm else \
                solve_normal(block, rhs[s, i], alpha)
    return coef


def _minimum_norm(gram: np.ndarray, rhs: np.ndarray, alpha: float) -> np.ndarray:
    a = gram + alpha * np.eye(len(gram)) if alpha else gram
    return np.linalg.lstsq(a, rhs, rcond=None)[0]


#: folds of a standalone ``fit(theta, y)`` (each made of two contiguous runs of rows)
FIT_FOLDS = 5


class Optimizer(Estimator, ABC):
    """A sparse regression solver ``y ≈ Θ ξ`` (scikit-learn style).

    ``fit(theta, y)`` forms the Gram statistics (rows taken as consecutive samples in time,
    cut into contiguous cross-validation folds); ``fit_gram(gram, rhs)`` and
    ``fit_statistics(stats)`` work from accumulated statistics alone. After any of them,
    ``coef_`` is ``(n_targets, n_features)`` as in PySINDy.

    Args (shared):
        normalize_columns: solve on columns scaled to unit l2 norm, then scale back.
    """

    normalize_columns: bool = False

    @property
    def needs_rows(self) -> bool:
        """Whether this solver needs the rows themselves, not only their Gram statistics
        (trimming samples, bagging samples): then it fits in memory only."""
        return False

    def fit(self, theta, y, sample_weight=None) -> Optimizer:
        """Fit on a feature matrix ``theta`` ``(m, p)`` and targets ``y`` ``(m,)`` or
        ``(m, n)``, rows in time order; ``sample_weight``: a number or ``(m,)`` weights of
        the rows (PySINDy's: each row scaled by the square root of its weight)."""
        from ..data.trajectory import as_2d, check_weight
        from .resampling import Rows

        theta = as_2d("theta", theta)
        y = as_2d("y", y, n_rows=theta.shape[0], allow_1d=True)
        weight = check_weight("sample_weight", sample_weight, theta.shape[0])
        if weight is not None and not np.any(weight > 0):
            raise DataError("sample_weight must have at least one positive weight; all are 0")
        segment = max(1, -(-theta.shape[0] // (2 * FIT_FOLDS)))
        with np.errstate(over="ignore", invalid="ignore"):
            stats = GramStatistics(theta.shape[1], y.shape[1], FIT_FOLDS, segment).add(
                theta, y, weight=weight)
        for name, sums, a in (("theta", stats.gram, theta), ("y", stats.yy, y)):
            if not np.all(np.isfinite(sums)):
                raise DataError(f"{name}'s sums of squares overflow (largest |{name}| = "
                                f"{np.max(np.abs(a)):.3g}); scale {name} down")
        if self.needs_rows:
            fold = (np.arange(theta.shape[0]) // segment) % FIT_FOLDS
            stats.rows = Rows(theta, y, y, weight, fold)
        return self.fit_statistics(stats)

    def fit_gram(self, gram, rhs, *, n_samples: int | None = None, yy=None) -> Optimizer:
        """Fit from ``gram = ΘᵀΘ`` ``(p, p)`` and ``rhs = Θᵀy`` ``(p, n)`` (or ``(p,)``).

        ``n_samples`` (m) and ``yy`` (``Σ y²`` per target, ``(n,)``) are needed only by
        solvers that use them (Lasso's 1/m scaling, automatic thresholds, which without
        folds fall back to an information criterion).
        """
        from ..data.trajectory import as_2d

        gram = as_2d("gram", gram)
        rhs = as_2d("rhs", rhs, n_rows=gram.shape[0], allow_1d=True)
        if gram.shape[0] != gram.shape[1]:
            raise ShapeError(f"gram must be square (p, p); got {gram.shape}")
        if not np.allclose(gram, gram.T, rtol=1e-10, atol=0) or np.any(np.diag(gram) < 0):
            raise DataError("gram must be symmetric with a non-negative diagonal (Θᵀ Θ); got "
                            "a matrix that is not")
        if n_samples is not None and not Interval(Integral, 1).is_satisfied_by(n_samples):
            raise ParameterError(f"n_samples must be None or an integer >= 1; got "
                                 f"{n_samples!r}")
        stats = GramStatistics(gram.shape[0], rhs.shape[1])
        stats.gram, stats.rhs, stats.count = gram, rhs, int(n_samples or 0)
        if yy is not None:
            stats.yy = as_2d("yy", np.reshape(yy, (1, -1)), n_cols=rhs.shape[1]).ravel()
            stats.signal = stats.yy
        else:
            stats.yy = stats.signal = None
        return self.fit_statistics(stats)

    def fit_statistics(self, stats: GramStatistics) -> Optimizer:
        """Fit from :class:`GramStatistics` (with their folds, when kept); returns self."""
        self._validate_params()
        if not isinstance(stats, GramStatistics):
            raise ParameterError(f"stats must be GramStatistics; got {describe(stats)}")
        if self.needs_rows and stats.rows is None:
            raise ParameterError(f"{self!r} needs the samples themselves ({self._rows_reason}), "
                                 "which statistics alone (a stream, Dask, fit_gram) do not "
                                 "keep: fit in memory (fit(theta, y), or a model's fit on "
                                 "arrays)")
        for name in ("gram", "rhs", "yy"):
            value = getattr(stats, name)
            if value is not None and not np.all(np.isfinite(value)):
                raise DataError(f"the statistics' {name} holds non-finite values: the library "
                                "or the targets overflowed on these data (scale the data or "
                                "use a smaller library)")
        scale = np.ones(stats.p)
        if self.normalize_columns:
            norms = np.sqrt(np.diag(stats.gram))
            scale = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
            stats = stats.scaled(scale)
        coef = self._solve(stats, scale)
        if not np.all(np.isfinite(coef)):
            raise ConvergenceError(f"{type(self).__name__} produced non-finite coefficients; "
                                   "the library columns may be collinear or overflow (try "
                                   "normalize_columns=True or a smaller library)")
        self.coef_ = coef * scale[None, :]
        self.ind_ = np.abs(self.coef_) > 0
        return self

    def predict(self, theta) -> np.ndarray:
        """``Θ ξ``: the fitted targets ``(m, n_targets)`` of rows ``theta`` ``(m, p)``."""
        from ..data.trajectory import as_2d

        self.check_is_fitted()
        return as_2d("theta", theta, n_cols=self.coef_.shape[1]) @ self.coef_.T

    @property
    def complexity(self) -> int:
        """Number of nonzero coefficients (PySINDy's ``complexity``)."""
        self.check_is_fitted()
        return int(np.count_nonzero(self.coef_))

    @abstractmethod
    def _solve(self, stats: GramStatistics, scale: np.ndarray) -> np.ndarray:
        """Hook: coefficients ``(n_targets, p)`` from the (possibly normalised) statistics
        (``stats.yy``, ``stats.signal`` may be None and ``stats.folds`` empty when the
        caller only had ``ΘᵀΘ`` and ``Θᵀy``); ``scale`` ``(p,)`` is the column scaling
        applied (``ξ = scale * ξ_scaled``), for solvers with constraints in original units."""

    _fit_hint = "fit or fit_gram"
    _rows_reason = ""


#: the optimizers by spec name (``"stlsq"``, ``"lasso"``, ...)
OPTIMIZERS = Registry("optimizer", "optimizer", Optimizer)
register = OPTIMIZERS.register


def get_optimizer(optimizer=None, **params) -> Optimizer:
    """An Optimizer from an instance, a registered name or spec text (``"stlsq(threshold=0.1)"``),
    a ``{"name", "params"}`` mapping, ``None`` (``STLSQ(threshold="auto")``), or a
    scikit-learn regressor (wrapped as PySINDy uses one: :mod:`.wrapped`)."""
    if optimizer is None:
        optimizer, params = "stlsq", {"threshold": "auto", **params}
    if is_regressor(optimizer):
        return OPTIMIZERS.create("wrapped", optimizer=optimizer, unbias=False)
    return OPTIMIZERS.create(optimizer, **params)


def is_regressor(value) -> bool:
    """A scikit-learn style regressor (an instance with ``fit`` and ``get_params``) that is
    not one of this package's solvers: PySINDy takes one as a model's optimizer."""
    return not isinstance(value, (type, Optimizer, str)) and callable(getattr(value, "fit", None)) \
        and callable(getattr(value, "get_params", None))
