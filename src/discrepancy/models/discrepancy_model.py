"""DiscrepancyModel: learn g(x, u) so that f_m + g matches measured trajectories."""
from __future__ import annotations

import copy

import numpy as np

from ..base import Estimator
from ..constraints import (
    InstanceOf,
    Integral,
    Interval,
    Options,
    Predicate,
    is_callable,
    validate_params,
)
from ..data.chunks import data_kind
from ..data.trajectory import Trajectory, as_2d, as_trajectories, is_number
from ..data.validation import as_float_array, check_vector
from ..differentiation import Differentiator
from ..errors import DataError, ParameterError, ShapeError, describe
from ..expression_tape import compile_numpy_many
from ..fitting.distributed import dask_statistics
from ..fitting.setup import FitSetup
from ..fitting.streaming import chunk_statistics
from ..libraries import FeatureLibrary
from ..optimizers import GramStatistics, Optimizer
from ..optimizers.wrapped import REGRESSOR
from ..symbolic import feature_name
from .core.arguments import keywords_only, require_t
from .core.checks import checked_discrepancy, pairs
from .core.conditioning import warn_if_ill_conditioned
from .core.prediction_error_methods import PredictionErrorMethods
from .core.pysindy_interface import PySINDyInterface
from .core.resolve import resolve_setup
from .core.scoring import score
from .core.term_choice import announce, choose_terms
from .core.term_constraints import Constraints
from .core.uncertainty import bootstrap, predict_interval, simulate_interval
from .files.export import choice_line, equations, to_casadi, to_latex, to_sympy
from .files.model_file import corrupted, decode, encode, read_json, write_json
from .files.model_parameters import FITTED, check_parameters
from .outputs.output_methods import OutputErrorMethods
from .simulate.discrete import iterate
from .simulate.fast_simulation import compiled_stepper
from .simulate.prediction import checked_states, iterate_ahead, predict_ahead
from .simulate.region import guard, guard_run, region_of
from .simulate.simulate_arguments import map_options, simulation_options
from .simulate.simulation import integrate

_SPEC = InstanceOf(str, "a spec string")
_NAMES = [None, InstanceOf(str, "a name"),
          Predicate(lambda v: isinstance(v, (list, tuple)) and all(isinstance(n, str) for n in v),
                    "a list of names")]


class DiscrepancyModel(PredictionErrorMethods, OutputErrorMethods, PySINDyInterface, Estimator):
    """Hybrid model ``dx/dt = f_m(x, u) + g(x, u)`` with a sparse discrepancy ``g = Θ(x, u) Ξ``.

    Args:
        prior: ``f_m``: a vectorised callable ``f_m(x, u) -> (m, n)`` (``x`` ``(m, n)``,
            ``u`` ``(m, r)`` or ``None``), a list of ``n`` sympy expressions in the state and
            input symbols (then :meth:`to_sympy` and :meth:`to_casadi` give the whole hybrid
            model), or ``None`` for plain SINDy.
        feature_library: candidate terms Θ (default ``PolynomialLibrary(degree=2)``), or a
            spec such as ``"poly(3) + fourier(1)"``.
        optimizer: sparse regression (default ``STLSQ(threshold="auto")``: no hand tuning;
            ``STLSQ(threshold=0.1)`` is PySINDy's default), or a spec such as ``"lasso"``.
        differentiation_method: a Differentiator or a spec such as
            ``"savitzky_golay(window_length=31)"``; default ``"auto"``: smoothing chosen
            from the data at each fit (:class:`~discrepancy.differentiation.AutoSmoothing`,
            the choice in ``differentiation_method_`` and ``differentiation_choice_``);
            ignored when ``x_dot`` is given to :meth:`fit`.
        state_names: names of the n states (default ``x1 ... xn``).
        input_names: names of the r inputs (default ``u`` for one, ``u1 ... ur`` for more).
        discrete_time: a map ``x[k+1] = f_m(x[k], u[k]) + g(x[k], u[k])`` instead of an ODE
            (no derivatives; ``simulate`` iterates the map; ``t`` is ignored by ``fit``).
        constraints: a :class:`~discrepancy.models.core.term_constraints.Constraints`: equations
            without correction, terms confined to some equations, linear (in)equalities on
            coefficients by name (needs an optimizer that takes constraints: STLSQ).
        selection: how the terms are chosen. ``"auto"`` (default): by forecasts when the
            optimizer chooses its own sparsity (``STLSQ(threshold="auto")``, the default):
            equation error proposes supports, free-run and k-step forecasts from origins in
            held-out blocks of the training data decide, and the prior alone is always a
            candidate (:mod:`discrepancy.models.core.term_choice`); a fixed threshold or another
            optimizer is used as given. ``"forecast"``: also a given optimizer's answer is
            compared with the prior alone. ``"optimizer"``: the optimizer's own choice.

    Fitted attributes: ``coef_`` ``(n, p)``, ``setup_`` (the :class:`FitSetup` used),
    ``statistics_`` (its Gram statistics), ``optimizer_`` (the fitted optimizer) and the
    resolved ``state_names_``, ``input_names_``, ``prior_``, ``feature_library_``,
    ``differentiation_method_``; ``prior_only_`` (no learned term), ``forecast_selection_``
    (every candidate's forecast score when forecasts chose, else None) and ``region_``
    (the range of each state and input fitted on, a
    :class:`~discrepancy.models.simulate.region.FittedRegion`: ``simulate`` and ``predict`` warn
    when they leave it).
    """

    _parameter_constraints = {
        "prior": [None, is_callable, Predicate(lambda v: isinstance(v, (list, tuple)) and v,
                                               "a list of sympy expressions")],
        "feature_library": [None, InstanceOf(FeatureLibrary, "a feature library"), _SPEC],
        "optimizer": [None, InstanceOf(Optimizer, "an Optimizer"), _SPEC, REGRESSOR],
        "differentiation_method": [None, InstanceOf(Differentiator, "a Differentiator"), _SPEC],
        "state_names": _NAMES, "input_names": _NAMES,
        "constraints": [None, InstanceOf(Constraints, "a discrepancy.Constraints")],
        "discrete_time": [bool],
        "selection": [Options(["auto", "forecast", "optimizer"])],
    }
    _fit_hint = "fit(x, t)"
    _fitted_attribute = "coef_"

    def __init__(self, prior=None, feature_library: FeatureLibrary | str | None = None,
                 optimizer=None, differentiation_method=None, *, state_names=None,
                 input_names=None, constraints=None, discrete_time: bool = False,
                 selection: str = "auto"):
        self.prior = prior
        self.feature_library = feature_library
        self.optimizer = optimizer
        self.differentiation_method = differentiation_method
        self.state_names = state_names
        self.input_names = input_names
        self.constraints = constraints
        self.discrete_time = discrete_time
        self.selection = selection

    # ----------------------------------------------------------------- fitting
    def fit(self, x, t=None, *args, u=None, x_dot=None, sample_weight=None,
            feature_names=None) -> DiscrepancyModel:
        """Learn the discrepancy from measured states.

        Args:
            x: states ``(m, n)``, a list of trajectories (never differentiated across
                joins), a dask array, or chunks (see :mod:`discrepancy.streaming`).
            t: time step or times ``(m,)`` (or a list per trajectory); required unless
                ``x_dot`` is given or the model is discrete-time (chunks may carry times).
            u: inputs ``(m, r)``, a list per trajectory, or one number (a constant input).
            x_dot: measured derivatives ``(m, n)``; skips numerical differentiation.
            sample_weight: weight of each sample in the regression, ``(m,)``, or a list per
                trajectory of arrays or numbers (a number weighs a whole trajectory). Chunked
                data carry them in the chunks (``Chunk(x, weight=...)``).
            feature_names: names of the states and then the inputs for this fit (PySINDy's
                ``fit(feature_names=...)``; they replace ``state_names``/``input_names``).

        Returns:
            self
        """
        keywords_only("fit", args, "u, x_dot, sample_weight and feature_names")
        kind = data_kind(x)
        if kind != "arrays" and (sample_weight is not None or feature_names is not None):
            raise ParameterError("with chunked or dask x, give sample weights inside the chunks "
                                 "(Chunk(x, weight=...); dask arrays take none) and names as "
                                 "the model's state_names and input_names")
        if kind != "chunks":  # chunks may carry their own times
            require_t("fit", t, needed=x_dot is None and not self.discrete_time)
        if kind == "dask":  # the set-up is made once the rows its choices need are read
            setup, stats = dask_statistics(self.make_setup, self.differentiation_method, x, t=t,
                                           u=u, x_dot=x_dot)
        elif kind == "chunks":
            setup, stats = chunk_statistics(self.make_setup, self.differentiation_method, x, t=t,
                                            u=u, x_dot=x_dot)
        else:
            trajectories = as_trajectories(x, t, u, x_dot, sample_weight)
            first = trajectories[0]
            setup = self.make_setup(first.x.shape[1], 0 if first.u is None else first.u.shape[1],
                                    sample=trajectories, feature_names=feature_names)
            stats = setup.new_statistics()
            for trajectory in trajectories:
                setup.statistics(trajectory, into=stats)
        return self.fit_statistics(stats, setup)

    def differentiate(self, x, t=None):
        """Derivatives ``(m, n)`` of ``x`` (or a list, one per trajectory) by this model's
        differentiation method, as ``fit`` would estimate them (``"auto"`` chooses from
        ``x`` itself; PySINDy's ``differentiate``)."""
        if self.discrete_time:
            raise ParameterError("a discrete-time model has no derivatives to estimate")
        require_t("differentiate", t, needed=True)
        trajectories = as_trajectories(x, t)
        n = trajectories[0].x.shape[1]
        method = self.make_setup(n, 0, sample=trajectories).differentiation
        out = [method.smooth_and_differentiate(tr.x, tr.t)[1] for tr in trajectories]
        return out if isinstance(x, (list, tuple)) else out[0]

    def make_setup(self, n_states: int, n_inputs: int, *, sample=None,
                   feature_names=None) -> FitSetup:
        """The frozen set-up (names, prior, library, optimizer, differentiation) of this
        model's parameters for ``n_states`` states and ``n_inputs`` inputs. Its
        :meth:`~FitSetup.statistics` of any number of trajectories, summed, go to
        :meth:`fit_statistics`. ``sample`` (a list of
        :class:`~discrepancy.data.Trajectory`) is needed when the differentiation method
        is chosen from the data (the default); ``feature_names`` (states then inputs)
        replace the model's names."""
        self._validate_params()
        validate_params("make_setup", {"n_states": n_states, "n_inputs": n_inputs},
                        {"n_states": [Interval(Integral, 1)], "n_inputs": [Interval(Integral, 0)]})
        return resolve_setup(self, n_states, n_inputs, sample, feature_names)

    def fit_statistics(self, stats: GramStatistics, setup: FitSetup) -> DiscrepancyModel:
        """Fit from Gram statistics computed with ``setup`` (see :meth:`make_setup`);
        returns self."""
        if not isinstance(setup, FitSetup):
            raise ParameterError(f"setup must be a FitSetup (from make_setup); got "
                                 f"{type(setup).__name__}")
        if not isinstance(stats, GramStatistics):
            raise ParameterError(f"stats must be GramStatistics (from setup.statistics); got "
                                 f"{describe(stats)}")
        if (stats.p, stats.n) != (setup.n_features, setup.n_states):
            raise ShapeError(f"stats are for {stats.p} features and {stats.n} states; the set-up "
                             f"has {setup.n_features} and {setup.n_states}")
        if stats.count == 0:
            raise DataError("stats hold no samples: nothing to fit")
        if not np.any(stats.gram):
            raise DataError("the statistics are all zero: every sample has weight 0 or every "
                            "library column is 0 on these data (or so small that their "
                            "squares underflow); nothing to fit")
        diagonal = np.abs(np.diag(stats.gram))
        if np.any((diagonal > 0) & (diagonal < np.finfo(float).tiny)):
            raise DataError("a library column's weighted sum of squares is below the smallest "
                            f"normal number ({np.finfo(float).tiny:.1e}), so it has lost its "
                            "precision: rescale the data (or the sample weights)")

        optimizer = copy.deepcopy(setup.optimizer)
        optimizer.fit_statistics(stats)
        coef, chosen_by = choose_terms(self, setup, stats, optimizer)
        self._set_fit(setup, coef, optimizer, stats)
        self.forecast_selection_ = chosen_by
        self.region_ = region_of(stats.held_out, self.variable_names_)
        self.conditioning_ = warn_if_ill_conditioned(
            stats.gram, self.coef_, self.get_feature_names(), self.state_names_, stacklevel=4)
        announce(self, chosen_by)
        return self

    def _set_fit(self, setup: FitSetup, coef, optimizer, statistics) -> None:
        """Store the fitted state; compile the active terms (the hot path of evaluation)."""
        self.setup_ = setup
        self.state_names_, self.input_names_ = list(setup.state_names), list(setup.input_names)
        self.n_states_, self.n_inputs_ = setup.n_states, setup.n_inputs
        self.prior_, self.feature_library_ = setup.prior, setup.library
        self.differentiation_method_ = setup.differentiation
        self.differentiation_choice_ = setup.choice
        self.optimizer_, self.statistics_ = optimizer, statistics
        self.feature_expressions_ = list(setup.library.feature_expressions_)
        self.coef_ = np.asarray(coef, dtype=float)
        self.prior_only_ = not np.any(self.coef_)
        if not hasattr(self, "region_"):
            self.region_ = None
        converged = getattr(optimizer, "converged_", None)
        self.converged_ = None if converged is None else dict(zip(
            self.state_names_, np.asarray(converged, dtype=bool).tolist(), strict=True))
        self._compile()

    def _compile(self) -> None:
        """Compile the active terms of ``coef_`` (kept as ``_compiled_coef`` to notice edits)."""
        active = np.flatnonzero(np.any(self.coef_ != 0, axis=0))
        functions = self.setup_.library.user_functions()
        # one tape for all the active terms (a subexpression they share is computed once)
        self._active_terms = compile_numpy_many(
            [self.feature_expressions_[j] for j in active], self.variable_names_,
            functions) if len(active) else None
        self._active_coef = self.coef_[:, active].T
        self._compiled_coef = self.coef_.copy()
        self._compiled_steps = {}   # CasADi steppers of these coefficients, by substeps

    def _sync(self) -> None:
        """Recompile when ``coef_`` was edited in place since the fit (``coefficients()``
        returns it, as PySINDy's does, so such edits change predict and simulate)."""
        if not np.array_equal(self.coef_, self._compiled_coef):
            if np.shape(self.coef_) != self._compiled_coef.shape or \
                    not np.all(np.isfinite(self.coef_)):
                raise ShapeError(f"coef_ must stay finite with shape "
                                 f"{self._compiled_coef.shape}; it was changed to "
                                 f"{describe(self.coef_)}")
            self.coef_ = np.asarray(self.coef_, dtype=float)
            self._compile()

    def residual(self, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
        """``(Z, y)``: variables ``[x_smooth, u]`` ``(m, n + r)`` and ``x_dot - f_m`` ``(m, n)``."""
        self.check_is_fitted()
        if not isinstance(trajectory, Trajectory):
            raise ParameterError(f"trajectory must be a Trajectory (see "
                                 f"discrepancy.data.as_trajectories); got {describe(trajectory)}")
        return self.setup_.residual(trajectory)

    # --------------------------------------------------------------- evaluation
    @property
    def variable_names_(self) -> list[str]:
        """The states' then the inputs' names: the variables the library acts on, ``z = [x, u]``."""
        return [*self.state_names_, *self.input_names_]

    def _variables(self, x, u) -> tuple[np.ndarray, np.ndarray | None]:
        self.check_is_fitted()
        self._sync()
        x = as_2d("x", x, n_cols=self.n_states_, allow_1d=self.n_states_ == 1)
        if self.n_inputs_ == 0:
            if u is not None:
                raise ShapeError("u was given but the model was fitted without inputs")
            return x, None
        if u is None:
            raise ShapeError(f"u is required: the model was fitted with {self.n_inputs_} inputs "
                             f"{self.input_names_}")
        if is_number(u):  # one number: a constant input (PySINDy broadcasts it too)
            u = np.full((x.shape[0], 1), u)
        return x, as_2d("u", u, n_rows=x.shape[0], n_cols=self.n_inputs_, allow_1d=True)

    def _g(self, z: np.ndarray) -> np.ndarray:
        if self._active_terms is None:
            return np.zeros((z.shape[0], self.n_states_))
        theta = np.column_stack(self._active_terms(z))
        return theta @ self._active_coef

    def discrepancy(self, x, u=None) -> np.ndarray:
        """The learned correction ``g(x, u)``, ``(m, n)`` (a list for a list of ``x``)."""
        if isinstance(x, (list, tuple)):
            return [self.discrepancy(xi, ui) for xi, ui in pairs(x, u)]
        x, u = self._variables(x, u)
        return checked_discrepancy(self, x if u is None else np.hstack([x, u]))

    def predict(self, x, u=None) -> np.ndarray:
        """Hybrid model derivatives ``f_m(x, u) + g(x, u)``, ``(m, n)``; a list of ``x``
        (and of ``u``) gives a list, as in PySINDy."""
        if isinstance(x, (list, tuple)):
            return [self.predict(xi, ui) for xi, ui in pairs(x, u)]
        x, u = self._variables(x, u)
        z = x if u is None else np.hstack([x, u])
        guard(self, z, "predict")
        return self.prior_(x, u) + checked_discrepancy(self, z)

    @property
    def complexity(self) -> int:
        """Number of nonzero coefficients (PySINDy's ``complexity``)."""
        self.check_is_fitted()
        return int(np.count_nonzero(self.coef_))

    def simulate(self, x0, t, *args, u=None, compiled: bool = True, integrator=None,
                 integrator_kws=None, interpolator=None, interpolator_kws=None,
                 stop_condition=None, **options) -> np.ndarray:
        """Trajectory of the hybrid model from ``x0`` ``(n,)`` at times ``t`` ``(k,)``.

        ``u`` is an array ``(k, r)`` sampled at ``t`` (between samples ``u_hold="linear"``,
        ``"zoh"`` or ``"bandlimited"``, see :mod:`discrepancy.hybrid.inputs`) or a callable
        ``u(t) -> (r,)``. Keyword arguments go to
        :func:`discrepancy.models.simulate.simulation.integrate` (``method``, ``rtol``, ``atol``,
        ``substeps``, ``max_evaluations``); a model with a discontinuous term (``sign``) is
        stepped with fixed-step RK4 on ``t`` unless a method is given. ``method="rk4"`` with
        a sampled or no input runs compiled by CasADi when it is installed and the model can
        be expressed in it (``compiled=False`` steps in Python; same numbers): the fast way
        to simulate long records with measured inputs. A simulation that blows up or runs
        out of its evaluation budget raises SimulationError with the partial trajectory.
        Returns ``(k, n)``. PySINDy's ``integrator`` (``"solve_ivp"``, ``"odeint"``),
        ``integrator_kws``, ``interpolator`` and ``interpolator_kws`` are taken as PySINDy
        takes them (:mod:`discrepancy.models.simulate.simulate_arguments`). A discrete-time model
        iterates its map: ``t`` is the number of states to return (row 0 is ``x0``), ``u``
        has one row (or call ``u(k)``) per step and ``stop_condition(x) -> bool`` ends the
        run at the first state for which it is true (that state included), as in PySINDy.
        """
        keywords_only("simulate", args, "u")
        self.check_is_fitted()
        self._sync()
        x0 = check_vector("x0", x0, self.n_states_)
        validate_params("simulate", {"compiled": compiled}, {"compiled": [bool]})

        pysindy = dict(integrator=integrator, integrator_kws=integrator_kws,
                       interpolator=interpolator, interpolator_kws=interpolator_kws)
        if self.discrete_time:
            states = iterate(self._rhs_one, x0, t, u, self.n_states_, self.n_inputs_,
                             stop_condition=map_options(stop_condition, pysindy, options))
            guard_run(self, states, u, "simulate")
            return states
        u, integrator_kws = simulation_options(u, t, stop_condition, pysindy, options)
        if "method" not in integrator_kws and self._has_jumps():
            integrator_kws["method"] = "rk4"  # adaptive steps would chatter at the jumps
        if integrator_kws.get("method") == "rk4" and compiled and not callable(u):
            integrator_kws["compiled"] = compiled_stepper(self, x0, u,
                                                          integrator_kws.get("substeps", 4))
        states = integrate(self._rhs_one, x0, t, u, n_states=self.n_states_,
                           n_inputs=self.n_inputs_, **integrator_kws)
        guard_run(self, states, u, "simulate")
        return states

    def predict_ahead(self, x, t=None, *args, u=None, steps: int = 1,
                      u_hold: str = "linear", substeps: int = 4) -> np.ndarray:
        """``steps``-ahead predictions from measured states ``x`` ``(m, n)`` at ``t``:
        ``(m - steps, n)``, row ``i`` predicting ``x[i + steps]`` from ``x[i]`` (RK4 with
        ``substeps`` per sample, the input held by ``u_hold``). Compare with ``x[steps:]``.
        A discrete-time model iterates its map ``steps`` times from each ``x[i]`` with
        ``u[i], ..., u[i + steps - 1]`` (``t``, ``u_hold`` and ``substeps`` are not used)."""
        keywords_only("predict_ahead", args, "u and the options")
        self.check_is_fitted()
        self._sync()

        x = checked_states(self, x, u)
        if self.discrete_time:
            ahead = iterate_ahead(self._rhs_one, x, u, n_inputs=self.n_inputs_, steps=steps)
            guard_run(self, ahead, None if u is None else np.asarray(u)[:len(ahead)],
                      "predict_ahead")
            return ahead
        require_t("predict_ahead", t, needed=True)
        ahead = predict_ahead(self._rhs_one, x, t, u,
                              n_inputs=self.n_inputs_, steps=steps, u_hold=u_hold,
                              substeps=substeps)
        guard_run(self, ahead, None if u is None else np.asarray(u)[steps:], "predict_ahead")
        return ahead

    def _has_jumps(self) -> bool:
        """Whether an active term or the (symbolic) prior is discontinuous (``sign``)."""
        import sympy as sp

        active = [self.feature_expressions_[j]
                  for j in np.flatnonzero(np.any(self.coef_ != 0, axis=0))]
        prior = self.prior_.expressions or []
        return any(e.has(sp.sign) for e in [*active, *prior])

    def _rhs_one(self, x: np.ndarray, u: np.ndarray | None) -> np.ndarray:
        """``f_m + g`` for a batch of states without re-validation (hot path of simulate)."""
        z = x if u is None else np.hstack([x, u])
        return self.prior_(x, u) + self._g(z)

    # ----------------------------------------------------------------- output
    def coefficients(self) -> np.ndarray:
        """``Ξ`` as ``(n_states, n_features)``, PySINDy's layout: the model's own array, as
        in PySINDy, so editing it in place changes the model (``predict``, ``simulate``,
        ``equations``, files); copy it to keep a snapshot."""
        self.check_is_fitted()
        return self.coef_

    def get_feature_names(self) -> list[str]:
        """Names of the library's ``p`` terms, the column order of :meth:`coefficients`."""
        self.check_is_fitted()
        return [feature_name(e, self.variable_names_) for e in self.feature_expressions_]

    def equations(self, precision: int = 3, *, uncertainty=None) -> list[str]:
        """Right-hand sides as text, e.g. ``prior + 0.400 x2 - 0.400 x1^2 x2``; with
        ``uncertainty`` (:meth:`bootstrap`) each coefficient as ``0.400 ± 0.004`` (one
        bootstrap standard deviation)."""
        return equations(self, precision, uncertainty)

    def print(self, precision: int = 3, *, lhs=None, uncertainty=None) -> None:
        """Print one line per state: ``(x2)' = prior + 0.400 x2 - 0.400 x1^2 x2`` (a map:
        ``(x1)[k+1] = ...``; with
        ``± std`` when ``uncertainty`` is given; ``lhs``: a list of left-hand sides to
        print instead of ``(x1)'``, ...), then, when the derivatives were estimated with a
        method chosen from the data, a ``#`` line saying which and why."""
        lines = self.equations(precision, uncertainty=uncertainty)
        if lhs is None:
            step = "[k+1]" if self.discrete_time else "'"
            lhs = [f"({name}){step}" for name in self.state_names_]
        elif not isinstance(lhs, (list, tuple)) or len(lhs) != self.n_states_ or \
                not all(isinstance(s, str) for s in lhs):
            raise ParameterError(f"lhs must be a list of {self.n_states_} strings (one per "
                                 f"state); got {describe(lhs)}")
        for name, eq in zip(lhs, lines, strict=True):
            print(f"{name} = {eq}")
        line = choice_line(self)
        if line:
            print(line)

    def score(self, x, t=None, *args, u=None, x_dot=None, metric="r2", **metric_kws):
        """Goodness of fit on data: ``"r2"`` (mean over states) or ``"rmse"`` of the
        derivatives, a callable ``metric(truth, prediction, **metric_kws)`` of them (e.g. a
        ``sklearn.metrics`` function), or ``"trajectory"``: ``‖x_sim − x‖ / ‖x‖``
        simulating from ``x[0]`` (one trajectory). ``t`` is required unless ``x_dot`` is
        given (or the model is discrete-time). ``metric_kws`` go to the metric, as in
        PySINDy (with ``"r2"``: to ``sklearn.metrics.r2_score``, e.g.
        ``multioutput="raw_values"``)."""
        keywords_only("score", args, "u, x_dot and metric")
        self.check_is_fitted()
        self._sync()
        require_t("score", t, needed=not self.discrete_time and
                  (x_dot is None or metric == "trajectory"))
        return score(self, x, t, u, x_dot, metric=metric, metric_kws=metric_kws)

    def bootstrap(self, x, t=None, *args, u=None, x_dot=None, n_resamples: int = 200,
                  block_length: int | None = None, method: str = "wild", seed: int = 0,
                  sample_weight=None):
        """Uncertainty of every term: a block bootstrap of the fit on these data.

        ``method="wild"`` (repeat the experiment with new noise) or ``"pairs"`` (also
        resample which states were visited); see :mod:`discrepancy.models.core.uncertainty`.

        Returns a :class:`~discrepancy.models.core.uncertainty.CoefficientUncertainty` with
        ``std``, ``interval()``, ``inclusion_probability`` and a printable ``table()``.
        """
        keywords_only("bootstrap", args, "u, x_dot and the options")
        require_t("bootstrap", t, needed=x_dot is None and not self.discrete_time)
        return bootstrap(self, x, t, u, x_dot, n_resamples=n_resamples,
                         block_length=block_length, method=method, seed=seed,
                         sample_weight=sample_weight)

    def predict_interval(self, x, u=None, *, uncertainty, level: float = 0.95):
        """Pointwise ``level`` band ``(low, high)``, each ``(m, n)``, of the hybrid
        derivatives ``f_m + g`` over the bootstrap's resampled coefficients
        (``uncertainty`` = :meth:`bootstrap` of this model)."""
        return predict_interval(self, x, u, uncertainty, level)

    def simulate_interval(self, x0, t, *args, u=None, uncertainty, level: float = 0.95,
                          n_draws: int | None = 100, seed: int = 0, **integrator_kws):
        """Pointwise ``level`` band ``(low, high)``, each ``(k, n)``, of trajectories
        simulated with ``n_draws`` of the bootstrap's resampled models (all with ``None``).
        It holds the coefficients' uncertainty, not the measurement noise. Resampled models
        that diverge are left out, with a warning."""
        keywords_only("simulate_interval", args, "u and the options")
        self.check_is_fitted()
        return simulate_interval(self, x0, t, u, uncertainty, level, n_draws, seed,
                                 **integrator_kws)

    def with_coefficients(self, coef) -> DiscrepancyModel:
        """A copy of this fitted model with coefficients ``coef`` ``(n, p)`` (e.g. one
        bootstrap resample); shares the set-up."""
        self.check_is_fitted()
        coef = as_float_array("coef", coef)
        if coef.shape != self.coef_.shape:
            raise ShapeError(f"coef must have shape {self.coef_.shape}; got {coef.shape}")
        if not np.all(np.isfinite(coef)):
            raise DataError(f"coef must be finite; got {np.sum(~np.isfinite(coef))} "
                            "non-finite entries")
        other = copy.copy(self)
        other._set_fit(self.setup_, coef, self.optimizer_, None)
        other.differentiation_choice_ = self.differentiation_choice_
        return other

    # ------------------------------------------------------------------ export
    def to_sympy(self, part: str | None = None):
        """Equations as sympy expressions, one per state.

        ``part="hybrid"`` gives ``f_m + g`` and needs a sympy prior (or none);
        ``"discrepancy"`` gives ``g`` alone. The default is the hybrid model when the
        prior is symbolic or absent, and the discrepancy when it is a Python callable.
        """
        return to_sympy(self, part)

    def to_latex(self, precision: int = 4, part: str | None = None) -> str:
        """LaTeX ``aligned`` block of the equations, coefficients rounded to ``precision``."""
        return to_latex(self, precision, part)

    def to_casadi(self, part: str | None = None):
        """CasADi ``Function`` ``f(x, u) -> xdot`` (``f(x)`` without inputs), exact; for a
        discrete-time model the map ``f(x, u) -> x_next``.

        The default is the whole hybrid model, which needs a sympy prior: a callable
        prior raises ExportError (ask for ``part="discrepancy"`` to get ``g`` alone).
        """
        return to_casadi(self, part)

    # ------------------------------------------------------------------- files
    def to_state(self) -> dict:
        """The fitted model as a JSON-compatible dict (the model file's content)."""
        self.check_is_fitted()
        return encode(self)

    @classmethod
    def from_state(cls, state: dict, *, prior=None, functions=None) -> DiscrepancyModel:
        """A fitted model from :meth:`to_state`'s dict, validated (nothing is evaluated).

        ``prior``: the callable prior, when the state says it was one (code is never
        stored); ``functions``: numpy functions of custom terms, by the names it lists.
        """
        fields = decode(state, prior=prior, functions=functions)
        given = fields["parameters"]   # empty before version 4: the defaults
        check_parameters(cls, given, corrupted)
        optimizer = fields["optimizer"]
        if optimizer is None and given.get("optimizer") is not FITTED:
            optimizer = given.get("optimizer")
        model = cls(prior=fields["prior"], feature_library=fields["library"],
                    optimizer=optimizer,
                    differentiation_method=fields["differentiation_method"],
                    state_names=fields["state_names"], input_names=fields["input_names"],
                    constraints=given.get("constraints"),
                    discrete_time=given.get("discrete_time", False),
                    selection=given.get("selection", "auto"))
        setup = model.make_setup(len(fields["state_names"]), len(fields["input_names"]))
        optimizer = copy.deepcopy(setup.optimizer)
        optimizer.coef_ = fields["coefficients"]
        model._set_fit(setup, fields["coefficients"], optimizer, None)
        model.differentiation_choice_ = fields["differentiation_choice"]
        model.region_, model.forecast_selection_ = fields["region"], None
        model.set_params(**{k: v for k, v in given.items() if v is not FITTED})
        return model

    @classmethod
    def from_prior(cls, prior, *, state_names=None, input_names=None,
                   discrete_time: bool = False) -> DiscrepancyModel:
        """The prior alone as a fitted model, without data: no correction (``prior_only_``
        is True), simulated, scored, exported and saved like any fitted model. The states
        are ``state_names`` or, for a sympy prior, one per expression; inputs
        ``input_names`` (none by default). With data, ``DiscrepancyModel(prior=f_m,
        optimizer="prior_only").fit(x, t)`` gives the same model."""
        names = [state_names] if isinstance(state_names, str) else state_names
        if names is None and not isinstance(prior, (list, tuple)):
            raise ParameterError("from_prior needs state_names (the states of a callable "
                                 "prior); a sympy prior gives them by its length")
        n = len(prior) if names is None else len(names)
        inputs = [input_names] if isinstance(input_names, str) else (input_names or [])
        model = cls(prior=prior, optimizer="prior_only", state_names=state_names,
                    input_names=input_names if inputs else None, discrete_time=discrete_time)
        setup = model.make_setup(n, len(inputs))
        model._set_fit(setup, np.zeros((n, setup.n_features)), copy.deepcopy(setup.optimizer),
                       None)
        model.differentiation_choice_, model.forecast_selection_ = None, None
        return model

    def save(self, path) -> None:
        """Write the fitted model as versioned JSON (atomically: a failed write never
        destroys an existing file)."""
        write_json(path, self.to_state())


def load_model(path, prior=None, *, functions=None) -> DiscrepancyModel:
    """Load a model saved with :meth:`DiscrepancyModel.save` (see
    :meth:`~DiscrepancyModel.from_state` for ``prior`` and ``functions``)."""
    return DiscrepancyModel.from_state(read_json(path), prior=prior, functions=functions)
