"""PDEDiscrepancyModel: learn ``g`` so that ``u_t = N_m(u, u_x, ...) + g(u, u_x, ...)``."""
from __future__ import annotations

import copy

import numpy as np

from ..base import Estimator
from ..constraints import InstanceOf, Options, Predicate, is_callable
from ..data.chunks import is_dask
from ..data.fields import Grid, as_field_runs, field_array, input_array
from ..differentiation import Differentiator, FiniteDifference
from ..differentiation.spatial import SpatialDifferentiator
from ..errors import DataError, ParameterError, ShapeError, describe
from ..libraries import FeatureLibrary, PolynomialLibrary
from ..models.files.export import equations
from ..optimizers import GramStatistics, Optimizer
from ..symbolic import compile_numpy, feature_name
from .distributed import dask_statistics
from .export import ExportView, to_latex, to_sympy
from .integrate import simulate
from .resolve import first_snapshots, resolve_setup
from .setup import FieldSetup
from .simulation import simulation_methods
from .solve import solve
from .streaming import FieldSource, stream_statistics
from .weak import FieldWeakForm

_NAMES = [None, InstanceOf(str, "a name"),
          Predicate(lambda v: isinstance(v, (list, tuple)) and all(isinstance(n, str) for n in v),
                    "a list of names")]
_METHOD = [None, Options(["auto", "weak"]), InstanceOf((Differentiator, FieldWeakForm),
                                                       "a Differentiator or FieldWeakForm"),
           InstanceOf(str, "a spec string")]


class PDEDiscrepancyModel(Estimator):
    """Hybrid PDE ``u_t = N_m + g`` with a sparse discrepancy ``g = Θ(u, u_x, ...) Ξ``.

    Args:
        prior: ``N_m``: sympy expressions in the fields and their derivatives (``u_xx``,
            ``u_xy``, see :mod:`discrepancy.pde.prior`), a callable on snapshots (your
            solver's right-hand side), or ``None`` (PDE-FIND).
        feature_library: candidate terms over the fields, their derivatives and inputs
            (default :class:`~discrepancy.libraries.pde.PDELibrary` of cubic polynomials
            with a constant and derivatives up to the prior's order, at least 2).
        optimizer: default ``STLSQ(threshold="auto")`` (blocked cross-validation).
        differentiation_method: ``"auto"`` (default: pointwise for clean fields, the weak
            form for noisy ones, :mod:`discrepancy.pde.auto`), ``"weak"`` or a
            :class:`~discrepancy.pde.weak.FieldWeakForm`, or a time differentiator
            (``dc.FiniteDifference()``, ``dc.SavitzkyGolay(...)``: pointwise form).
        spatial_differentiation: ``"auto"`` or one spatial method (``dc.SpatialSpectral()``,
            ``dc.SpatialFiniteDifference(order)``, ``dc.SpatialSavitzkyGolay(...)``) or one
            per axis.
        field_names: names of the ``n`` fields (default ``u`` or ``u1 ... un``).
        input_names: names of the inputs (default ``f`` or ``f1 ...``).

    Fitted attributes: ``coef_`` ``(n, p)``, ``setup_``, ``statistics_``, ``optimizer_``,
    ``grid_``, ``field_names_``, ``feature_expressions_`` and ``differentiation_choice_``.
    """

    _parameter_constraints = {
        "prior": [None, is_callable, Predicate(lambda v: isinstance(v, (list, tuple)) and v,
                                               "a list of sympy expressions")],
        "feature_library": [None, InstanceOf(FeatureLibrary, "a feature library")],
        "optimizer": [None, InstanceOf(Optimizer, "an Optimizer"), InstanceOf(str, "a spec")],
        "differentiation_method": _METHOD,
        "spatial_differentiation": [None, Options(["auto"]), InstanceOf(
            SpatialDifferentiator, "a spatial differentiator"), InstanceOf(str, "a spec"),
            Predicate(lambda v: isinstance(v, (list, tuple)) and v, "a list, one per axis")],
        "field_names": _NAMES, "input_names": _NAMES}
    _fit_hint = "fit(u, t, grid=...)"
    _fitted_attribute = "coef_"

    def __init__(self, prior=None, feature_library=None, optimizer=None,
                 differentiation_method=None, *, spatial_differentiation=None,
                 field_names=None, input_names=None):
        self.prior = prior
        self.feature_library = feature_library
        self.optimizer = optimizer
        self.differentiation_method = differentiation_method
        self.spatial_differentiation = spatial_differentiation
        self.field_names = field_names
        self.input_names = input_names

    # ------------------------------------------------------------------ fitting
    def fit(self, u, t=None, *, grid: Grid, inputs=None, progress: bool | None = None):
        """Learn the discrepancy from fields.

        Args:
            u: fields ``(m, *grid.shape)`` (one) or ``(m, *grid.shape, n)``, time first; a
                list of runs; a dask array of that shape (chunked in time); or a
                :class:`~discrepancy.pde.streaming.FieldSource` (zarr/HDF5 on disk),
                streamed in time chunks.
            t: time step (a number) or uniform times ``(m,)`` (a list per run); default 1.
            grid: the :class:`~discrepancy.Grid` of the fields.
            inputs: per run input fields ``(m, *grid.shape, r)`` or signals ``(m, r)``.
            progress: progress bar for streamed and Dask fits (default: on a terminal).

        Returns:
            self
        """

        self._validate_params()
        if isinstance(u, FieldSource):
            setup, stats = stream_statistics(self, u, progress=progress)
        elif _is_dask(u):
            setup, stats = dask_statistics(self, u, t=t, grid=grid, progress=progress)
        else:

            runs = as_field_runs(u, t, grid, inputs)
            first = runs[0]
            setup = self.make_setup(first.n_fields, 0 if first.inputs is None else
                                    first.inputs.shape[-1], grid, sample=first_snapshots(runs),
                                    lengths=[r.n_samples for r in runs])
            stats = setup.new_statistics()
            for run in runs:
                if run.n_samples < setup.min_samples:
                    raise ShapeError(f"a run of {run.n_samples} samples is shorter than the "
                                     f"{setup.min_samples} the time method needs")
                setup.statistics(run, into=stats)
        return self.fit_statistics(stats, setup)

    def make_setup(self, n_fields: int, n_inputs: int, grid: Grid, *, sample=None,
                   lengths=None) -> FieldSetup:
        """The frozen set-up for ``n_fields`` fields and ``n_inputs`` inputs on ``grid``
        (``sample``: the data's first snapshots, which data-driven choices look at;
        ``lengths``: snapshots per run)."""

        self._validate_params()
        if not isinstance(grid, Grid):
            raise ParameterError(f"grid must be a discrepancy.Grid; got {describe(grid)}")
        return resolve_setup(self, n_fields, n_inputs, grid, sample, lengths)

    @classmethod
    def prior_only(cls, prior, grid: Grid, *, field_names=None, input_names=None,
                   n_inputs: int = 0) -> PDEDiscrepancyModel:
        """A model whose discrepancy is zero: the prior alone, ready to simulate (to make
        data, or to compare the hybrid with)."""

        n = len(prior) if isinstance(prior, (list, tuple)) else len(
            [field_names] if isinstance(field_names, str) else field_names or ["u"])
        model = cls(prior=prior, differentiation_method=FiniteDifference(),
                    spatial_differentiation="finite_difference", field_names=field_names,
                    input_names=input_names)
        model.feature_library = PolynomialLibrary(0)
        setup = model.make_setup(n, n_inputs, grid)
        model._set_fit(setup, np.zeros((n, setup.n_features)), None, None)
        return model

    def fit_statistics(self, stats: GramStatistics, setup: FieldSetup):
        """Fit from Gram statistics made with ``setup``; returns self."""
        if not isinstance(setup, FieldSetup) or not isinstance(stats, GramStatistics):
            raise ParameterError(f"need GramStatistics and a FieldSetup; got "
                                 f"{describe(stats)} and {describe(setup)}")
        if (stats.p, stats.n) != (setup.n_features, setup.n_fields):
            raise ShapeError(f"stats are for {stats.p} features and {stats.n} fields; the "
                             f"set-up has {setup.n_features} and {setup.n_fields}")
        if stats.count == 0 or not np.any(stats.gram):
            raise DataError("the statistics hold no usable rows (runs too short for the "
                            "test functions or derivative windows?)")

        optimizer = solve(copy.deepcopy(setup.optimizer), stats)
        self._set_fit(setup, optimizer.coef_, optimizer, stats)
        return self

    def _set_fit(self, setup, coef, optimizer, stats) -> None:
        self.setup_, self.optimizer_, self.statistics_ = setup, optimizer, stats
        self.grid_ = setup.grid
        self.field_names_, self.input_names_ = setup.field_names, setup.input_names
        self.prior_ = setup.prior
        self.feature_library_ = setup.library
        self.feature_expressions_ = list(setup.library.feature_expressions_)
        self.differentiation_choice_ = setup.choice
        self.coef_ = np.asarray(coef, dtype=float)
        active = np.flatnonzero(np.any(self.coef_ != 0, axis=0))
        functions = setup.library.user_functions()
        self._active = [compile_numpy(self.feature_expressions_[j], setup.variables.names,
                                      functions) for j in active]
        self._active_coef = self.coef_[:, active].T

    # --------------------------------------------------------------- evaluation
    def _snapshots(self, u, inputs):
        """Checked snapshots ``(k, *shape, n)`` and inputs ``(k, *shape, r)`` or ``None``."""

        self.check_is_fitted()
        u = field_array("u", u, self.grid_, n_fields=len(self.field_names_))
        r = len(self.input_names_)
        if (inputs is None) != (r == 0):
            raise ShapeError(f"the model has {r} inputs; inputs must be given exactly when it "
                             f"has some (got {describe(inputs)})")
        return u, None if inputs is None else input_array("inputs", inputs, self.grid_,
                                                          u.shape[0], r)

    def _g_flat(self, z: np.ndarray) -> np.ndarray:
        if not self._active:
            return np.zeros((z.shape[0], len(self.field_names_)))
        theta = np.column_stack([np.broadcast_to(f(z), z.shape[:1]) for f in self._active])
        return theta @ self._active_coef

    def _evaluate(self, u, inputs, methods, part: str, check: bool = True) -> np.ndarray:
        variables = self.setup_.variables
        jet = variables.jet(u, inputs, self.grid_, methods, check=check)
        g = self._g_flat(jet.reshape(-1, jet.shape[-1])).reshape(u.shape)
        if part == "discrepancy":
            return g
        return self.prior_.values(u, inputs, jet, variables.names) + g

    def discrepancy(self, u, inputs=None) -> np.ndarray:
        """The learned ``g`` on snapshots ``u`` ``(k, *grid.shape[, n])``, ``(k, *shape, n)``
        (derivatives spectral on periodic axes, 4th-order differences elsewhere)."""

        u, inputs = self._snapshots(u, inputs)
        return self._evaluate(u, inputs, simulation_methods(self.grid_), "discrepancy")

    def predict(self, u, inputs=None) -> np.ndarray:
        """``u_t = N_m + g`` of the hybrid model on snapshots, ``(k, *shape, n)``."""

        u, inputs = self._snapshots(u, inputs)
        return self._evaluate(u, inputs, simulation_methods(self.grid_), "hybrid")

    def simulate(self, u0, t, *, inputs=None, method: str = "auto", rtol: float = 1e-6,
                 atol: float = 1e-9, boundary: str = "fixed") -> np.ndarray:
        """Fields of the hybrid PDE from ``u0`` ``(*grid.shape[, n])`` at times ``t``
        ``(k,)``: ``(k, *grid.shape, n)`` (see :mod:`discrepancy.pde.simulation`).

        ``method``: ``"auto"`` (ETDRK4 on periodic grids with symbolic terms, else BDF),
        ``"etdrk4"`` or a ``solve_ivp`` method; ``inputs``: a callable ``f(t)`` returning
        ``(*grid.shape, r)`` or ``(r,)``; ``boundary``: ``"fixed"`` holds the ends of
        non-periodic axes at ``u0`` (Dirichlet), ``"free"`` does not."""
        self.check_is_fitted()
        return simulate(self, u0, t, inputs=inputs, method=method, rtol=rtol, atol=atol,
                        boundary=boundary)

    # ------------------------------------------------------------------ output
    @property
    def complexity(self) -> int:
        """Number of nonzero coefficients of ``g`` (PySINDy's ``complexity``)."""
        self.check_is_fitted()
        return int(np.count_nonzero(self.coef_))

    def coefficients(self) -> np.ndarray:
        """``Ξ`` as ``(n_fields, n_features)``, the column order of :meth:`get_feature_names`:
        a copy, so editing it leaves the model unchanged."""
        self.check_is_fitted()
        return self.coef_.copy()

    def get_feature_names(self) -> list[str]:
        """Names of the library's ``p`` terms over the jet variables (``u``, ``u_x``, ...,
        inputs), the column order of :meth:`coefficients`."""
        self.check_is_fitted()
        return [feature_name(e, self.setup_.variables.names) for e in self.feature_expressions_]

    def equations(self, precision: int = 3) -> list[str]:
        """Right-hand sides as text: ``prior - 1.000 u_xx``."""
        self.check_is_fitted()
        return equations(ExportView(self), precision)

    def print(self, precision: int = 3) -> None:
        """One line per field, ``(u)_t = prior + 0.050 u_xx``, then how the derivatives were
        chosen (a ``#`` line) when they were chosen from the data."""
        self.check_is_fitted()
        for name, eq in zip(self.field_names_, self.equations(precision), strict=True):
            print(f"({name})_t = {eq}")
        choice = self.differentiation_choice_
        if choice:
            noise = ", ".join(f"{v:.3g}" for v in choice["noise_std"])
            print(f"# {choice['form']} form, chosen from the data (noise std ≈ [{noise}])")

    def to_sympy(self, part: str | None = None, *, derivatives: bool = False):
        """Right-hand sides as sympy expressions (``part`` as for ODE models); with
        ``derivatives=True`` in ``sympy.Derivative`` form of functions ``u(t, x)``."""
        self.check_is_fitted()
        return to_sympy(self, part, derivatives)

    def to_latex(self, precision: int = 4, part: str | None = None) -> str:
        """LaTeX ``aligned`` block: ``u_{t} &= - u u_{x} - 1.0 u_{xx} ...``."""
        self.check_is_fitted()
        return to_latex(self, precision, part)


def _is_dask(u) -> bool:
    """A dask array, or a non-empty list of them (runs)."""
    items = list(u) if isinstance(u, (list, tuple)) else [u]
    return bool(items) and all(is_dask(a) for a in items)
