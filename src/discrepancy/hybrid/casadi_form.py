"""The hybrid model as CasADi expressions: for compiled simulation and output-error fits.

The library's columns are sympy expressions and map onto CasADi exactly
(:func:`discrepancy.symbolic.to_casadi`). A prior given as sympy expressions does too. A
prior given as a numpy callable is *traced*: it is called once on an object array of CasADi
symbols, which works for the arithmetic and elementwise functions numpy dispatches to the
elements (``+ - * / **``, ``np.sin``, ``np.sqrt``, ``np.c_``, indexing, ...). A callable
that branches on values (``if``, ``np.where``, ``np.maximum``, ``np.sign``) cannot be
traced; the error says so, and sympy expressions (``sp.Max``, ``sp.sign``) are the way
out. A traced prior is checked against the callable on sample points before it is used.
"""
from __future__ import annotations

import numpy as np

from .._optional import require
from ..errors import ExportError
from ..runge_kutta import runge_kutta_step
from ..symbolic import feature_name, to_casadi

#: relative agreement required between a traced prior and the callable it came from
TRACE_TOLERANCE = 1e-9


def casadi_module():
    """The casadi module (an optional extra), or a clear error naming what needs it."""
    return require("casadi", purpose="compiled simulation and output-error fitting")


def variables(names, x, u) -> dict:
    """``{name: SX}`` for state names then input names."""
    return {n: (x[i] if i < x.numel() else u[i - x.numel()]) for i, n in enumerate(names)}


def prior_expression(prior, x, u, *, check_points=None):
    """CasADi column ``(n, 1)`` of the prior ``f_m(x, u)`` at the symbols ``x``, ``u``.

    ``prior`` is a :class:`~discrepancy.fitting.prior.Prior`. ``check_points``: an optional
    ``(states (k, n), inputs (k, r) or None)`` on which a traced callable must agree with
    itself evaluated by numpy."""
    ca = casadi_module()
    n = x.numel()
    if prior.is_symbolic:
        names = variables(prior.names, x, u)
        return ca.vertcat(*[ca.SX(to_casadi(e, names, term=f"prior[{i}]"))
                            for i, e in enumerate(prior.expressions)])
    if prior._call is None:
        return ca.SX.zeros(n, 1)
    column = _trace(prior, x, u)
    if check_points is not None:
        _check_trace(prior, ca.Function("prior", [x, u], [column]), *check_points)
    return column


def _trace(prior, x, u):
    ca = casadi_module()
    n, r = x.numel(), u.numel()
    xs = np.empty((1, n), dtype=object)
    xs[0, :] = [x[i] for i in range(n)]
    us = None
    if r:
        us = np.empty((1, r), dtype=object)
        us[0, :] = [u[i] for i in range(r)]
    try:
        with np.errstate(all="ignore"):
            out = np.asarray(prior._call(xs, us), dtype=object)
        if out.size != n:
            raise ValueError(f"it returned {out.size} values for {n} states")
        return ca.vertcat(*[ca.SX(v) for v in out.ravel()])
    except Exception as e:  # any failure of tracing means: not traceable
        raise ExportError(
            "the prior (a Python callable) could not be turned into CasADi expressions "
            f"({type(e).__name__}: {str(e)[:160]}). Tracing supports arithmetic and numpy's "
            "elementwise functions, not branches on values (if, np.where, np.maximum, "
            "np.sign, np.clip) or conversions to float; give the prior as sympy expressions "
            "instead (sp.Max, sp.Min, sp.sign are supported)") from e


def _check_trace(prior, traced, xs, us):
    xs = np.atleast_2d(np.asarray(xs, dtype=float))
    expected = prior(xs, us)
    got = np.array([np.asarray(traced(xs[k], [] if us is None else us[k])).ravel()
                    for k in range(len(xs))])
    scale = max(float(np.max(np.abs(expected))), 1e-300)
    if not np.allclose(got, expected, rtol=TRACE_TOLERANCE, atol=TRACE_TOLERANCE * scale):
        raise ExportError("the prior traced into CasADi does not agree with the callable "
                          f"(largest difference {np.max(np.abs(got - expected)):.3g}); it "
                          "probably depends on values in a way tracing cannot see: give it "
                          "as sympy expressions instead")


def library_columns(expressions, names, x, u):
    """CasADi column ``(p, 1)`` of the library's columns (sympy expressions) at ``x``, ``u``."""
    ca = casadi_module()
    symbols = variables(names, x, u)
    return ca.vertcat(*[ca.SX(to_casadi(e, symbols, term=feature_name(e, names)))
                        for e in expressions])


def hybrid_function(model, *, check_points=None):
    """CasADi Function ``f(x (n,), u (r,)) -> ẋ (n,)`` of a fitted hybrid model, built from its
    active terms and its prior (traced when it is a callable)."""
    ca = casadi_module()
    x, u = ca.SX.sym("x", model.n_states_), ca.SX.sym("u", model.n_inputs_)
    active = np.flatnonzero(np.any(model.coef_ != 0, axis=0))
    g = ca.SX.zeros(model.n_states_, 1)
    if len(active):
        theta = library_columns([model.feature_expressions_[j] for j in active],
                                model.variable_names_, x, u)
        g = ca.mtimes(ca.DM(model.coef_[:, active]), theta)
    f = prior_expression(model.prior_, x, u, check_points=check_points) + g
    return ca.Function("hybrid", [x, u], [f], ["x", "u"], ["xdot"])


def rk4_step(f, n_states: int, n_inputs: int, substeps: int, *, n_parameters: int = 0):
    """CasADi Function ``step(x (n,), U (r (2S+1),), h, [p]) -> x_next`` : ``S`` classical
    RK4 steps of length ``h / S`` with the input at the stage times (``U`` column-major:
    the ``2S + 1`` stage values of input 0, then of input 1, ...)."""
    ca = casadi_module()
    width = 2 * substeps + 1
    x = ca.SX.sym("x", n_states)
    stages = ca.SX.sym("U", n_inputs * width)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", n_parameters)
    extra = [p] if n_parameters else []

    def rhs(z, j):
        uj = ca.vertcat(*[stages[i * width + j] for i in range(n_inputs)])
        return f(z, uj, *extra)

    z, dt = x, h / substeps
    for s in range(substeps):
        z = runge_kutta_step(rhs, z, dt, 2 * s, 2 * s + 1, 2 * s + 2)
    return ca.Function("step", [x, stages, h, *extra], [z])


def rk4_substep(f, n_states: int, n_inputs: int, n_parameters: int):
    """CasADi Function ``substep(x (n,), U (3 r,), dt, p) -> x_next`` for ``f(x, u, p)``: one
    classical RK4 step of length ``dt`` with the input at its start, middle and end (``U``
    column-major: the three values of input 0, then of input 1, ...). The same arithmetic as
    one substep of :func:`rk4_step`."""
    ca = casadi_module()
    x, stages, dt = ca.SX.sym("x", n_states), ca.SX.sym("U", 3 * n_inputs), ca.SX.sym("dt")
    p = ca.SX.sym("p", n_parameters)

    def rhs(z, j):
        return f(z, ca.vertcat(*[stages[3 * i + j] for i in range(n_inputs)]), p)

    return ca.Function("substep", [x, stages, dt, p], [runge_kutta_step(rhs, x, dt, 0, 1, 2)])


def chained_step(substep, n_inputs: int, substeps: int):
    """``step(z, U (r (2S+1),), h, p) -> z_next``: ``substep`` (any function of ``(z, U3, dt,
    p)``, e.g. a state with its sensitivities) applied ``S = substeps`` times with
    ``dt = h / S``, substep ``j`` taking stage values ``2j, 2j+1, 2j+2`` of every input (the
    layout of :func:`stage_columns`). A loop (CasADi ``mapaccum``), not an unrolled
    expression, so its size does not grow with ``substeps``."""
    ca = casadi_module()
    width = 2 * substeps + 1
    z = ca.MX.sym("z", substep.size1_in(0))
    stages = ca.MX.sym("U", n_inputs * width)
    h, p = ca.MX.sym("h"), ca.MX.sym("p", substep.size1_in(3))
    if n_inputs:
        table = ca.reshape(stages, width, n_inputs)          # [stage, input]
        per = ca.horzcat(*[ca.vec(table[2 * j:2 * j + 3, :]) for j in range(substeps)])
    else:
        per = ca.MX(0, substeps)
    out = substep.mapaccum(substeps)(z, per, h / substeps, p)
    return ca.Function("step", [z, stages, h, p], [out[:, -1]])


def stage_columns(stages: np.ndarray) -> np.ndarray:
    """``(k, 2S+1, r)`` stage inputs as the ``(r (2S+1), k)`` matrix :func:`rk4_step` maps over."""
    k = stages.shape[0]
    return np.ascontiguousarray(stages.transpose(2, 1, 0).reshape(-1, k))
