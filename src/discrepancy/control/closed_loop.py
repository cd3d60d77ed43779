"""A controller on a plant: noisy measurements, an actuator with limits, a record to learn from.

Every ``dt`` the controller sees the plant's state plus measurement noise (or, with
``outputs``, only some states: output feedback), its command is saturated by the
:class:`~.limits.Limits` (input bounds and rate, as an actuator would) and held for the
interval while the plant's ODE is solved tightly (:func:`~.replay.replay`). The run keeps
the true states (to judge it) and the noisy measurements at every output sample (what a rig
would log, and what the discrepancy is learned from; states not measured are NaN there).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..constraints import Integral, Interval, check_argument
from ..errors import ParameterError, ShapeError
from .limits import Limits
from .replay import Run, replay


@dataclass(frozen=True)
class ClosedLoopRun(Run):
    """A :class:`~.replay.Run` (true states) with what the controller and the logger saw.

    Attributes:
        x_measured: ``(N+1, n)`` noisy states the controller was given at the grid times.
        x_measured_dense: ``(N, S+1, n)`` noisy states at every output sample (the log).
        u_commanded: ``(N, r)`` the controller's commands before the actuator's limits.
        outputs: indices of the measured states (None: all); the others are NaN in the
            measurements.
    """

    x_measured: np.ndarray = None
    x_measured_dense: np.ndarray = None
    u_commanded: np.ndarray = None
    outputs: tuple | None = None

    def control_log(self):
        """``(y, dt, u)``: what the controller measured at every control sample ``(N+1, k)``
        (the measured states only), the period (s) and the applied inputs ``(N+1, r)`` (the
        last repeated: nothing is applied after the run). The log a rig records at its
        control rate, for :class:`~.reidentification.SmoothedLogUpdater`."""
        cols = list(range(self.x.shape[1])) if self.outputs is None else list(self.outputs)
        return (self.x_measured[:, cols], float(self.t[1] - self.t[0]),
                np.vstack([self.u, self.u[-1:]]))

    def measured_trajectories(self, *, until: float | None = None):
        """``(x, t, u)`` lists, one entry per hold interval: the log cut where the input
        jumps (a derivative never straddles a jump), ready for ``DiscrepancyModel.fit`` or
        :meth:`~.learning.DiscrepancyUpdater.update`. ``until``: keep only the intervals
        that end by this time (s), e.g. when a rig's safety stop ended the log."""
        if until is not None and (isinstance(until, bool) or not isinstance(
                until, (int, float, np.number)) or np.isnan(until)):
            raise ParameterError(f"until must be a time (s) or None; got {until!r}")
        k = len(self.u) if until is None else int(np.sum(self.t_dense[:, -1] <= until + 1e-12))
        us = [np.full((len(x), len(uk)), uk) for x, uk in
              zip(self.x_measured_dense[:k], self.u[:k], strict=True)]
        return list(self.x_measured_dense[:k]), list(self.t_dense[:k]), us

    def first_exit(self, limits: Limits, *, state_tol: float = 1e-3) -> float | None:
        """The first output time (s) at which a true state left its bounds (None if never)."""
        if not isinstance(limits, Limits):
            raise ParameterError(f"limits must be a Limits; got {type(limits).__name__}")
        n = self.x.shape[1]
        xl, xu, *_ = limits.sized(n, self.u.shape[1])
        out = np.any((self.x_dense > xu + state_tol) | (self.x_dense < xl - state_tol), axis=2)
        if not out.any():
            return None
        k, j = np.argwhere(out)[0]
        return float(self.t_dense[k, j])


def closed_loop(plant, law, x0, *, dt: float, steps: int, limits: Limits | None = None,
                noise_std=None, seed=None, samples: int = 1, u_initial=None, outputs=None,
                rtol: float = 1e-10, atol: float = 1e-12) -> ClosedLoopRun:
    """Run ``law`` on ``plant`` for ``steps`` intervals of ``dt`` from ``x0``.

    Args:
        plant: the true dynamics (CasADi Function or a vectorised numpy ``f(x, u)``).
        law: ``law(k, x_measured) -> u (r,)``, e.g. a TVLQR :class:`~.tracking.Tracker` or an
            :class:`~.mpc.MPCLaw`; a law with ``notify_applied(u)`` is told the input the
            actuator applied.
        x0: initial true state ``(n,)``.
        limits: the actuator saturates commands to the input bounds and rate limits (from
            ``u_initial``, default 0); state bounds are only judged (:meth:`Limits.check`).
        noise_std: ``(n,)`` standard deviation of the Gaussian measurement noise per state
            (or a scalar; default none), drawn independently at every output sample.
        seed: seed of the noise.
        samples: output samples per interval in the log.
        outputs: indices of the states the sensors measure (output feedback): the law gets
            ``y = x[outputs] + noise`` ``(k,)`` (in this order) instead of the state, and
            the log holds NaN for the other states. Default: every state is measured.
    """
    x0 = np.asarray(x0, dtype=float).ravel()
    n = len(x0)
    measured = _measured(outputs, n)
    check_argument("steps", steps, Interval(Integral, 1))
    check_argument("samples", samples, Interval(Integral, 1))
    steps, samples = int(steps), int(samples)
    from ..resources import check_memory, n_bytes
    check_memory(f"the log of {steps} steps x {samples} samples of {n} states",
                 n_bytes((steps * samples + 1, 3 * n)), "Use fewer steps or samples per step")
    std = np.zeros(n) if noise_std is None else np.broadcast_to(
        np.asarray(noise_std, dtype=float), (n,)).copy()
    if np.any(~np.isfinite(std)) or np.any(std < 0):
        raise ShapeError(f"noise_std must be ({n},) finite values >= 0; got {std.tolist()}")
    limits = Limits() if limits is None else limits
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((steps * samples + 1, n)) * std
    t = np.arange(steps + 1) * float(dt)
    seen, commanded = [], []
    state = {"u": None}

    def actuated(k, x):
        xm = x + noise[k * samples]
        u_cmd = np.asarray(law(k, xm if measured is None else xm[measured]),
                           dtype=float).ravel()
        if state["u"] is None:
            state["u"] = np.zeros(len(u_cmd)) if u_initial is None else \
                np.asarray(u_initial, dtype=float).ravel()
        u = limits.saturate(u_cmd, state["u"], dt)
        if hasattr(law, "notify_applied"):
            law.notify_applied(u)
        state["u"] = u
        seen.append(xm)
        commanded.append(u_cmd)
        return u

    run = replay(plant, x0, t, actuated, samples=samples, rtol=rtol, atol=atol)
    idx = np.arange(steps)[:, None] * samples + np.arange(samples + 1)[None, :]
    x_measured = np.vstack([seen, run.x[-1] + noise[-1]])
    x_measured_dense = run.x_dense + noise[idx]
    if measured is not None:
        hidden = np.setdiff1d(np.arange(n), measured)
        x_measured[:, hidden] = np.nan
        x_measured_dense[..., hidden] = np.nan
    return ClosedLoopRun(t=run.t, x=run.x, u=run.u, t_dense=run.t_dense, x_dense=run.x_dense,
                         x_measured=x_measured, x_measured_dense=x_measured_dense,
                         u_commanded=np.array(commanded),
                         outputs=None if measured is None else tuple(measured.tolist()))


def _measured(outputs, n: int):
    """Indices ``(k,)`` of the measured states, or None for all."""
    if outputs is None:
        return None
    idx = np.asarray(outputs)
    if idx.ndim != 1 or idx.size == 0 or idx.dtype.kind not in "iu" \
            or np.any((idx < 0) | (idx >= n)) or len(set(idx.tolist())) != idx.size:
        raise ParameterError(f"outputs must be distinct indices of the {n} states (at least "
                             f"one); got {outputs!r}")
    return idx
