"""A controller on a plant: noisy measurements, an actuator with limits, a record to learn from.

Every ``dt`` the controller sees the plant's state plus measurement noise, its command is
saturated by the :class:`~.limits.Limits` (input bounds and rate, as an actuator would) and
held for the interval while the plant's ODE is solved tightly (:func:`~.replay.replay`).
The run keeps the true states (to judge it) and the noisy measurements at every output
sample (what a rig would log, and what the discrepancy is learned from).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
    """

    x_measured: np.ndarray = None
    x_measured_dense: np.ndarray = None
    u_commanded: np.ndarray = None

    def measured_trajectories(self, *, until: float | None = None):
        """``(x, t, u)`` lists, one entry per hold interval: the log cut where the input
        jumps (a derivative never straddles a jump), ready for ``DiscrepancyModel.fit`` or
        :meth:`~.learning.DiscrepancyUpdater.update`. ``until``: keep only the intervals
        that end by this time (s), e.g. when a rig's safety stop ended the log."""
        k = len(self.u) if until is None else int(np.sum(self.t_dense[:, -1] <= until + 1e-12))
        us = [np.full((len(x), len(uk)), uk) for x, uk in
              zip(self.x_measured_dense[:k], self.u[:k], strict=True)]
        return list(self.x_measured_dense[:k]), list(self.t_dense[:k]), us

    def first_exit(self, limits: Limits, *, state_tol: float = 1e-3) -> float | None:
        """The first output time (s) at which a true state left its bounds (None if never)."""
        n = self.x.shape[1]
        xl, xu, *_ = limits.sized(n, self.u.shape[1])
        out = np.any((self.x_dense > xu + state_tol) | (self.x_dense < xl - state_tol), axis=2)
        if not out.any():
            return None
        k, j = np.argwhere(out)[0]
        return float(self.t_dense[k, j])


def closed_loop(plant, law, x0, *, dt: float, steps: int, limits: Limits | None = None,
                noise_std=None, seed=None, samples: int = 1, u_initial=None,
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
    """
    x0 = np.asarray(x0, dtype=float).ravel()
    n = len(x0)
    if not (isinstance(steps, int) and steps >= 1):
        raise ParameterError(f"steps must be a positive integer; got {steps!r}")
    std = np.zeros(n) if noise_std is None else np.broadcast_to(
        np.asarray(noise_std, dtype=float), (n,)).copy()
    if np.any(~np.isfinite(std)) or np.any(std < 0):
        raise ShapeError(f"noise_std must be ({n},) finite values >= 0; got {std.tolist()}")
    limits = Limits() if limits is None else limits
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((steps * samples + 1, n)) * std
    t = np.arange(steps + 1) * float(dt)
    measured, commanded = [], []
    state = {"u": None}

    def actuated(k, x):
        xm = x + noise[k * samples]
        u_cmd = np.asarray(law(k, xm), dtype=float).ravel()
        if state["u"] is None:
            state["u"] = np.zeros(len(u_cmd)) if u_initial is None else \
                np.asarray(u_initial, dtype=float).ravel()
        u = limits.saturate(u_cmd, state["u"], dt)
        if hasattr(law, "notify_applied"):
            law.notify_applied(u)
        state["u"] = u
        measured.append(xm)
        commanded.append(u_cmd)
        return u

    run = replay(plant, x0, t, actuated, samples=samples, rtol=rtol, atol=atol)
    idx = np.arange(steps)[:, None] * samples + np.arange(samples + 1)[None, :]
    return ClosedLoopRun(t=run.t, x=run.x, u=run.u, t_dense=run.t_dense, x_dense=run.x_dense,
                         x_measured=np.vstack([measured, run.x[-1] + noise[-1]]),
                         x_measured_dense=run.x_dense + noise[idx],
                         u_commanded=np.array(commanded))
