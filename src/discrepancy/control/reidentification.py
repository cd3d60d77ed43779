"""Learning the discrepancy from closed-loop logs at the control rate, with partial noisy
measurements: a Kalman smoother estimates the states, a one-step prediction error fits.

A controller logs what it measured at every control sample (every 20 ms for the cart), often
not every state. Differentiating such a log fails twice: 20 ms pieces between input jumps
are too short to differentiate through noise, and unmeasured states have no samples.
:class:`SmoothedLogUpdater` instead

1. runs an extended Kalman filter and its Rauch–Tung–Striebel smoother
   (:mod:`discrepancy.estimation`) on the current model (the prior, then the last model
   learned; in later passes the model just fitted) over the whole log: every state at every
   sample, the input held between samples as the controller held it. The process-noise
   intensity (one number for the rows the discrepancy may act on) is the one whose filter
   best predicts the measurements (largest innovation likelihood on a grid: the
   prediction-error criterion, no tuning by hand);
2. fits the discrepancy ``g = Ξ θ(x, u)`` so that the hybrid model's step over each
   control interval, from the smoothed state, lands on the next smoothed state. The step
   is the prior's RK4 flow plus ``g``; the fit iterates ``target_k = (x̂_{k+1} -
   Φ_Ξ(x̂_k, u_k)) / dt + Ξ θ̄_k`` on ``θ̄_k`` (θ averaged over the interval's two ends) to
   a fixed point, each iteration one sparse regression of the model's own optimizer (its
   cross-validated threshold, constraints, ...). At the fixed point the one-step residuals
   are orthogonal to the chosen terms, and the ``O(dt²)`` coupling a discrepancy in one
   state has on the others over an interval is in the flow, not left to spurious terms.

``kinematics``: rows the estimator integrates exactly, ``{"phi1": "dphi1"}`` for
``(phi1)' = dphi1``: the definition of velocity states in mechanical coordinates. With
angles measured and their rates not, an estimator that trusted a prior's wrong kinematic
row would move the wrong into the unmeasured rates (a change of coordinates the
measurements cannot see); with the definition imposed, the rates are the angles'
derivatives and the kinematic row's error shows in the one-step residuals.

Logs accumulate: the model after ``k`` updates is fitted on all ``k`` smoothed logs, as
with :class:`~.learning.DiscrepancyUpdater`.
"""
from __future__ import annotations

import copy

import numpy as np

from ..constraints import Integral, Interval, check_argument
from ..differentiation import FiniteDifference
from ..errors import ParameterError, ShapeError, describe
from ..estimation import ExtendedKalmanFilter
from ..estimation.dynamics import dynamics_of
from ..symbolic import symbol
from .one_step import OneStepFit

#: process-noise intensities tried (units of the state per second per √second)
PROCESS_NOISE_GRID = tuple(np.logspace(-3, 1, 9))


class SmoothedLogUpdater:
    """Accumulates control-rate logs of measured outputs and refits the discrepancy.

    Args:
        model: an unfitted :class:`~discrepancy.DiscrepancyModel` with a sympy prior and
            its state and input names (copied, never changed).
        outputs: the measured state names, in the log's column order.
        measurement_noise: std per output (the sensors').
        kinematics: ``{state: rate state}`` rows the estimator integrates exactly.
        process_noise: ``"auto"`` (chosen per log by the filter's likelihood, see the
            module docstring) or a std per state (units per √s; 0 on kinematic rows).
        start: the model the first log is smoothed with (a fitted hybrid model or
            ``(states, inputs, rhs)`` sympy equations); default the prior.
        optimizer: the sparse regression (default: the model's own). Thresholds on
            normalised columns (``STLSQ(threshold="auto", normalize_columns=True)``) suit
            libraries whose columns differ in scale (an input of 20 beside sines of 1).
        substeps: RK4 steps per control interval in the estimator and the fit.
        max_sweeps: most fixed-point iterations of the fit.
        passes: most rounds of smoothing and fitting per update. The first chooses the
            terms; the others re-smooth with the latest model and refit those terms (the
            smoother leans towards the model it runs; re-smoothing with the learned model
            removes that pull), stopping when the coefficients settle (0.1 %).

    Attributes (after :meth:`update`): ``models_`` (one per update), ``smoothed_`` (the
    smoothed states of every log by the last model, ``(m, n)`` each), ``process_noise_``
    (the process-noise std per state used for each log), ``process_noise_passes_`` (the
    same for every pass of the last update: the first pass's is chosen with the model the
    update started from), ``sweeps_`` (iterations of the last fit).
    """

    def __init__(self, model, *, outputs, measurement_noise, kinematics=None,
                 process_noise="auto", start=None, optimizer=None, substeps: int = 4,
                 max_sweeps: int = 20, passes: int = 4):
        self.model, self.outputs, self.optimizer = model, outputs, optimizer
        self.measurement_noise, self.kinematics = measurement_noise, kinematics
        self.process_noise, self.start = process_noise, start
        self.substeps, self.max_sweeps = substeps, max_sweeps
        self.passes = passes
        self.models_, self.smoothed_, self.process_noise_, self._raw = [], [], [], []

    # ------------------------------------------------------------------ public
    def update(self, y, t, *, u):
        """Add one log and refit; returns the new fitted model.

        Args:
            y: ``(m, k)`` measured outputs at the control samples (NaN where missing).
            t: the control period (s).
            u: ``(m, r)`` inputs, ``u[k]`` held from sample ``k`` to ``k + 1``.
        """
        setup = self._setup()
        if not (isinstance(t, (int, float, np.floating)) and np.isfinite(t) and t > 0):
            raise ParameterError(f"t must be the control period (s) of the log; got {t!r}")
        u = np.asarray(u, dtype=float)
        y = np.asarray(y, dtype=float)
        if y.ndim != 2 or y.shape[1] != len(self.outputs) or u.shape != (len(y),
                                                                          setup.n_inputs):
            raise ShapeError(f"y must be (m, {len(self.outputs)}) and u (m, "
                             f"{setup.n_inputs}); got {y.shape} and {u.shape}")
        if len(y) < 3:
            raise ShapeError(f"a log needs at least 3 samples; got {len(y)}")
        self._raw.append((y, float(t), u))
        current = self.models_[-1] if self.models_ else self.start
        levels, chosen, self.process_noise_passes_ = [None] * len(self._raw), None, []
        for _ in range(self.passes):
            smoothed = [self._smooth(setup, current, *log, previous=level)
                        for log, level in zip(self._raw, levels, strict=True)]
            levels = [float(np.max(q)) or None for _, q in smoothed]
            self.process_noise_passes_.append([q for _, q in smoothed])
            self._logs = [(x, log[2], log[1]) for (x, _), log in
                          zip(smoothed, self._raw, strict=True)]
            fitted, self.sweeps_ = self._one_step.fit(
                self._logs, self.models_[-1].coefficients() if self.models_ else None, chosen)
            chosen = fitted if chosen is None else chosen
            settled = current is not None and hasattr(current, "coefficients") and \
                np.allclose(fitted.coefficients(), current.coefficients(), rtol=1e-3,
                            atol=1e-6 * max(np.max(np.abs(fitted.coefficients())), 1e-12))
            current = fitted
            if settled:
                break
        self.smoothed_ = [x for x, _ in smoothed]
        self.process_noise_ = [q for _, q in smoothed]
        self.models_.append(fitted)
        return fitted

    def update_from(self, run):
        """:meth:`update` with the control log of a :class:`~.closed_loop.ClosedLoopRun`."""
        y, dt, u = self.log_of(run)
        return self.update(y, dt, u=u)

    def log_of(self, run):
        """``(y, t, u)`` of a :class:`~.closed_loop.ClosedLoopRun` for :meth:`update`: its
        control-rate log, the columns of ``outputs``."""
        y, dt, u = run.control_log()
        measured = list(range(run.x.shape[1])) if run.outputs is None else list(run.outputs)
        names = self._setup().state_names
        cols = [measured.index(names.index(o)) for o in self.outputs]
        return y[:, cols], dt, u

    # ---------------------------------------------------------------- smoothing
    def _setup(self):
        if not hasattr(self, "setup_"):
            model = self.model
            if not hasattr(model, "make_setup") or not isinstance(model.prior, (list, tuple)):
                raise ParameterError(f"model must be an unfitted DiscrepancyModel with a sympy "
                                     f"prior (a list of expressions); got {describe(model)}")
            _check_settings(self)
            self._template = copy.deepcopy(model)
            if self.optimizer is not None:
                self._template.optimizer = copy.deepcopy(self.optimizer)
            # no derivative is taken here: a fixed method keeps make_setup from choosing one
            self._template.differentiation_method = FiniteDifference()
            n, r = len(model.prior), len(model.input_names or [])
            self.setup_ = self._template.make_setup(n, r)
            names = list(self.setup_.state_names)
            unknown = sorted({*self.outputs, *self._kinematics, *self._kinematics.values()}
                             - set(names))
            if unknown:
                raise ParameterError(f"outputs and kinematics name unknown states {unknown}; "
                                     f"the states are {names}")
            self._one_step = OneStepFit(self.setup_, self._template, self.substeps,
                                        self.max_sweeps)
        return self.setup_

    def _equations(self, setup, current) -> list:
        """The estimator's right-hand sides: the current model with the kinematic rows."""
        if current is None:
            rhs = list(setup.prior.expressions)
        elif hasattr(current, "to_sympy"):
            rhs = list(current.to_sympy(part="hybrid"))
        else:
            rhs = list(current[2])
        names = list(setup.state_names)
        for state, rate in self._kinematics.items():
            rhs[names.index(state)] = symbol(rate)
        return rhs

    def _smooth(self, setup, current, y, dt, u, previous=None):
        names = list(setup.state_names)
        # the model is written in CasADi once; each noise level only rebuilds the filter steps
        dynamics = dynamics_of(self._equations(setup, current), state_names=names,
                               input_names=list(setup.input_names))
        free = np.array([name not in self._kinematics for name in names], dtype=float)

        def filter_with(q):
            ekf = ExtendedKalmanFilter(dynamics, outputs=self.outputs, process_noise=q,
                                       measurement_noise=self.measurement_noise,
                                       substeps=self.substeps, u_hold="zoh")
            return ekf, ekf.filter(y, dt, u=u)

        if isinstance(self.process_noise, str):
            if self.process_noise != "auto":
                raise ParameterError(f"process_noise must be 'auto' or a std per state; got "
                                     f"{self.process_noise!r}")
            grid = PROCESS_NOISE_GRID if previous is None else \
                [level for level in PROCESS_NOISE_GRID
                 if abs(np.log10(level / previous)) < 0.6]
            level, run = _most_likely(filter_with, grid, free)
            q = level * free
            # no level scored: the first is run again, and a diverging filter raises here
            ekf, result = run or filter_with(q)
        else:
            q = np.broadcast_to(np.asarray(self.process_noise, dtype=float), free.shape)
            ekf, result = filter_with(q)
        return ekf.smooth(result)[0], q


def _check_settings(updater) -> None:
    """The constructor's arguments, checked when first needed (the estimator contract)."""
    outputs, kin = updater.outputs, updater.kinematics
    if isinstance(outputs, str) or not isinstance(outputs, (list, tuple)) or not outputs \
            or not all(isinstance(o, str) for o in outputs) or len(set(outputs)) < len(outputs):
        raise ParameterError(f"outputs must be a list of distinct state names; got "
                             f"{outputs!r}")
    if kin is not None and not (isinstance(kin, dict) and all(
            isinstance(a, str) and isinstance(b, str) for a, b in kin.items())):
        raise ParameterError(f"kinematics must be a dict {{state: rate state}} of names; got "
                             f"{kin!r}")
    for name in ("substeps", "max_sweeps", "passes"):
        check_argument(name, getattr(updater, name), Interval(Integral, 1))
    updater.outputs, updater._kinematics = list(outputs), dict(kin or {})


def _most_likely(filter_with, grid, free):
    """The first level of ``grid`` whose filter (process noise ``level * free``) has the
    largest innovation likelihood, with its ``(filter, result)`` (None if every one
    diverged; then the first level). Only the best run is kept: a long log's covariances
    are large."""
    best, best_score, best_run = grid[0], -np.inf, None
    for level in grid:
        try:
            run = filter_with(level * free)
        except (ArithmeticError, ValueError, np.linalg.LinAlgError):  # a diverging filter
            continue
        score = float(run[1].log_likelihood)
        if score > best_score:
            best, best_score, best_run = level, score, run
    return best, best_run
