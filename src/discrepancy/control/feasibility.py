"""Why a plan failed: relaxed ("elastic") versions of the problem say which limit is to blame.

When IPOPT finds no plan, two relaxed problems are solved from the same initial guesses
(IPOPT is a local method: each relaxed problem keeps its best solution over the guesses):

1. every state bound may be exceeded by a slack (one per bounded state), the total slack
   minimised: if the smallest slack that admits a plan is positive, that bound is too
   tight for the task (a rail too short for the swing), and the plan that needs the least
   excess says by how much;
2. the state bounds are dropped and the final condition becomes a cost: if even then the
   final state cannot be reached, the horizon ``T`` is too short for the input limits.

Either finding raises :class:`~discrepancy.errors.InfeasibleError`; if neither relaxed
problem needs a violation, the failure was numerical and the caller says so.
"""
from __future__ import annotations

import numpy as np

from ..errors import InfeasibleError
from .shooting import Problem, build, solver_options

#: a relaxed problem "needs" a violation larger than this (in the state's units)
SLACK_TOLERANCE = 1e-5
#: the final state counts as unreachable when missed by more than this (max-abs)
MISS_TOLERANCE = 1e-4


def _solve(problem: Problem, objective, guesses, elastic):
    """``(x, slack)`` of the relaxed problem with the smallest objective over ``guesses``
    (None if IPOPT solves it from none of them)."""
    opti, X, U, J, slack = build(problem, J_of=objective, elastic=elastic)
    opti.solver("ipopt", *solver_options(False, 3000, 1e-8))
    best = None
    for xg, ug in guesses:
        opti.set_initial(X, xg.T)
        opti.set_initial(U, np.clip(ug, problem.ul, problem.uu).T)
        try:
            sol = opti.solve()
        except RuntimeError:
            continue
        if best is None or float(sol.value(J)) < best[0]:
            x = np.array(sol.value(X)).T.reshape(-1, len(problem.x0))
            s = None if slack is None else np.atleast_1d(np.array(sol.value(slack), dtype=float))
            best = (float(sol.value(J)), x, s)
    return None if best is None else best[1:]


def _limits_text(p: Problem) -> str:
    parts = []
    if np.any(np.isfinite(p.ul)) or np.any(np.isfinite(p.uu)):
        parts.append("u_bounds " + str(np.column_stack([p.ul, p.uu]).tolist()))
    if np.any(np.isfinite(p.du_max)):
        parts.append("du_max " + str(p.du_max.tolist()))
    return " and ".join(parts) if parts else "no input limits"


def explain(p: Problem, objective, guesses, status: str) -> None:
    """Raise InfeasibleError if a relaxed problem shows that a state bound or the horizon is
    to blame for IPOPT's failure (``status``); return None if neither is. ``guesses``:
    ``[(x (N+1, n), u (N, r))]`` initial guesses."""
    T = float(p.t[-1])
    bounded = [i for i in range(len(p.x0)) if np.isfinite(p.xl[i]) or np.isfinite(p.xu[i])]
    if bounded:
        found = _solve(p, objective, guesses, "states")
        if found is not None:
            x, slack = found
            tight = [(i, s) for i, s in zip(bounded, slack, strict=True)
                     if s > SLACK_TOLERANCE]
            if not tight:
                return None
            lines = [f"state {p.state_names[i]!r} must stay in [{p.xl[i]:g}, {p.xu[i]:g}] but "
                     f"the plan found that exceeds it least spans [{x[:, i].min():.4g}, "
                     f"{x[:, i].max():.4g}] ({s:.3g} beyond the bound)" for i, s in tight]
            raise InfeasibleError(
                f"x_bounds are too tight for this task (IPOPT: {status}): "
                + "; ".join(lines) + f", with T = {T:g} s and {_limits_text(p)}; widen the "
                "bound or lengthen T")
    found = _solve(p, objective, guesses, "final")
    if found is None:
        return None
    x, _ = found
    miss = np.abs(x[-1] - p.xf)
    if miss.max() <= MISS_TOLERANCE:
        return None
    worst = int(np.argmax(miss))
    raise InfeasibleError(
        f"T = {T:g} s is too short to reach xf from x0 with {_limits_text(p)} (IPOPT: "
        f"{status}): even without state bounds the closest final state misses xf by "
        f"{miss[worst]:.3g} in {p.state_names[worst]!r}; lengthen T or loosen the input limits")
