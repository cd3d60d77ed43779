"""Real-time iteration: one Gauss-Newton SQP step per sample on a condensed QP.

The MPC problem of :mod:`.mpc` is solved the way real-time MPC on embedded hardware does
(Diehl's real-time iteration, as in acados): at each sample the dynamics are linearised about
the previous solution shifted by one sample, ``(x̄_k, ū_k)``,

    x_{k+1} ≈ F(x̄_k, ū_k) + A_k (x_k - x̄_k) + B_k (u_k - ū_k),

the states are eliminated (condensing: ``x - x̄ = h + G Δu`` with ``x_0`` the measured
state), and the remaining QP in the input steps ``Δu`` (``N r`` variables) and the
state-bound slacks is small and dense. Its Hessian ``2 (Gᵀ Q̄ G + R̄)`` is exact for the
quadratic tracking cost (Gauss-Newton: the dynamics' curvature is left out), so the QP is
convex. One QP per sample, solved by any CasADi conic (``daqp``, a dual active-set solver
for small dense QPs, by default), bounds the cost per sample; more steps (``iterations``)
converge to the NLP's solution.

Two CasADi functions do the work: ``linearise`` (model-dependent: the held-input RK4 step
and its Jacobians, mapped over the horizon) and ``condense`` (depends only on the sizes,
weights and limits), both compiled to C on request
(:func:`~discrepancy.hybrid.codegen.compiled`): re-identified models with the same
settings reuse the compiled ``condense``. Written with CasADi rather than a hand-coded
Riccati/condensing routine: the same expression graph gives the QP, its sparsity and the
generated code.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid.codegen import compiled
from .dynamics import rk4_step


def linearisation(f: ca.Function, dt: float, substeps: int, horizon: int) -> ca.Function:
    """``(X (n, N), U (r, N)) -> (F (n, N), A (n, n N), B (n, r N))``: the held-input RK4
    step and its Jacobians at every stage of the horizon."""
    n, r = f.size1_in(0), f.size1_in(1)
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", r)
    x_next = rk4_step(f, dt, substeps)(x, u)
    one = ca.Function("linearise_stage", [x, u],
                      [x_next, ca.jacobian(x_next, x), ca.jacobian(x_next, u)])
    X, U = ca.SX.sym("X", n, horizon), ca.SX.sym("U", r, horizon)
    F, A, B = one.map(horizon)(X, U)
    return ca.Function("linearise", [X, U], [F, A, B])


def condensing(n: int, r: int, horizon: int, Q, R, bounds, soft_penalty: float) -> ca.Function:
    """The condensed QP of one Gauss-Newton step.

    Inputs: ``x0 (n)``, ``u_prev (r)``, ``Xr (n, N+1)``, ``Ur (r, N)``, ``P (n, n)``, the
    linearisation point ``Xb (n, N+1)``, ``Ub (r, N)`` and ``F, A, B`` of
    :func:`linearisation` there. Outputs: ``H, g, C, lba, uba, lbz, ubz`` of
    ``min ½ zᵀHz + gᵀz  s.t. lba <= C z <= uba, lbz <= z <= ubz`` with
    ``z = [vec(Δu); vec(σ)]``, and ``X0, GX`` with ``vec(X) = X0 + GX z``.

    ``bounds``: ``(xl, xu, ul, uu, du)`` sized arrays (:meth:`.limits.Limits.sized`); the
    rate limits enter as ``|u_k - u_{k-1}| <= du dt``, so ``du`` is given per hold already
    multiplied by ``dt``.
    """
    N = horizon
    xl, xu, ul, uu, du_step = bounds
    bounded = [i for i in range(n) if np.isfinite(xl[i]) or np.isfinite(xu[i])]
    x0, u_prev = ca.SX.sym("x0", n), ca.SX.sym("u_prev", r)
    Xr, Ur, P = ca.SX.sym("Xr", n, N + 1), ca.SX.sym("Ur", r, N), ca.SX.sym("P", n, n)
    Xb, Ub = ca.SX.sym("Xb", n, N + 1), ca.SX.sym("Ub", r, N)
    F, A, B = ca.SX.sym("F", n, N), ca.SX.sym("A", n, n * N), ca.SX.sym("B", n, r * N)
    dU, S = ca.SX.sym("dU", r, N), ca.SX.sym("S", max(len(bounded), 1), N)
    delta, columns = x0 - Xb[:, 0], [x0]
    for k in range(N):
        delta = F[:, k] - Xb[:, k + 1] + ca.mtimes(A[:, k * n:(k + 1) * n], delta) \
            + ca.mtimes(B[:, k * r:(k + 1) * r], dU[:, k])
        columns.append(Xb[:, k + 1] + delta)
    X, U = ca.horzcat(*columns), Ub + dU
    E, V = X - Xr, U - Ur
    J = ca.sum2(ca.sum1(E[:, :-1] * (ca.DM(Q) @ E[:, :-1]))) \
        + ca.sum2(ca.sum1(V * (ca.DM(R) @ V))) + ca.bilin(P, E[:, -1], E[:, -1]) \
        + soft_penalty * (ca.sum1(ca.sum2(S)) + ca.sumsqr(S))
    rows, lower, upper = [], [], []
    for i in range(r):
        if np.isfinite(du_step[i]):
            rows.append(ca.horzcat(U[i, 0] - u_prev[i], ca.diff(U[i, :], 1, 1)).T)
            lower.append(np.full(N, -du_step[i]))
            upper.append(np.full(N, du_step[i]))
    for j, i in enumerate(bounded):
        rows += [(X[i, 1:] + S[j, :]).T, (X[i, 1:] - S[j, :]).T]
        lower += [np.full(N, xl[i]), np.full(N, -np.inf)]
        upper += [np.full(N, np.inf), np.full(N, xu[i])]
    z = ca.vertcat(ca.vec(dU), ca.vec(S))
    at_zero = {"z": ca.DM.zeros(z.shape)}
    G = ca.vertcat(*rows) if rows else ca.SX(0, 1)
    G0 = ca.substitute(G, z, at_zero["z"])
    H, g = ca.hessian(J, z)
    Xv = ca.vec(X)
    lbz = ca.vertcat(ca.vec(ca.repmat(ca.DM(ul), 1, N) - Ub), ca.DM.zeros(S.numel()))
    ubz = ca.vertcat(ca.vec(ca.repmat(ca.DM(uu), 1, N) - Ub), ca.DM.inf(S.numel()))
    lba = ca.DM(np.concatenate(lower) if lower else np.zeros(0)) - G0
    uba = ca.DM(np.concatenate(upper) if upper else np.zeros(0)) - G0
    return ca.Function("condense", [x0, u_prev, Xr, Ur, P, Xb, Ub, F, A, B],
                       [H, ca.substitute(g, z, at_zero["z"]), ca.jacobian(G, z), lba, uba,
                        lbz, ubz, ca.substitute(Xv, z, at_zero["z"]),
                        ca.densify(ca.jacobian(Xv, z))],
                       ["x0", "u_prev", "Xr", "Ur", "P", "Xb", "Ub", "F", "A", "B"],
                       ["H", "g", "C", "lba", "uba", "lbz", "ubz", "X0", "GX"])


class RealTimeIteration:
    """Gauss-Newton SQP steps for :class:`~.mpc.MPC` (see the module docstring).

    Args:
        f: CasADi dynamics; dt, substeps, horizon, Q, R, bounds, soft_penalty: as the MPC's
            (``bounds``: :meth:`~.limits.Limits.sized` arrays, rates per second).
        qp_solver: a CasADi conic plugin name (``casadi.has_conic``); ``"daqp"`` default.
        compile: generate and compile C for both functions
            (:func:`~discrepancy.hybrid.codegen.compiled`).
    """

    def __init__(self, f, *, dt, substeps, horizon, Q, R, bounds, soft_penalty,
                 qp_solver="daqp", compile=False):
        if not (isinstance(qp_solver, str) and ca.has_conic(qp_solver)):
            raise ParameterError(f"qp_solver must be a CasADi QP solver available here "
                                 f"(e.g. 'daqp', 'qpoases', 'osqp', 'qrqp', 'proxqp'); got "
                                 f"{qp_solver!r}")
        n, r = f.size1_in(0), f.size1_in(1)
        xl, xu, ul, uu, du = bounds
        self.n, self.r, self.horizon = n, r, horizon
        self.u_bounds, self.du_step = (ul, uu), du * dt
        linearise = compiled(linearisation(f, dt, substeps, horizon), enabled=compile)
        condense = compiled(condensing(n, r, horizon, Q, R, (xl, xu, ul, uu, self.du_step),
                                       soft_penalty), enabled=compile)
        qp = ca.conic("mpc_qp", qp_solver, {"h": condense.sparsity_out("H"),
                                            "a": condense.sparsity_out("C")},
                      {"error_on_fail": False, "inputs_check": False,
                       **QP_OPTIONS.get(qp_solver, {})})
        self._step = self._compose(linearise, condense, qp)
        self.n_slacks = condense.sparsity_out("H").size1() - horizon * r

    def _compose(self, linearise, condense, qp) -> ca.Function:
        """One CasADi call per step: linearise, condense, solve the QP, expand the states
        (the data stay in CasADi's buffers; only the answer comes back to numpy)."""
        n, r, N = self.n, self.r, self.horizon
        x0, u_prev = ca.MX.sym("x0", n), ca.MX.sym("u_prev", r)
        Xr, Ur, P = ca.MX.sym("Xr", n, N + 1), ca.MX.sym("Ur", r, N), ca.MX.sym("P", n, n)
        Xb, Ub = ca.MX.sym("Xb", n, N + 1), ca.MX.sym("Ub", r, N)
        F, A, B = linearise(Xb[:, :-1], Ub)
        H, g, C, lba, uba, lbz, ubz, X0, GX = condense(x0, u_prev, Xr, Ur, P, Xb, Ub, F, A, B)
        z = qp(h=H, g=g, a=C, lba=lba, uba=uba, lbx=lbz, ubx=ubz)["x"]
        X = ca.reshape(X0 + ca.mtimes(GX, z), n, N + 1)
        U = Ub + ca.reshape(z[:N * r], r, N)
        return ca.Function("rti_step", [x0, u_prev, Xr, Ur, P, Xb, Ub], [X, U, z[N * r:]])

    def step(self, x0, u_prev, Xr, Ur, P, Xb, Ub):
        """One Gauss-Newton step from the linearisation point ``(Xb (n, N+1), Ub (r, N))``:
        ``(X (n, N+1), U (r, N), S (slacks), solved)``. ``solved``: the QP was solved, its
        states are finite and its inputs keep the bounds and rates (to 1e-6 of their size);
        if not, the point is returned as it was (its inputs are the shifted previous plan)."""
        try:
            X, U, S = (v.full() for v in self._step(x0, u_prev, Xr, Ur, P, Xb, Ub))
        except RuntimeError:        # the QP solver refused its data (NaN from a diverged point)
            X = U = S = None
        if X is not None and np.all(np.isfinite(X)) and self._solved(U, u_prev):
            return X, U, S.ravel(), True
        return (np.asarray(Xb, dtype=float), np.asarray(Ub, dtype=float),
                np.zeros(self.n_slacks), False)

    def _solved(self, U, u_prev) -> bool:
        if not np.all(np.isfinite(U)):
            return False
        (ul, uu), du = self.u_bounds, self.du_step
        slack = 1e-6 * (1.0 + np.abs(U))
        steps = np.abs(np.diff(np.hstack([np.reshape(u_prev, (-1, 1)), U]), axis=1))
        return bool(np.all(U >= ul[:, None] - slack) and np.all(U <= uu[:, None] + slack)
                    and np.all(steps <= du[:, None] * (1 + 1e-6) + 1e-9))


#: quiet, accurate settings per QP solver (the defaults print or stop early)
QP_OPTIONS = {"qpoases": {"printLevel": "none", "sparse": False},
              "qrqp": {"print_iter": False, "print_header": False, "print_info": False},
              "osqp": {"osqp": {"verbose": False, "eps_abs": 1e-8, "eps_rel": 1e-8,
                                "max_iter": 20000, "polish": True}},
              "highs": {"highs": {"output_flag": False}}}
