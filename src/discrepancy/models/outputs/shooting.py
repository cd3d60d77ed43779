"""Simulation of the hybrid model with its sensitivities, for output-error fits.

The model ``ẋ = f_m(x, u) + Ξ θ(x, u)`` is discretised by RK4 with the input at its stage
times (exactly the steps :meth:`DiscrepancyModel.simulate` takes with ``method="rk4"``),
and CasADi differentiates one step of the discrete map symbolically; the sensitivities of
the state to the initial state and to every coefficient ride along as extra state (forward
sensitivities of the discrete map, exact), ``BLOCK`` steps per compiled call, so the cost
grows linearly with the record and CasADi never builds a graph as long as the record.

Only the coefficients a fit may change (``free``) get sensitivities, and when the work is
large (:func:`worth_compiling`) both block functions are compiled to C
(:func:`~discrepancy.hybrid.codegen.compiled`, cached by source): the same operations in the
same order, so the same numbers as CasADi's virtual machine, about six times faster
(``benchmarks/bench_output_error.py``). The blocks write into numpy arrays through CasADi's
buffer interface (converting each block's result from a CasADi matrix cost as much as
computing it).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...hybrid.casadi_form import (
    casadi_module,
    library_columns,
    prior_expression,
    rk4_step,
    stage_columns,
)
from ...hybrid.codegen import BufferedFunction, compiled

#: steps per differentiated block
BLOCK = 256
#: work (sample intervals over all records times the width of the sensitivity state) from
#: which the blocks are compiled. Compiling takes about 1 s at width 26 and 40 s at width
#: 192 (it grows like the square of the width); a fit evaluates the sensitivities hundreds
#: of times, each costing about a microsecond per interval and width unit in CasADi's
#: virtual machine and a sixth of that compiled. The Cascaded Tanks (767 intervals, width
#: 46: 35,000) compile, and its reproduction went from 88 s to 31 s with the same results;
#: the short records of most tests (a few hundred samples of a small model) do not
COMPILE_WORK = 25_000


def worth_compiling(intervals: int, n: int, n_free: int) -> bool:
    """Whether a fit of ``intervals`` sample intervals, ``n`` states and ``n_free`` free
    coefficients should compile its blocks (see :data:`COMPILE_WORK`)."""
    return intervals * (n + n * n + n * n_free) >= COMPILE_WORK


@dataclass
class Sensitivities:
    """States ``(m, n)`` at the samples (row 0 is ``x0``) and their derivatives:
    ``d_x0`` ``(m, n, n)`` with respect to ``x0`` and ``d_coef`` ``(m, n, c)`` with
    respect to the free coefficients ``columns`` ``(c,)`` (indices into the row-major
    flattened ``Ξ``: ``Ξ[i, j]`` is ``i p + j``)."""

    states: np.ndarray
    d_x0: np.ndarray
    d_coef: np.ndarray
    columns: np.ndarray

    def d_coefficients(self, index) -> np.ndarray:
        """``d_coef`` for the flattened coefficient indices ``index`` (all free)."""
        position = np.searchsorted(self.columns, index)
        if np.any(position >= len(self.columns)) or \
                np.any(self.columns[np.minimum(position, len(self.columns) - 1)] != index):
            raise ValueError("sensitivities were asked for coefficients that are not free")
        return self.d_coef[:, :, position]


class ShootingModel:
    """The discretised hybrid model of one set-up, with all ``n p`` coefficients free.

    Args:
        setup: a :class:`~discrepancy.fitting.setup.FitSetup` (names, prior, library).
        substeps: RK4 steps per sample interval.
        check_points: ``(states, inputs)`` on which a traced callable prior is checked.
        free: ``(n, p)`` bool, the coefficients that get sensitivities (default all).
        compile: compile the blocks to C (warns and runs them uncompiled without a C
            compiler).
    """

    def __init__(self, setup, substeps: int, *, check_points=None, free=None,
                 compile: bool = False):
        ca = casadi_module()
        n, r = setup.n_states, setup.n_inputs
        p = setup.n_features
        self.n, self.r, self.p, self.substeps = n, r, p, substeps
        x, u, coef = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("xi", n * p)
        theta = library_columns(setup.library.feature_expressions_, setup.variable_names,
                                x, u)
        xi = ca.reshape(coef, p, n).T                      # row-major Ξ (n, p)
        rhs = prior_expression(setup.prior, x, u, check_points=check_points) + \
            ca.mtimes(xi, theta)
        f = ca.Function("f", [x, u, coef], [rhs])
        self._rhs, self._rhs_jacobian = f, None
        self.library_function = ca.Function("theta", [x, u], [theta])
        prior = rhs - ca.mtimes(xi, theta)
        self._prior_uses = _uses(ca.jacobian(prior, x))       # (n, n): f_m,j uses x_i
        self._term_uses = _uses(ca.jacobian(theta, x))        # (p, n): θ_k uses x_i
        step = rk4_step(f, n, r, substeps, n_parameters=n * p)
        free = np.ones((n, p), bool) if free is None else np.asarray(free, bool)
        self.free = np.flatnonzero(free.ravel())
        self._step, self._compile = step, compile
        plain = step.mapaccum("shooting_plain", BLOCK)
        self._plain = BufferedFunction(compiled(plain, enabled=compile))
        self._augmented = {}     # by the free coefficients: all of them, or none (x0 only)

    def _sensitive_blocks(self, free: np.ndarray) -> BufferedFunction:
        """The blocks of the state and its sensitivities to ``x0`` and ``free``, built (and
        compiled) on first use: fits of initial states alone need no coefficient's."""
        key = len(free)
        if key not in self._augmented:
            step = _sensitivity_step(self._step, self.n, free)
            blocks = step.mapaccum(f"shooting_sensitive_{key}", BLOCK)
            self._augmented[key] = BufferedFunction(compiled(blocks, enabled=self._compile))
        return self._augmented[key]

    def _blocks(self, stages, h):
        """Padded stage columns and step lengths, ``BLOCK`` steps at a time (steps of
        length 0 change nothing)."""
        k = len(h)
        padded = max(1, -(-k // BLOCK)) * BLOCK
        cols = np.zeros((self.r * (2 * self.substeps + 1), padded))
        if self.r:
            cols[:, :k] = stage_columns(stages)
        lengths = np.zeros((1, padded))
        lengths[0, :k] = h
        for i in range(0, padded, BLOCK):
            yield i, cols[:, i:i + BLOCK], lengths[:, i:i + BLOCK]

    def _run(self, blocks, start, stages, h, coef) -> np.ndarray:
        """The accumulated state of ``blocks`` at every sample ``(len(h) + 1, width)``."""
        k, c = len(h), np.asarray(coef, dtype=float).ravel()
        out = np.empty((k + 1 + BLOCK, len(start)))
        out[0] = state = start
        for i, cols, lengths in self._blocks(stages, h):
            block = blocks(state, cols, lengths, c)
            out[i + 1:i + 1 + BLOCK] = block.T
            state = block[:, -1].copy()
        return out[:k + 1]

    def simulate(self, x0, stages, h, coef) -> np.ndarray:
        """States ``(len(h) + 1, n)`` from ``x0`` with coefficients ``coef`` ``(n, p)``."""
        return self._run(self._plain, np.asarray(x0, dtype=float), stages, h, coef)

    def sensitivities(self, x0, stages, h, coef, *, coefficients: bool = True
                      ) -> Sensitivities:
        """States and their derivatives (see :class:`Sensitivities`); without
        ``coefficients`` only those to ``x0`` (``d_coef`` empty: a quarter of the work
        for a two-state model with ten free terms)."""
        free = self.free if coefficients else self.free[:0]
        n, npar = self.n, len(free)
        start = np.concatenate([np.asarray(x0, dtype=float), np.eye(n).ravel(order="F"),
                                np.zeros(n * npar)])
        out = self._run(self._sensitive_blocks(free), start, stages, h, coef)
        m = len(out)
        d_x0 = out[:, n:n + n * n].reshape(m, n, n, order="F")
        d_coef = out[:, n + n * n:].reshape(m, n, npar, order="F")
        return Sensitivities(out[:, :n], d_x0, d_coef, free)

    def rhs_and_jacobian(self, u, coef):
        """``(f, dfdx)``: numpy callables of the state ``(n,)`` giving the model's
        derivative ``(n,)`` and its Jacobian ``(n, n)`` at input ``u`` ``(r,)``."""
        if self._rhs_jacobian is None:      # only initial-state fits need it: built then
            ca = casadi_module()
            x, u_sym = ca.SX.sym("x", self.n), ca.SX.sym("u", self.r)
            c_sym = ca.SX.sym("c", self.n * self.p)
            value = self._rhs(x, u_sym, c_sym)
            self._rhs_jacobian = ca.Function("f_and_jacobian", [x, u_sym, c_sym],
                                             [value, ca.jacobian(value, x)])
        c = np.asarray(coef, dtype=float).ravel()

        def f(x):
            return np.asarray(self._rhs_jacobian(x, u, c)[0]).ravel()

        def dfdx(x):
            return np.asarray(self._rhs_jacobian(x, u, c)[1])

        return f, dfdx

    def influences(self, allowed: np.ndarray) -> np.ndarray:
        """``(n, n)`` bool: ``[j, i]`` when the equation of state ``j`` can depend on state
        ``i`` through the prior or a term ``allowed`` ``(n, p)`` in that equation."""
        return self._prior_uses | (allowed.astype(int) @ self._term_uses.astype(int) > 0)

    def theta(self, states, inputs) -> np.ndarray:
        """Library columns ``(m, p)`` along a trajectory (for scaling the coefficients)."""
        u = np.zeros((len(states), 0)) if inputs is None else inputs
        return np.asarray(self.library_function.map(len(states))(states.T, u.T)).T


def _sensitivity_step(step, n: int, free: np.ndarray):
    """One step of the state and its forward sensitivities, as one augmented state
    ``[x, vec(S_x0), vec(S_coef)]`` (column-major): ``S' = A S (+ B)`` with ``A = ∂step/∂x``
    and ``B = ∂step/∂coef`` for the ``free`` coefficients only, differentiated symbolically
    once for the step."""
    ca = casadi_module()
    n_parameters = step.size1_in(3)
    width = n + n * n + n * len(free)
    z = ca.SX.sym("z", width)
    cols = ca.SX.sym("U", step.size1_in(1))
    h, c = ca.SX.sym("h"), ca.SX.sym("c", n_parameters)
    x = z[:n]
    s_x = ca.reshape(z[n:n + n * n], n, n)
    s_c = ca.reshape(z[n + n * n:], n, len(free))
    nxt = step(x, cols, h, c)
    a = _finite_or(ca.jacobian(nxt, x), np.eye(n))
    b = _finite_or(ca.jacobian(nxt, ca.vertcat(*[c[int(i)] for i in free])),
                   np.zeros((n, len(free)))) if len(free) else ca.SX(n, 0)
    out = ca.vertcat(nxt, ca.vec(ca.mtimes(a, s_x)), ca.vec(ca.mtimes(a, s_c) + b))
    return ca.Function("sensitive_step", [z, cols, h, c], [out])


def _finite_or(jacobian, carry: np.ndarray):
    """``jacobian`` of one step with each entry that evaluates to an infinite or undefined
    slope (a square root at 0, ``sqrt(max(0, h))`` below 0: inf times 0) replaced by
    ``carry``'s: the identity for the state (that step carries its state over and only its
    increment, of the order of the step, counts as flat), zero for the coefficients. Without
    this, one such step spreads NaN through every later sensitivity and leaves the fit no
    slope to follow. Sparsity is kept; where every entry is finite the values agree with the
    plain Jacobian's to rounding (1e-10 relative on the benchmarks' fits: the compiled
    code's order of operations can change)."""
    ca = casadi_module()
    out = ca.SX(jacobian.sparsity())
    rows, cols = jacobian.sparsity().get_triplet()
    for k, (i, j) in enumerate(zip(rows, cols, strict=True)):
        entry = jacobian.nz[k]
        out.nz[k] = ca.if_else(ca.fabs(entry) < np.inf, entry, float(carry[i, j]))
    return out


def _uses(jacobian) -> np.ndarray:
    """Structural nonzeros of a CasADi Jacobian as a bool array."""
    pattern = jacobian.sparsity()
    out = np.zeros(pattern.shape, bool)
    rows, cols = pattern.get_triplet()
    out[rows, cols] = True
    return out
