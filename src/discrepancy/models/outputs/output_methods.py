"""The model's output-error methods: fitting, refining and starting from measured outputs
when some states are not measured (see :mod:`discrepancy.models.outputs.output_error`)."""
from __future__ import annotations

import numpy as np

from ...optimizers import PriorOnly, get_optimizer
from ..core.arguments import keywords_only

_COMMON = """
            y: recorded outputs ``(m, k)`` (1-D for one), or a list per trajectory.
            t: time step or times ``(m,)`` (a list per trajectory).
            u: inputs ``(m, r)`` or a list per trajectory.
            outputs: what each column of ``y`` measures: a state (name or index) or a
                sympy expression in the state names (``sp.Min(h2, 10)`` for a saturating
                sensor).
            x0: a guess of the initial state ``(n,)`` (or one per trajectory); by default
                measured states start at their first sample and the others at 0. Every
                initial state is estimated, within ``x0_bounds`` = ``(lower, upper)``
                (numbers or one per state) when given (e.g. levels that cannot be negative).
            u_hold: the input between samples (``"linear"``, ``"zoh"``, ``"bandlimited"``).
            substeps: RK4 steps per sample interval (simulate the result with the same
                ``method="rk4"``, ``substeps`` and ``u_hold``)."""


class OutputErrorMethods:
    """Mixed into :class:`~discrepancy.models.DiscrepancyModel`."""

    def fit_outputs(self, y, t=None, *args, u=None, outputs=None, x0=None, x0_bounds=None,
                    u_hold: str = "linear", substeps: int = 4, max_terms: int | None = None,
                    holdout: float = 0.25, tolerance: float | None = None,
                    progress: bool | None = None):
        """Learn the discrepancy from measured outputs when some states are not measured
        (output error: the simulation of ``f_m + g`` from estimated initial states, with the
        measured input, is fitted to the recorded outputs). Needs CasADi (``[control]``).

        Args:{common}
            max_terms: the most terms the fit may start from (the most important are kept).
            holdout, tolerance: with the optimizer's ``threshold="auto"`` (the default),
                supports are compared by forecasting the last ``holdout`` of every record
                after fitting the rest; the sparsest within one standard error of the best
                (or within ``tolerance``, relative) is refitted on everything. A numeric
                threshold drops coefficients below it instead. Term masks of
                ``constraints`` are honoured. The model's states come from
                ``state_names``, a sympy prior or ``x0``.
            progress: a progress bar over the supports tried (tqdm); ``None``: only on a
                terminal.

        After the fit, ``x0_`` holds the estimated initial states, ``output_selection_``
        the scored supports, ``output_error_`` the scaled RMS output error of the fit and
        ``uncertainty_`` the coefficients' uncertainty (a Gauss–Newton sandwich over blocks
        of samples, as draws: ``model.print(uncertainty=model.uncertainty_)``). The path
        ends with no term: when that is chosen the model is the prior alone
        (``prior_only_``, with a ``PriorOnlyWarning``). ``region_`` is the range of the
        states along the fitted simulation and of the inputs (``simulate`` warns beyond).
        """
        keywords_only("fit_outputs", args, "u, outputs and the options")
        self._refuse_maps("fit_outputs")
        from .output_fit import fit_outputs

        self._validate_params()
        if isinstance(get_optimizer(self.optimizer), PriorOnly):
            return self._fit_prior_outputs(y, t, u, outputs=outputs, x0=x0,
                                           x0_bounds=x0_bounds, u_hold=u_hold,
                                           substeps=substeps)
        setup, coef, x0s, fit, path, error, worse = fit_outputs(
            self, y, t, u, outputs=outputs, x0=x0, x0_bounds=x0_bounds, u_hold=u_hold,
            substeps=substeps, max_terms=max_terms, holdout=holdout, tolerance=tolerance,
            progress=progress)
        self._set_fit(setup, coef, None, None)
        self._keep_outputs(y, x0s, fit, error)
        self.output_selection_ = path
        self._after_output_fit(y, t, u, x0s, substeps, u_hold, chosen_by_path=bool(path),
                               prior_because=worse)
        return self

    def refine(self, y, t=None, *args, u=None, outputs=None, x0=None, x0_bounds=None,
               u_hold: str = "linear", substeps: int = 4):
        """Refit the nonzero coefficients of a fitted model (and the initial states) by
        output error on measured outputs, keeping its terms: e.g. after a derivative-based
        fit whose derivatives were noisy or whose velocities were estimated. Sets ``x0_``,
        ``output_error_`` and ``uncertainty_`` as :meth:`fit_outputs` does.

        Never worse than the model it starts from on held-out forecasts: the refit is
        repeated on the first 75 % of every record and both models forecast the rest;
        when the refit forecasts worse, the coefficients are kept (only the initial states
        are estimated) with a ``SelectionWarning``. ``refine_check_`` holds both held-out
        errors and the outcome (:func:`discrepancy.models.outputs.output_checks.check_refine`).
        A model with no terms (the prior alone) has nothing to refit: its initial states
        are estimated, with a ``PriorOnlyWarning`` that says so.

        Args:{common}
        """
        keywords_only("refine", args, "u, outputs and the options")
        self.check_is_fitted()
        self._refuse_maps("refine")
        from .output_fit import refit_outputs

        if not np.any(self.coef_):
            import warnings

            from ...errors import PriorOnlyWarning
            warnings.warn("refine keeps a model's terms and this one has none (the prior "
                          "alone): only its initial states are estimated. To let output error "
                          "choose terms, use fit_outputs with a feature_library",
                          PriorOnlyWarning, stacklevel=2)

        before = self.coef_.copy()
        coef, x0s, fit = refit_outputs(self, y, t, u, outputs=outputs, x0=x0,
                                       x0_bounds=x0_bounds, u_hold=u_hold,
                                       substeps=substeps, coefficients=True)
        from .output_checks import check_refine

        kw = dict(outputs=outputs, x0=x0, x0_bounds=x0_bounds, u_hold=u_hold,
                  substeps=substeps)
        self.refine_check_ = check_refine(self, before, y, t, u, **kw)
        if self.refine_check_["kept_original"]:   # the refit forecast worse: keep the model
            coef, x0s, fit = refit_outputs(self, y, t, u, coefficients=False, **kw)
        self._set_fit(self.setup_, coef, self.optimizer_, self.statistics_)
        self._keep_outputs(y, x0s, fit, fit.error(coef, x0s, [np.ones(r.m, bool)
                                                               for r in fit.records]))
        return self

    def estimate_initial_state(self, y, t=None, *args, u=None, outputs=None, x0=None,
                               x0_bounds=None, u_hold: str = "linear", substeps: int = 4):
        """The initial state ``(n,)`` (a list for a list of records) that makes the fitted
        model's simulation best match measured outputs (e.g. the first samples of a test
        record); the model is unchanged. The state is fitted from several starts (``x0``
        when given, the measured states with the others at 0, the unmeasured ones at either
        sign of the outputs' size, solutions of ``h(x) = y[0]`` for an output map, the
        model's steady state with the first input) and the best fit kept per record; when
        even that fits the outputs with an RMS error above a quarter of their spread,
        :class:`~discrepancy.errors.InitialStateWarning` says how poorly.

        Args:{common}
        """
        keywords_only("estimate_initial_state", args, "u, outputs and the options")
        self.check_is_fitted()
        self._refuse_maps("estimate_initial_state")
        from .output_fit import estimate_initial_states

        x0s = estimate_initial_states(self, y, t, u, outputs=outputs, x0=x0,
                                      x0_bounds=x0_bounds, u_hold=u_hold, substeps=substeps)
        return list(x0s) if isinstance(y, (list, tuple)) else x0s[0]

    def _refuse_maps(self, method: str) -> None:
        """Output error integrates an ODE: a discrete-time model is refused by name."""
        if self.discrete_time is True:
            from ...errors import ParameterError
            raise ParameterError(f"{method} simulates continuous-time models (an ODE with "
                                 "RK4 between samples); this model is discrete_time=True. For "
                                 "a map, fit the successors (fit(x, u=u)) or filter with "
                                 "ExtendedKalmanFilter(model, ...)")

    def _fit_prior_outputs(self, y, t, u, *, outputs, x0, x0_bounds, u_hold, substeps):
        """The prior alone by output error: only the initial states are estimated."""
        import copy

        from ...data.trajectory import as_trajectories
        from .output_checks import state_count
        from .output_fit import refit_outputs

        first = as_trajectories(y, t, u, x_name="y")[0]
        setup = self.make_setup(state_count(self, x0), 0 if first.u is None else
                                first.u.shape[1])
        self._set_fit(setup, np.zeros((setup.n_states, setup.n_features)),
                      copy.deepcopy(setup.optimizer), None)
        coef, x0s, fit = refit_outputs(self, y, t, u, outputs=outputs, x0=x0,
                                       x0_bounds=x0_bounds, u_hold=u_hold, substeps=substeps,
                                       coefficients=False)
        self.x0_ = list(x0s) if isinstance(y, (list, tuple)) else x0s[0]
        self.output_error_ = fit.error(coef, x0s, [np.ones(rec.m, bool) for rec in fit.records])
        self.output_names_ = list(fit.out_map.names)
        self.uncertainty_, self.output_selection_ = None, []
        self._after_output_fit(y, t, u, x0s, substeps, u_hold, chosen_by_path=False)
        return self

    def _after_output_fit(self, y, t, u, x0s, substeps, u_hold, *, chosen_by_path,
                          prior_because=None):
        """The region along the fitted simulation; a prior-only outcome flagged (with
        ``prior_because`` when the chosen support was set aside after the path)."""
        import warnings

        from ...errors import PriorOnlyWarning
        from .output_checks import simulated_region

        self.forecast_selection_, self.region_ = None, None
        self.region_ = simulated_region(self, y, t, u, x0s=x0s, substeps=substeps,
                                        u_hold=u_hold)
        if prior_because:
            warnings.warn(prior_because, PriorOnlyWarning, stacklevel=3)
        elif chosen_by_path and self.prior_only_:
            warnings.warn("no support forecast the held-out end of the records better than "
                          "the prior alone: the model is the prior alone (model.prior_only_ "
                          "is True; model.output_selection_ has every support's score)",
                          PriorOnlyWarning, stacklevel=3)

    def _keep_outputs(self, y, x0s, fit, error):
        from .output_fit import sandwich_uncertainty

        self.x0_ = list(x0s) if isinstance(y, (list, tuple)) else x0s[0]
        self.output_error_ = error
        self.output_names_ = list(fit.out_map.names)
        covariance = getattr(fit, "covariance", None)   # none when only x0 was fitted
        self.uncertainty_ = None if covariance is None else sandwich_uncertainty(
            self, covariance, fit.covariance_blocks - 1)

    fit_outputs.__doc__ = fit_outputs.__doc__.format(common=_COMMON)
    refine.__doc__ = refine.__doc__.format(common=_COMMON)
    estimate_initial_state.__doc__ = estimate_initial_state.__doc__.format(common=_COMMON)
