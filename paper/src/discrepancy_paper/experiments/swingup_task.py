"""A swing-up campaign on any system: plan, track (TVLQR or MPC), judge with limits, learn.

:class:`SwingUpTask` holds every setting of a campaign (fixed before any run) and the
steps the experiments compose: a plan on a model, a TVLQR or MPC law for it, a closed
loop on a plant with measurement noise, the verdict (final state near the goal AND the
rail, input and rate limits kept), the discrepancy model to learn, and an MPC attempt
for :func:`discrepancy.control.learn_by_attempts`. Nothing here knows which system it is.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from discrepancy import STLSQ, DiscrepancyModel, SavitzkyGolay
from discrepancy.control import (
    MPC,
    Limits,
    OutputFeedback,
    SmoothedLogUpdater,
    as_casadi,
    closed_loop,
    plan_trajectory,
    swing_up_errors,
    tvlqr,
)
from discrepancy.errors import ConvergenceError, InfeasibleError


@dataclass(frozen=True)
class SwingUpTask:
    """Settings of a swing-up campaign.

    Attributes:
        state_names, input_names: the system's variables.
        x_start, x_goal: ``(n,)`` hanging at rest and upright at rest.
        angles, rates: state indices judged at the end (angles wrapped to [-pi, pi)).
        T, n_intervals, substeps: the plan's horizon (s), hold intervals, RK4 steps each.
        balance_time: how long the controller balances after the plan (s); the run is
            judged at ``T + balance_time``.
        Q, R: weights of the plan's tracking cost, the TVLQR and the MPC.
        limits: rail, input and rate limits (planning, actuator, verdict).
        mpc_backoff: ``{state: margin}`` by which the MPC tightens its state bounds.
        mpc_options: keyword arguments of :class:`~discrepancy.control.MPC`.
        noise_std: ``(n,)`` standard deviation of the measurement noise.
        log_samples: samples logged per hold interval (for learning).
        library: ``() -> FeatureLibrary`` of the discrepancy.
        smoothing: Savitzky-Golay polynomial degree (window: one hold interval).
        measured: the states the sensors measure in output feedback (e.g. the angles and
            the cart's position); their noise is ``noise_std``'s.
        kinematics: ``{position: rate}``: rate states defined as the positions' derivatives
            (the re-identification's estimator integrates them exactly).
        initial_std: ``(n,)`` std of the belief about ``x_start`` (the filter's start).
        reference_mpc: MPC options of the reference solver (IPOPT) run beside the real-time
            one for timing and success.
    """

    state_names: tuple
    input_names: tuple
    x_start: np.ndarray
    x_goal: np.ndarray
    angles: tuple
    rates: tuple
    T: float
    n_intervals: int
    substeps: int
    balance_time: float
    Q: tuple
    R: float
    limits: Limits
    mpc_backoff: dict
    mpc_options: dict
    noise_std: np.ndarray
    log_samples: int
    library: Callable
    smoothing: int = 3
    measured: tuple = ()
    kinematics: dict | None = None
    initial_std: np.ndarray | None = None
    reference_mpc: dict | None = None

    @property
    def dt(self) -> float:
        return self.T / self.n_intervals

    @property
    def steps(self) -> int:
        return self.n_intervals + int(round(self.balance_time / self.dt))

    def mpc_limits(self) -> Limits:
        xb = np.array(self.limits.x_bounds, dtype=float)
        for name, margin in self.mpc_backoff.items():
            i = self.state_names.index(name)
            xb[i] += [margin, -margin]
        return replace(self.limits, x_bounds=xb)

    def plan(self, model, *, guess=None, cost="tracking", diagnose=False):
        """The plan on ``model`` or None if none is found (``diagnose`` explains why)."""
        try:
            return plan_trajectory(model, x0=self.x_start, xf=self.x_goal, T=self.T,
                                   n_intervals=self.n_intervals, substeps=self.substeps,
                                   cost=cost, Q=self.Q, R=self.R, limits=self.limits,
                                   initial_guess=guess, verbose=False, diagnose=diagnose,
                                   max_iter=500)
        except (ConvergenceError, InfeasibleError):
            if diagnose:
                raise
            return None

    def tracker(self, model, plan):
        return tvlqr(model, plan, Q=self.Q, R=self.R, Q_final="lqr")

    def mpc(self, model, *, reference: bool = False) -> MPC:
        """The MPC controller on ``model`` (build once, follow many plans); ``reference``:
        with the reference solver's options instead of the real-time ones."""
        options = {**self.mpc_options, **(self.reference_mpc if reference else {})}
        return MPC(model, dt=self.dt, Q=self.Q, R=self.R, limits=self.mpc_limits(), **options)

    @property
    def outputs(self) -> list[int]:
        """Indices of the measured states (output feedback)."""
        return [self.state_names.index(name) for name in self.measured]

    def estimator(self, model, process_noise):
        """EKF on ``model`` measuring ``measured`` with the sensors' noise."""
        from discrepancy.estimation import ExtendedKalmanFilter

        names = {}
        if isinstance(model, tuple):          # (states, inputs, rhs) sympy equations
            names = {"state_names": list(self.state_names),
                     "input_names": list(self.input_names)}
            model = list(model[2])
        return ExtendedKalmanFilter(model, outputs=list(self.measured),
                                    process_noise=process_noise,
                                    measurement_noise=np.asarray(self.noise_std)[self.outputs],
                                    substeps=self.substeps, u_hold="zoh", **names)

    def output_feedback(self, law, model, process_noise) -> OutputFeedback:
        """``law`` driven by the EKF's estimate on ``model`` (starts from ``x_start``)."""
        return OutputFeedback(law, self.estimator(model, process_noise), x0=self.x_start,
                              P0=self.initial_std, dt=self.dt)

    def smoothed_updater(self, prior_equations, *, outputs, start=None) -> SmoothedLogUpdater:
        """Re-identification from control-rate logs of ``outputs`` (state names)."""
        noise = np.asarray(self.noise_std)[[self.state_names.index(o) for o in outputs]]
        return SmoothedLogUpdater(self.template(prior_equations), outputs=list(outputs),
                                  measurement_noise=noise, kinematics=self.kinematics,
                                  start=start, substeps=self.substeps,
                                  optimizer=STLSQ(threshold="auto", normalize_columns=True))

    def mpc_law(self, model, plan, tracker=None, mpc=None):
        mpc = self.mpc(model) if mpc is None else mpc
        return mpc.follow(plan, tracker=tracker if tracker is not None
                          else self.tracker(model, plan))

    def run(self, plant, law, x0, *, seed, noise_scale=1.0, samples=4, outputs=None):
        """Closed loop of ``law`` on ``plant`` for the plan and the balance time
        (``outputs``: indices of the measured states, for output feedback)."""
        return closed_loop(plant, law, x0, dt=self.dt, steps=self.steps, limits=self.limits,
                           noise_std=noise_scale * np.asarray(self.noise_std), seed=seed,
                           samples=samples, outputs=outputs)

    def judge(self, run) -> dict:
        """Final errors, limits kept, and ``success``: both."""
        e = swing_up_errors(run.final, angles=self.angles, rates=self.rates)
        kept = self.limits.check(run)
        travel = {f"max_abs_{self.state_names[i]}": float(np.max(np.abs(run.x_dense[..., i])))
                  for i in range(len(self.state_names))
                  if np.isfinite(self.limits.x_bounds[i]).any()}
        final = max(e[f"angle_{i}"] for i in self.angles)
        return {"success": bool(e["success"] and kept["respected"]),
                "final_state_reached": e["success"], "limits_respected": kept["respected"],
                "within_state_bounds": bool(kept["within_state_bounds"]),
                "final_max_angle_error_rad": final, **travel,
                "max_rate_ratio": kept["max_rate_ratio"]}

    def template(self, prior_equations) -> DiscrepancyModel:
        """The unfitted discrepancy model on the prior ``(states, inputs, rhs)``."""
        return DiscrepancyModel(prior=list(prior_equations[2]), feature_library=self.library(),
                                differentiation_method=SavitzkyGolay(
                                    window_length=self.log_samples + 1,
                                    polyorder=self.smoothing, smooth=False),
                                state_names=list(self.state_names),
                                input_names=list(self.input_names))

    def mpc_attempt(self, plant, x0, *, seed, noise_scale=1.0, guess=None, first=None,
                    process_noise=None, log=None):
        """``attempt(model) -> (success, log, result)`` for ``learn_by_attempts``: plan on
        ``model`` (warm from the last plan; if no plan is found, track the last plan), run
        MPC on ``plant`` and log every sample. ``first``: ``(plan, tracker, mpc)`` to reuse
        for the first attempt (``mpc`` may be None). ``process_noise``: run with output
        feedback (the EKF on ``model`` with this process noise, ``measured`` states only).
        ``log``: ``run -> log`` for the updater (default the 0.5 ms log of every interval)."""
        state = {"plan": guess, "count": 0, "first": first}
        output_feedback = process_noise is not None

        def attempt(model):
            state["count"] += 1
            f = as_casadi(model)  # ExportError names a term with no symbolic form
            reuse, state["first"] = state["first"], None
            if reuse is not None:
                plan, tracker, mpc = reuse
            else:
                plan = self.plan(f, guess=state["plan"]) or state["plan"]
                tracker, mpc = self.tracker(f, plan), None
            state["plan"] = plan
            mpc_law = law = self.mpc_law(f, plan, tracker, mpc)
            if output_feedback:
                law = self.output_feedback(mpc_law, model, process_noise)
            run = self.run(plant, law, x0, seed=seed + state["count"], noise_scale=noise_scale,
                           samples=self.log_samples,
                           outputs=self.outputs if output_feedback else None)
            verdict = self.judge(run)
            result = {"run": run, "verdict": verdict, "plan": plan,
                      "solve_times_s": mpc_law.solve_times, "cpu_times_s": mpc_law.cpu_times}
            if output_feedback:
                result["estimation_rms"] = law.estimation_errors(run)["rms"].tolist()
                result["controller_cpu_times_s"] = list(law.cpu_times)
            logged = run.measured_trajectories() if log is None else log(run)
            return verdict["success"], logged, result

        return attempt
