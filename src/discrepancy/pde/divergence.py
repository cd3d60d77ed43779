"""Terms in divergence form: moving spatial derivatives from the data onto test functions.

The weak form integrates every term against a test function ``φ`` that vanishes with its
derivatives at the edge of its support, so ``∫ φ ∂^β h = (-1)^|β| ∫ (∂^β φ) h``. A term
``e`` of the fields and their derivatives is rewritten as ``e = Σ_β ∂^β h_β`` with the
``h_β`` of the lowest derivative order this finds, by integrating by parts one axis at a
time: for a term linear in its highest derivative ``w = ∂_a w'`` with cofactor ``A``,

    A w = ∂_a (A w') - (∂_a A) w',

and when the remainder holds the term itself again (``u u_x = ∂_x(u²) - u u_x``) the
equation is solved for it (``u u_x = ∂_x(u²/2)``). Pure derivatives (``u_xxxx``) and
conservative fluxes (``u u_x``, ``u² u_x``) lose every derivative; ``u u_xx`` becomes
``∂_x²(u²/2) - u_x²``, so only a first derivative is left to estimate from the data. Terms
nonlinear in their top derivative, or involving inputs (which are not differentiated),
stay as they are. Written here because sympy has no such rewriting for jet variables.
"""
from __future__ import annotations

import sympy as sp

from ..libraries.pde import derivative_name, parse_derivative
from ..symbolic import symbol

#: recursion depth of the rewriting (orders up to 8 in 3 axes need far fewer)
MAX_DEPTH = 24


class Jet:
    """The jet variables of some fields on a grid: their symbols, orders and shifts."""

    def __init__(self, fields, coordinates):
        self.fields, self.coordinates = list(fields), list(coordinates)

    def alpha(self, s: sp.Symbol) -> tuple[str, tuple[int, ...]] | None:
        """``(field, α)`` of a field (α = 0) or derivative symbol; ``None`` otherwise."""
        if s.name in self.fields:
            return s.name, (0,) * len(self.coordinates)
        return parse_derivative(s.name, self.fields, self.coordinates)

    def shifted(self, field: str, alpha) -> sp.Symbol:
        """The symbol of ``∂^α`` of ``field`` (``alpha``: one derivative order per axis):
        ``u_xx`` for ``alpha=(2,)``, the field's own symbol when ``alpha`` is all zeros."""
        if not any(alpha):
            return symbol(field)
        return symbol(derivative_name(field, alpha, self.coordinates))

    def order(self, expr: sp.Expr) -> int:
        """Highest total derivative order of the jet variables in ``expr`` (0 when it holds no
        derivative)."""
        return max((sum(a[1]) for s in expr.free_symbols if (a := self.alpha(s))), default=0)

    def total_derivative(self, expr: sp.Expr, axis: int) -> sp.Expr | None:
        """``D_axis expr`` (chain rule over jet variables), or ``None`` when ``expr`` holds
        a symbol that is not a jet variable (an input)."""
        out = sp.S.Zero
        for s in expr.free_symbols:
            found = self.alpha(s)
            if found is None:
                return None
            field, alpha = found
            up = list(alpha)
            up[axis] += 1
            out += sp.diff(expr, s) * self.shifted(field, up)
        return sp.expand(out)


def divergence_form(expr: sp.Expr, jet: Jet) -> dict[tuple[int, ...], sp.Expr]:
    """``{β: h_β}`` with ``expr = Σ_β ∂^β h_β`` (see the module docstring); ``β = 0``
    holds what stays pointwise."""
    out: dict[tuple[int, ...], sp.Expr] = {}
    for term in sp.Add.make_args(sp.expand(expr)):
        _merge(out, _reduce(term, jet, set(), 0))
    return {b: h for b, h in out.items() if h != 0}


def _merge(into: dict, parts: dict, scale=1, shift: int | None = None) -> None:
    for beta, h in parts.items():
        if shift is not None:
            beta = tuple(b + (i == shift) for i, b in enumerate(beta))
        into[beta] = sp.expand(into.get(beta, sp.S.Zero) + scale * h)


def _reduce(term: sp.Expr, jet: Jet, active: set, depth: int) -> dict:
    """Divergence form of one product ``term`` (``active``: terms being rewritten above)."""
    zero = (0,) * len(jet.coordinates)
    coefficient, monomial = term.as_coeff_Mul()
    top = _top_derivative(monomial, jet)
    if top is None or depth > MAX_DEPTH or monomial in active:
        return {zero: term}
    w, field, alpha = top
    cofactor = sp.expand(term / w)
    if cofactor.has(w) or jet.order(cofactor) >= sum(alpha):
        return {zero: term}       # nonlinear in its top derivative: stays pointwise
    axis = next(i for i, a in enumerate(alpha) if a > 0)
    lower = list(alpha)
    lower[axis] -= 1
    flux = sp.expand(cofactor * jet.shifted(field, lower))
    d_cofactor = jet.total_derivative(cofactor, axis)
    if d_cofactor is None:
        return {zero: term}       # depends on an input: no derivative of it is known
    rest = sp.expand(-d_cofactor * jet.shifted(field, lower))
    again = rest.coeff(monomial) if rest.has(monomial) else sp.S.Zero
    if again.free_symbols:
        again = sp.S.Zero
    if again == coefficient:
        return {zero: term}
    rest = sp.expand(rest - again * monomial)
    scale = coefficient / (coefficient - again)  # term = scale * (∂_a flux + rest)
    out: dict = {}
    inner = active | {monomial}
    _merge(out, _reduce_sum(flux, jet, inner, depth + 1), scale, axis)
    _merge(out, _reduce_sum(rest, jet, inner, depth + 1), scale)
    return out


def _reduce_sum(expr, jet, active, depth) -> dict:
    out: dict = {}
    for t in sp.Add.make_args(expr):
        if t != 0:
            _merge(out, _reduce(t, jet, active, depth))
    return out


def _top_derivative(monomial: sp.Expr, jet: Jet):
    """The derivative symbol of highest order in ``monomial`` (``(symbol, field, α)``), or
    ``None`` when it holds none."""
    best = None
    for s in sorted(monomial.free_symbols, key=lambda s: s.name):
        found = jet.alpha(s)
        if found and sum(found[1]) > 0 and (best is None or sum(found[1]) > sum(best[2])):
            best = (s, *found)
    return best
