"""Turning models into CasADi dynamics ``f(x, u) -> xdot`` and exact discrete steps."""
from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from .._optional import require
from ..constraints import Integral, Interval, Real, check_argument
from ..errors import ParameterError, ShapeError, describe
from ..runge_kutta import runge_kutta_step
from ..symbolic import to_casadi

ca = require("casadi", purpose="discrepancy.control")


def from_equations(states: Sequence, inputs: Sequence, rhs: Sequence) -> ca.Function:
    """CasADi ``f(x (n,1), u (r,1)) -> xdot (n,1)`` from sympy right-hand sides.

    ``states`` / ``inputs`` are sympy symbols (their names are looked up in ``rhs``).
    A term with no symbolic form raises :class:`~discrepancy.errors.ExportError`.
    """
    for name, symbols in (("states", states), ("inputs", inputs)):
        if isinstance(symbols, (str, bytes)) or not all(isinstance(s, sp.Symbol)
                                                        for s in symbols):
            raise ParameterError(f"{name} must be a sequence of sympy symbols; got "
                                 f"{symbols!r:.80}")
    if len(rhs) != len(states):
        raise ShapeError(f"rhs must have one expression per state ({len(states)}); got {len(rhs)}")
    x = ca.SX.sym("x", len(states))
    u = ca.SX.sym("u", len(inputs))
    variables = {s.name: x[i] for i, s in enumerate(states)}
    variables.update({s.name: u[i] for i, s in enumerate(inputs)})
    out = [to_casadi(e, variables, term=f"({states[i].name})' = {e}") if hasattr(e, "free_symbols")
           else float(e) for i, e in enumerate(rhs)]
    return ca.Function("f", [x, u], [ca.vertcat(*out)], ["x", "u"], ["xdot"])


def as_casadi(model) -> ca.Function:
    """CasADi dynamics of ``model``: a ``casadi.Function`` f(x, u) -> xdot (returned as is),
    anything with ``to_casadi()`` (a fitted hybrid model), or ``(states, inputs, rhs)`` sympy
    equations as returned by ``DoublePendulumOnCart.equations()``."""
    if isinstance(model, ca.Function):
        f = model
    elif hasattr(model, "to_casadi"):
        if getattr(model, "discrete_time", False) is True:
            raise ParameterError("model is discrete-time (a map x[k+1] = f(x[k], u[k])); "
                                 "control takes continuous-time dynamics f(x, u) -> xdot")
        f = model.to_casadi()  # ExportError naming the term if a term has no symbolic form
    elif isinstance(model, (tuple, list)) and len(model) == 3:
        f = from_equations(*model)
    else:
        raise ParameterError("model must be a casadi.Function f(x, u) -> xdot, a model with "
                             "to_casadi(), or (states, inputs, rhs) sympy equations; got "
                             f"{describe(model)}")
    if f.n_in() != 2 or f.n_out() != 1 or f.size1_in(1) < 1:
        raise ShapeError(f"dynamics must map (x (n,1), u (r,1)) -> xdot (n,1); got a function "
                         f"with {f.n_in()} inputs and {f.n_out()} outputs")
    if f.size_out(0) != f.size_in(0):
        raise ShapeError(f"dynamics output {f.size_out(0)} must match the state {f.size_in(0)}")
    return f


def rk4_step(f: ca.Function, dt: float, substeps: int) -> ca.Function:
    """``F(x, u) -> x(t + dt)``: ``substeps`` classical Runge–Kutta steps with ``u`` held."""
    check_argument("substeps", substeps, Interval(Integral, 1, 1000))
    substeps = int(substeps)
    check_argument("dt", dt, Interval(Real, 0, None, closed="neither"))
    if not isinstance(f, ca.Function):
        raise ParameterError(f"f must be a casadi.Function f(x, u) -> xdot (see as_casadi); "
                             f"got {describe(f)}")
    n, r = f.size1_in(0), f.size1_in(1)
    x0 = ca.SX.sym("x", n)
    u = ca.SX.sym("u", r)
    h = dt / substeps
    x = x0
    for _ in range(substeps):
        x = runge_kutta_step(f, x, h, u, u, u)
    return ca.Function("F", [x0, u], [x], ["x", "u"], ["x_next"])
