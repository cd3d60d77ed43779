"""DiscrepancyModel: learn g(x, u) so that f_m + g matches measured trajectories."""
from __future__ import annotations

import copy

import numpy as np

from ..data.trajectory import Trajectory, as_2d, as_trajectories
from ..differentiation import get_differentiation_method
from ..errors import NotFittedError, ShapeError
from ..libraries import FeatureLibrary, PolynomialLibrary
from ..optimizers import STLSQ, GramStatistics
from ..symbolic import compile_numpy, feature_name
from .prior import Prior
from .simulation import integrate


class DiscrepancyModel:
    """Hybrid model ``dx/dt = f_m(x, u) + g(x, u)`` with a sparse discrepancy ``g = Θ(x, u) Ξ``.

    Args:
        prior: ``f_m``: a vectorised callable ``f_m(x, u) -> (m, n)`` (``x`` ``(m, n)``,
            ``u`` ``(m, r)`` or ``None``), a list of ``n`` sympy expressions in the state and
            input symbols (then :meth:`to_sympy` and :meth:`to_casadi` give the whole hybrid
            model), or ``None`` for plain SINDy.
        feature_library: candidate terms Θ (default ``PolynomialLibrary(degree=2)``).
        optimizer: sparse regression (default ``STLSQ(threshold="auto")``: the threshold of
            each equation chosen by BIC, so no hand tuning; pass ``STLSQ(threshold=0.1)``
            for PySINDy's default).
        differentiation_method: a Differentiator or registered name (default finite
            differences); ignored when ``x_dot`` is given to :meth:`fit`.
        state_names: names of the n states (default ``x1 ... xn``).
        input_names: names of the r inputs (default ``u`` for one, ``u1 ... ur`` for more).
    """

    def __init__(self, prior=None, feature_library: FeatureLibrary | None = None,
                 optimizer=None, differentiation_method=None, *, state_names=None,
                 input_names=None):
        self.prior = prior
        self.feature_library = feature_library
        self.optimizer = optimizer
        self.differentiation_method = differentiation_method
        self.state_names = state_names
        self.input_names = input_names

    # ----------------------------------------------------------------- fitting
    def fit(self, x, t=None, u=None, x_dot=None) -> DiscrepancyModel:
        """Learn the discrepancy from measured states.

        Args:
            x: states ``(m, n)`` or a list of trajectories (never differentiated across joins).
            t: time step or times ``(m,)`` (or a list per trajectory); default step 1.
            u: inputs ``(m, r)`` or a list per trajectory.
            x_dot: measured derivatives ``(m, n)``; skips numerical differentiation.

        Returns:
            self
        """
        from ..streaming import is_streamed

        if is_streamed(x):  # dask arrays, chunk iterators and chunk sources: see streaming.py
            from ..streaming import fit_streamed
            return fit_streamed(self, x, t=t, u=u, x_dot=x_dot)
        trajectories = as_trajectories(x, t, u, x_dot)
        first = trajectories[0]
        self._setup(first.x.shape[1], 0 if first.u is None else first.u.shape[1])
        stats = GramStatistics(self.feature_library_.n_features_, self.n_states_)
        for trajectory in trajectories:
            self._accumulate(stats, trajectory)
        return self._fit_statistics(stats)

    def _setup(self, n: int, r: int) -> None:
        """Resolve names, prior, library, optimizer and differentiation for n states, r inputs."""
        self.state_names_ = _names("state_names", self.state_names, n, "x", one=None)
        self.input_names_ = _names("input_names", self.input_names, r, "u", one="u")
        self.n_states_, self.n_inputs_ = n, r
        self.prior_ = Prior(self.prior, self.state_names_, self.input_names_)
        library = self.feature_library if self.feature_library is not None \
            else PolynomialLibrary(degree=2)
        self.feature_library_ = copy.deepcopy(library).fit(self.variable_names_)
        self.optimizer_ = copy.deepcopy(self.optimizer) if self.optimizer is not None \
            else STLSQ(threshold="auto")
        self.differentiation_method_ = get_differentiation_method(self.differentiation_method)

    def residual(self, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
        """``(Z, y)``: variables ``[x_smooth, u]`` ``(m, n + r)`` and ``x_dot - f_m`` ``(m, n)``."""
        if trajectory.x_dot is None:
            xs, xd = self.differentiation_method_(trajectory.x, trajectory.t)
        else:
            xs, xd = trajectory.x, trajectory.x_dot
        y = xd - self.prior_(xs, trajectory.u)
        z = xs if trajectory.u is None else np.hstack([xs, trajectory.u])
        return z, y

    def _accumulate(self, stats: GramStatistics, trajectory: Trajectory) -> None:
        from ..accumulate import accumulate

        z, y = self.residual(trajectory)
        accumulate(stats, self.feature_library_.transform, z, y)

    def _fit_statistics(self, stats: GramStatistics) -> DiscrepancyModel:
        self.optimizer_.fit_gram(stats.gram, stats.rhs, n_samples=stats.count, yy=stats.yy)
        self.statistics_ = stats
        self._set_coefficients(self.optimizer_.coef_, self.feature_library_.feature_expressions_,
                               self.feature_library_.user_functions())
        return self

    def _set_coefficients(self, coef: np.ndarray, expressions, functions) -> None:
        """Store ``coef_`` ``(n, p)`` and the term expressions; compile the active terms."""
        self.coef_ = np.asarray(coef, dtype=float)
        self.feature_expressions_ = list(expressions)
        self.user_functions_ = dict(functions)
        active = np.flatnonzero(np.any(self.coef_ != 0, axis=0))
        self._active_terms = [compile_numpy(self.feature_expressions_[j], self.variable_names_,
                                            functions) for j in active]
        self._active_coef = self.coef_[:, active].T

    # --------------------------------------------------------------- evaluation
    @property
    def variable_names_(self) -> list[str]:
        return [*self.state_names_, *self.input_names_]

    def check_is_fitted(self) -> None:
        if not hasattr(self, "coef_"):
            raise NotFittedError("this DiscrepancyModel is not fitted yet; call fit(x, t) first")

    def _variables(self, x, u) -> tuple[np.ndarray, np.ndarray | None]:
        self.check_is_fitted()
        x = as_2d("x", x, n_cols=self.n_states_)
        if self.n_inputs_ == 0:
            if u is not None:
                raise ShapeError("u was given but the model was fitted without inputs")
            return x, None
        if u is None:
            raise ShapeError(f"u is required: the model was fitted with {self.n_inputs_} inputs "
                             f"{self.input_names_}")
        return x, as_2d("u", u, n_rows=x.shape[0], n_cols=self.n_inputs_, allow_1d=True)

    def _g(self, z: np.ndarray) -> np.ndarray:
        if not self._active_terms:
            return np.zeros((z.shape[0], self.n_states_))
        theta = np.column_stack([f(z) for f in self._active_terms])
        return theta @ self._active_coef

    def discrepancy(self, x, u=None) -> np.ndarray:
        """The learned correction ``g(x, u)``, ``(m, n)``."""
        x, u = self._variables(x, u)
        return self._g(x if u is None else np.hstack([x, u]))

    def predict(self, x, u=None) -> np.ndarray:
        """Hybrid model derivatives ``f_m(x, u) + g(x, u)``, ``(m, n)``."""
        x, u = self._variables(x, u)
        return self.prior_(x, u) + self._g(x if u is None else np.hstack([x, u]))

    def simulate(self, x0, t, u=None, **integrator_kws) -> np.ndarray:
        """Trajectory of the hybrid model from ``x0`` ``(n,)`` at times ``t`` ``(k,)``.

        ``u`` is an array ``(k, r)`` sampled at ``t`` (linearly interpolated, or held with
        ``u_hold="zoh"``) or a callable ``u(t) -> (r,)``. Keyword arguments go to
        :func:`discrepancy.models.simulation.integrate` (``method``, ``rtol``, ``atol``).
        Returns ``(k, n)``.
        """
        self.check_is_fitted()
        return integrate(self._rhs_one, x0, t, u, n_states=self.n_states_,
                         n_inputs=self.n_inputs_, **integrator_kws)

    def _rhs_one(self, x: np.ndarray, u: np.ndarray | None) -> np.ndarray:
        """``f_m + g`` for a batch of states without re-validation (hot path of simulate)."""
        z = x if u is None else np.hstack([x, u])
        return self.prior_(x, u) + self._g(z)

    # ----------------------------------------------------------------- output
    def coefficients(self) -> np.ndarray:
        """``Ξ`` as ``(n_states, n_features)``, PySINDy's layout."""
        self.check_is_fitted()
        return self.coef_.copy()

    def get_feature_names(self) -> list[str]:
        self.check_is_fitted()
        return [feature_name(e, self.variable_names_) for e in self.feature_expressions_]

    def equations(self, precision: int = 3) -> list[str]:
        """Right-hand sides as text, e.g. ``prior + 0.400 x2 - 0.400 x1^2 x2``."""
        names = self.get_feature_names()
        out = []
        for row in self.coef_:
            parts = [] if self.prior is None else ["prior"]
            for c, name in zip(row, names, strict=True):
                if c != 0:
                    term = f"{abs(c):.{precision}f}" + ("" if name == "1" else f" {name}")
                    parts.append(("- " if c < 0 else "+ ") + term if parts else
                                 ("-" if c < 0 else "") + term)
            out.append(" ".join(parts) if parts else f"{0:.{precision}f}")
        return out

    def print(self, precision: int = 3) -> None:
        """Print one line per state: ``(x2)' = prior + 0.400 x2 - 0.400 x1^2 x2``."""
        for name, eq in zip(self.state_names_, self.equations(precision), strict=True):
            print(f"({name})' = {eq}")

    def score(self, x, t=None, u=None, x_dot=None, *, metric: str = "r2") -> float:
        """Goodness of fit on data: ``"r2"`` or ``"rmse"`` of derivatives, or
        ``"trajectory"``: ``‖x_sim − x‖ / ‖x‖`` simulating from ``x[0]`` (one trajectory)."""
        from .scoring import score
        self.check_is_fitted()
        return score(self, x, t, u, x_dot, metric=metric)

    def bootstrap(self, x, t=None, u=None, x_dot=None, *, n_resamples: int = 200,
                  block_length: int | None = None, method: str = "wild", seed: int = 0):
        """Uncertainty of every term: a block bootstrap of the fit on these data.

        ``method="wild"`` (repeat the experiment with new noise) or ``"pairs"`` (also
        resample which states were visited); see :mod:`discrepancy.models.uncertainty`.

        Returns a :class:`~discrepancy.models.uncertainty.CoefficientUncertainty` with
        ``std``, ``interval()``, ``inclusion_probability`` and a printable ``table()``.
        """
        from .uncertainty import bootstrap
        return bootstrap(self, x, t, u, x_dot, n_resamples=n_resamples,
                         block_length=block_length, method=method, seed=seed)

    # ------------------------------------------------------------------ export
    def to_sympy(self, part: str | None = None):
        """Equations as sympy expressions, one per state.

        ``part="hybrid"`` gives ``f_m + g`` and needs a sympy prior (or none);
        ``"discrepancy"`` gives ``g`` alone. The default is the hybrid model when the
        prior is symbolic or absent, and the discrepancy when it is a Python callable.
        """
        from .export import to_sympy
        return to_sympy(self, part)

    def to_latex(self, precision: int = 4, part: str | None = None) -> str:
        """LaTeX ``aligned`` block of the equations, coefficients rounded to ``precision``."""
        from .export import to_latex
        return to_latex(self, precision, part)

    def to_casadi(self, part: str | None = None):
        """CasADi ``Function`` ``f(x, u) -> xdot`` (``f(x)`` without inputs), exact.

        The default is the whole hybrid model, which needs a sympy prior: a callable
        prior raises ExportError (ask for ``part="discrepancy"`` to get ``g`` alone).
        """
        from .export import to_casadi
        return to_casadi(self, part)

    def save(self, path) -> None:
        """Write the fitted model as versioned JSON (terms as structured expressions)."""
        from .model_file import save_model
        save_model(self, path)


def _names(arg: str, given, k: int, stem: str, *, one) -> list[str]:
    from ..symbolic import IDENTIFIER

    if given is None:
        return [one] if k == 1 and one else [f"{stem}{i + 1}" for i in range(k)]
    names = [given] if isinstance(given, str) else list(given)
    if len(names) != k:
        raise ShapeError(f"{arg} must have {k} names (one per column of the data); "
                         f"got {len(names)}: {names}")
    bad = [n for n in names if not isinstance(n, str) or not IDENTIFIER.match(n)]
    if bad or len(set(names)) != len(names):
        raise ShapeError(f"{arg} must be distinct identifiers (letters, digits, _); got {names}")
    return names
