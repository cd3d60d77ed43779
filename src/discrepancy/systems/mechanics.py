"""Equations of motion from a Lagrangian, derived with sympy.

Used by the pendulum systems so that their dynamics are derived, not hand-typed.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import sympy as sp


def lagrange_equations(kinetic: sp.Expr, potential: sp.Expr, q: Sequence[sp.Symbol],
                       dq: Sequence[sp.Symbol], *, dissipation: sp.Expr = sp.S.Zero,
                       forces: Sequence[sp.Expr] | None = None,
                       driven: Mapping[int, sp.Expr] | None = None, simplify: bool = True):
    """Euler–Lagrange equations ``M(q) q̈_free = b(q, q̇, ...)`` for the free coordinates.

    The Lagrangian is ``L = T - V``; a Rayleigh dissipation function ``D(q̇)`` adds
    ``∂D/∂q̇_i`` to each equation; ``forces`` are generalised forces ``Q_i``.
    Coordinates listed in ``driven`` (index -> prescribed acceleration, e.g. a cart
    whose acceleration is the input) have no equation of their own; their
    acceleration is substituted into the others.

    Returns ``(free, M, b)``: indices of the free coordinates, the mass matrix and
    the right-hand side, both sympy matrices (simplified unless ``simplify=False``: for
    numerical use of many coordinates, where simplifying costs more than it saves).
    """
    n = len(q)
    driven = dict(driven or {})
    forces = list(forces) if forces is not None else [sp.S.Zero] * n
    ddq = sp.symbols(f"_ddq0:{n}", real=True)
    lagrangian = kinetic - potential
    free = [i for i in range(n) if i not in driven]
    equations = []
    for i in free:
        p_i = sp.diff(lagrangian, dq[i])
        dt_p_i = sum(sp.diff(p_i, q[j]) * dq[j] + sp.diff(p_i, dq[j]) * ddq[j] for j in range(n))
        eq = dt_p_i - sp.diff(lagrangian, q[i]) + sp.diff(dissipation, dq[i]) - forces[i]
        equations.append(eq.subs({ddq[j]: a for j, a in driven.items()}))
    unknowns = [ddq[i] for i in free]
    mass = sp.Matrix([[sp.diff(eq, a) for a in unknowns] for eq in equations])
    rest = sp.Matrix([-eq.subs({a: 0 for a in unknowns}) for eq in equations])
    if not simplify:
        return free, mass.applyfunc(sp.expand), rest.applyfunc(sp.expand)
    return free, sp.simplify(mass), sp.simplify(rest)


def time_derivative(expr: sp.Expr, q: Sequence[sp.Symbol], dq: Sequence[sp.Symbol]) -> sp.Expr:
    """``d expr / dt`` for an expression of the coordinates ``q`` with rates ``dq``."""
    return sum(sp.diff(expr, qi) * dqi for qi, dqi in zip(q, dq, strict=True))
