"""The model's prediction-error method: fitting the discrepancy and the noise levels by the
one-step innovations of a Kalman filter (see :mod:`discrepancy.estimation.pem`), and the
filter of the fitted model."""
from __future__ import annotations

from ...errors import NotFittedError, ParameterError
from ...estimation import ExtendedKalmanFilter, UnscentedKalmanFilter
from ...estimation.pem import fit_prediction_error
from .arguments import keywords_only


class PredictionErrorMethods:
    """Mixed into :class:`~discrepancy.models.DiscrepancyModel`."""

    def fit_prediction_error(self, y, t=None, *args, u=None, outputs=None, disturbances=None,
                             process_noise=None, measurement_noise=None, x0=None,
                             u_hold: str = "linear", substeps: int = 4,
                             max_terms: int | None = None, holdout: float = 0.25,
                             tolerance: float | None = None, progress: bool | None = None):
        """Learn the discrepancy and the noise levels by the prediction-error method: the
        hybrid model runs inside an extended Kalman filter, and its coefficients, the
        process noise and the measurement noise minimise the negative log-likelihood of the
        filter's one-step innovations (exact gradients through the filter by CasADi,
        ``[control]``). Unlike output error
        (:meth:`~discrepancy.DiscrepancyModel.fit_outputs`), the state is corrected at every
        sample, so process noise, unmeasured disturbances and unstable or chaotic dynamics
        do not bend the fit.

        Args:
            y: recorded outputs ``(m, k)`` (NaN where an output was not measured), or a
                list per record.
            t: time step or times ``(m,)`` (a list per record).
            u: inputs ``(m, r)`` or a list per record.
            outputs: what each column of ``y`` measures: a state (name or index) or a sympy
                expression in the state names.
            disturbances: states (names or indices) whose equations get an unmeasured
                random-walk force ``d_<name>``, estimated as an extra state with a fitted
                intensity (a push, a load change, a slope the model does not know).
            process_noise: std per state and then per disturbance (per √s) to use instead of
                fitting them, NaN for those to fit (e.g. ``[0, np.nan]`` for a kinematic
                equation without noise); by default all are fitted.
            measurement_noise: std per output to use instead of fitting them (NaN: fit).
            x0: the initial state ``(n,)`` (one per record) the filter starts from; by
                default measured states at their first sample and the others at 0, with a
                broad uncertainty (the first samples do not count in the fit).
            u_hold, substeps: the input between samples and RK4 steps per interval, as in
                :meth:`~discrepancy.DiscrepancyModel.fit_outputs`.
            max_terms, holdout, tolerance: with the optimizer's ``threshold="auto"`` (the
                default) supports from the whole allowed library down to none are fitted on
                the first part of every record and scored by the innovations' likelihood on
                the last ``holdout``; the sparsest within one standard error of the best (or
                within ``tolerance`` nats per sample) is refitted on everything. A numeric
                threshold drops coefficients below it instead.

        After the fit: ``process_noise_`` and ``measurement_noise_`` (dicts of stds by
        name), ``x0_`` (smoothed initial state of each record), ``prediction_error_`` (a
        :class:`~discrepancy.estimation.pem.PredictionErrorFit`: the scored path, the
        choice, the fit's negative log-likelihood per sample); :meth:`kalman_filter`
        gives the filter of the fitted model with these noise levels.

        From :data:`~discrepancy.estimation.likelihood.COMPILE_SAMPLES` samples the
        likelihood is compiled to C (about ten times faster per evaluation; the libraries
        are cached, see :mod:`~discrepancy.hybrid.codegen`); without a C compiler it runs in
        CasADi's virtual machine with the same results and a
        :class:`~discrepancy.errors.CompilationWarning`.
        """
        keywords_only("fit_prediction_error", args, "u, outputs and the options")
        self._validate_params()
        setup, fit = fit_prediction_error(
            self, y, t, u, outputs=outputs, disturbances=disturbances,
            process_noise=process_noise, measurement_noise=measurement_noise, x0=x0,
            u_hold=u_hold, substeps=substeps, max_terms=max_terms, holdout=holdout,
            tolerance=tolerance, progress=progress)
        self._set_fit(setup, fit.coef, None, None)
        self.prediction_error_ = fit
        self.process_noise_, self.measurement_noise_ = fit.process_noise, fit.measurement_noise
        self.x0_ = list(fit.x0) if isinstance(y, (list, tuple)) else fit.x0[0]
        self.output_names_ = list(fit.outputs)
        return self

    def kalman_filter(self, kind: str = "ekf", **options):
        """The :class:`~discrepancy.estimation.ExtendedKalmanFilter` (``kind="ukf"``: the
        unscented one) of this model with the outputs, disturbances and noise levels of
        its :meth:`fit_prediction_error`; ``options`` override any of them."""
        self.check_is_fitted()
        fit = getattr(self, "prediction_error_", None)
        if kind not in ("ekf", "ukf"):
            raise ParameterError(f"kind must be 'ekf' or 'ukf'; got {kind!r}")
        if fit is None and not {"outputs", "process_noise", "measurement_noise"} <= set(options):
            raise NotFittedError("kalman_filter needs the noise levels of fit_prediction_error,"
                                 " or outputs=, process_noise= and measurement_noise=")
        settings = {} if fit is None else {
            "outputs": fit.outputs, "disturbances": fit.disturbances or None,
            "process_noise": list(fit.process_noise.values()),
            "measurement_noise": list(fit.measurement_noise.values()),
            "substeps": fit.substeps, "u_hold": fit.u_hold}
        cls = ExtendedKalmanFilter if kind == "ekf" else UnscentedKalmanFilter
        return cls(self, **{**settings, **options})
