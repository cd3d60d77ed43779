"""Simulation of the hybrid model with its sensitivities, for output-error fits.

The model ``ẋ = f_m(x, u) + Ξ θ(x, u)`` is discretised by RK4 with the input at its stage
times (exactly the steps :meth:`DiscrepancyModel.simulate` takes with ``method="rk4"``).
The sensitivities of the state to the state it started from and to chosen coefficients
ride along as extra state through the RK4 stages (forward sensitivities of the discrete
map, exact; CasADi differentiates the right-hand side symbolically once). A step chains
its substeps in a CasADi loop and a block chains ``length`` steps, so nothing grows with
the record or with ``substeps``; blocks are compiled to C when that pays
(:mod:`discrepancy.models.compiled`).

Two ways to run a record: :meth:`ShootingModel.simulate` and
:meth:`ShootingModel.sensitivities` go through it from its first state (single shooting);
:meth:`ShootingModel.segments` runs many segments, each from its own state, in one call
(multiple shooting; CasADi's thread map spreads them over ``n_jobs`` threads). Other
modules (output error, and estimators that need a discrete model with exact Jacobians)
use these three methods; parameters are given as the flattened ``Ξ`` (row-major, ``Ξ[i,
j]`` at ``i p + j``) and sensitivities are taken with respect to ``parameters``, indices
into that vector.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .casadi_form import (
    _casadi,
    chained_step,
    library_columns,
    nan_safe,
    prior_expression,
    rk4_substep,
    stage_columns,
)
from .compiled import compile_function, source_of, worth_compiling

#: steps per block when a whole record is run from its start
BLOCK = 256
#: largest output of one call (bytes); more segments are run in batches
BATCH_BYTES = 2**25


@dataclass
class Sensitivities:
    """States ``(m, n)`` at the samples (row 0 is the start) and their derivatives:
    ``d_x0`` ``(m, n, n)`` with respect to the start and ``d_coef`` ``(m, n, q)`` with
    respect to the ``q`` chosen coefficients."""

    states: np.ndarray
    d_x0: np.ndarray
    d_coef: np.ndarray


class ShootingModel:
    """The discretised hybrid model of one set-up, with all ``n p`` coefficients as inputs.

    Args:
        setup: a :class:`~discrepancy.models.setup.FitSetup` (names, prior, library).
        substeps: RK4 steps per sample interval (a positive integer, checked by the caller).
        check_points: ``(states, inputs)`` on which a traced callable prior is checked.
        jit: compile blocks to C: ``True``, ``False`` or ``"auto"`` (when it pays for
            ``work`` evaluated steps; see :func:`~discrepancy.models.compiled.worth_compiling`).
        work: the number of steps (samples × passes) the caller expects to evaluate.
        n_jobs: threads that run segments in parallel.
    """

    def __init__(self, setup, substeps: int, *, check_points=None, jit="auto",
                 work: float = 0.0, n_jobs: int = 1):
        ca = _casadi()
        n, r, p = setup.n_states, setup.n_inputs, setup.n_features
        self.n, self.r, self.p, self.substeps = n, r, p, substeps
        self.jit, self.work, self.n_jobs = jit, work, n_jobs
        x, u, coef = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("xi", n * p)
        theta = library_columns(setup.library.feature_expressions_, setup.variable_names,
                                x, u)
        prior = prior_expression(setup.prior, x, u, check_points=check_points)
        rhs = prior + ca.mtimes(ca.reshape(coef, p, n).T, theta)   # row-major Ξ (n, p)
        self.rhs_function = ca.Function("f", [x, u, coef], [rhs])
        self.library_function = ca.Function("theta", [x, u], [theta])
        self._prior_uses = _uses(ca.jacobian(prior, x))       # (n, n): f_m,j uses x_i
        self._term_uses = _uses(ca.jacobian(theta, x))        # (p, n): θ_k uses x_i
        self._substep = rk4_substep(self.rhs_function, n, r, n * p)
        self._blocks, self._maps = {}, {}
        self.compiled = {}          # kind -> whether its block runs compiled

    # ------------------------------------------------------------------ functions
    def width(self, parameters) -> int:
        """Length of the carried state: ``n`` (plain) or ``n + n² + n q``."""
        return self.n if parameters is None else self.n * (1 + self.n + len(parameters))

    def block(self, parameters, length: int):
        """``(z0, U (r (2S+1), length), h (1, length), ξ (n p)) -> z (width, length)``:
        ``length`` steps of the state (``parameters=None``) or of the state with its
        sensitivities to the start and to ``parameters``."""
        key = (None if parameters is None else tuple(parameters), length)
        if key not in self._blocks:
            substep = self._substep if parameters is None else _sensitive_substep(
                self.rhs_function, self.n, self.r, self.n * self.p, parameters)
            name = f"block_{'plain' if parameters is None else 'sens'}_{length}"
            block = _accumulated(chained_step(substep, self.r, self.substeps), name, length)
            cost = self.work * self.substeps * substep.n_instructions()
            self._blocks[key] = self._maybe_compiled(block, key, cost)
        return self._blocks[key]

    def _maybe_compiled(self, block, key, instructions: float):
        """``block`` compiled when ``jit`` says so or it pays for ``instructions``."""
        if self.jit is False:
            self.compiled[key] = False
            return block
        source = source_of(block)
        if self.jit is True or worth_compiling(block, instructions, source):
            built = compile_function(block, source)
            if built is not None:
                self.compiled[key] = True
                return built
        self.compiled[key] = False
        return block

    def _mapped(self, parameters, length: int, count: int):
        key = (None if parameters is None else tuple(parameters), length, count)
        if key not in self._maps:
            block = self.block(parameters, length)
            threads = min(self.n_jobs, count)
            mapped = block.map(f"segments_{count}", "thread" if threads > 1 else "serial",
                               count, [3], [])           # ξ (input 3) shared, not mapped
            self._maps[key] = _Call(mapped, threads)
        return self._maps[key]

    # ------------------------------------------------------------------ running
    def _start(self, x0, parameters) -> np.ndarray:
        """Carried start(s) ``(..., width)``: the state, identity and zero sensitivities."""
        x0 = np.asarray(x0, dtype=float)
        if parameters is None:
            return x0
        lead = x0.shape[:-1]
        eye = np.broadcast_to(np.eye(self.n).ravel(order="F"), (*lead, self.n * self.n))
        zero = np.zeros((*lead, self.n * len(parameters)))
        return np.concatenate([x0, eye, zero], axis=-1)

    def _unpack(self, carried, parameters) -> Sensitivities | np.ndarray:
        """Split carried values ``(..., width)`` into states and sensitivities."""
        n = self.n
        if parameters is None:
            return carried
        lead = carried.shape[:-1]
        d_x0 = carried[..., n:n + n * n].reshape(*lead, n, n, order="F")
        d_coef = carried[..., n + n * n:].reshape(*lead, n, len(parameters), order="F")
        return Sensitivities(carried[..., :n], d_x0, d_coef)

    def _run(self, parameters, x0, stages, h, coef) -> np.ndarray:
        """Carried values at every sample ``(len(h) + 1, width)`` from ``x0``."""
        k, c = len(h), np.ascontiguousarray(coef, dtype=float).ravel()
        length = block_length(k, self.substeps)
        cols, lengths = self.columns(stages, h, length)
        key = (None if parameters is None else tuple(parameters), length, 0)
        if key not in self._maps:
            self._maps[key] = _Call(self.block(parameters, length))
        call = self._maps[key]
        out = np.empty((len(lengths) + 1, self.width(parameters)))
        out[0] = self._start(x0, parameters)
        for i in range(0, len(lengths), length):
            call(out[i + 1:i + 1 + length], out[i].copy(), cols[i:i + length],
                 lengths[i:i + length], c)
        return out[:k + 1]

    def columns(self, stages, h, length: int):
        """Stage inputs ``(K, r (2S+1))`` and step lengths ``(K,)`` of ``len(h)`` steps (time
        along axis 0), padded to a multiple ``K`` of ``length`` with steps of length 0
        (which change nothing)."""
        k = len(h)
        padded = max(1, -(-k // length)) * length
        cols = np.zeros((padded, self.r * (2 * self.substeps + 1)))
        if self.r and k:
            cols[:k] = stage_columns(stages).T
        lengths = np.zeros(padded)
        lengths[:k] = h
        return cols, lengths

    def simulate(self, x0, stages, h, coef) -> np.ndarray:
        """States ``(len(h) + 1, n)`` from ``x0`` with coefficients ``coef`` ``(n, p)``."""
        return self._run(None, x0, stages, h, coef)

    def sensitivities(self, x0, stages, h, coef, parameters=None) -> Sensitivities:
        """States from ``x0`` and their derivatives with respect to ``x0`` and to the
        coefficients ``parameters`` (indices into the flattened ``Ξ``; default all)."""
        parameters = list(range(self.n * self.p)) if parameters is None else list(parameters)
        return self._unpack(self._run(parameters, x0, stages, h, coef), parameters)

    def segments(self, starts, cols, lengths, coef, parameters=None):
        """Run ``N`` segments of ``L`` steps each from their own starts.

        Args:
            starts: ``(N, n)`` states the segments start from.
            cols, lengths: stage inputs ``(N L, r (2S+1))`` and step lengths ``(N L,)``
                (time along axis 0, segment after segment; pad a short one with steps of
                length 0).
            coef: ``(n, p)`` coefficients.
            parameters: ``None`` for states only, else the coefficient indices to
                differentiate with respect to (states and sensitivities to the start only
                for an empty list).

        Returns:
            states ``(N, L + 1, n)`` (the starts first), or :class:`Sensitivities` whose
            arrays have the leading shape ``(N, L + 1)``.
        """
        starts = np.asarray(starts, dtype=float)
        count = len(starts)
        length = len(lengths) // max(count, 1)
        width, c = self.width(parameters), np.ascontiguousarray(coef, dtype=float).ravel()
        out = np.empty((count, length + 1, width))
        out[:, 0] = self._start(starts, parameters)
        batch = max(1, min(count, BATCH_BYTES // (8 * width * length)))
        values = np.empty((batch * length, width))
        for first in range(0, count, batch):
            last = min(first + batch, count)
            call = self._mapped(parameters, length, last - first)
            span = slice(first * length, last * length)
            result = values[:(last - first) * length]
            call(result, np.ascontiguousarray(out[first:last, 0]), cols[span], lengths[span], c)
            out[first:last, 1:] = result.reshape(last - first, length, width)
        return self._unpack(out, parameters)

    # ------------------------------------------------------------------ structure
    def influences(self, allowed: np.ndarray) -> np.ndarray:
        """``(n, n)`` bool: ``[j, i]`` when the equation of state ``j`` can depend on state
        ``i`` through the prior or a term ``allowed`` ``(n, p)`` in that equation."""
        return self._prior_uses | (allowed.astype(int) @ self._term_uses.astype(int) > 0)

    def rhs_and_jacobian(self, u, coef):
        """``(f, dfdx)``: numpy callables of the state ``(n,)`` giving the model's
        derivative ``(n,)`` and its Jacobian ``(n, n)`` at input ``u`` ``(r,)``."""
        if not hasattr(self, "_rhs_jacobian"):
            ca = _casadi()
            x = ca.SX.sym("x", self.n)
            u_sym, c = ca.SX.sym("u", self.r), ca.SX.sym("c", self.n * self.p)
            value = self.rhs_function(x, u_sym, c)
            self._rhs_jacobian = ca.Function("fj", [x, u_sym, c],
                                             [value, ca.jacobian(value, x)])
        c = np.asarray(coef, dtype=float).ravel()

        def f(x):
            return np.asarray(self._rhs_jacobian(x, u, c)[0]).ravel()

        def dfdx(x):
            return np.asarray(self._rhs_jacobian(x, u, c)[1])

        return f, dfdx

    def theta(self, states, inputs) -> np.ndarray:
        """Library columns ``(m, p)`` along a trajectory (for scaling the coefficients)."""
        u = np.zeros((len(states), 0)) if inputs is None else inputs
        return np.asarray(self.library_function.map(len(states))(states.T, u.T)).T


def block_length(k: int, substeps: int) -> int:
    """Steps per call for a run of ``k`` steps: a power of two, at least ``k`` when that is
    at most :data:`BLOCK` and ``4 BLOCK / substeps`` (the padding of the last call is work
    too: 3 samples with 10,000 substeps once ran 256 padded steps per call)."""
    need = 1 << max(0, (k - 1).bit_length())
    cap = 1 << (min(BLOCK, max(1, 4 * BLOCK // substeps)).bit_length() - 1)
    return max(1, min(need, cap))


class _Call:
    """A CasADi Function called on numpy arrays without copies (CasADi's buffer
    interface): arguments and the result are C-contiguous float arrays whose memory is
    the column-major layout CasADi expects, i.e. the transposes of its matrices."""

    def __init__(self, function, threads: int = 1):
        self.function, self.threads = function, threads
        self.buffer, self.evaluate = function.buffer()

    def __call__(self, out, *args):
        arrays = [np.ascontiguousarray(a, dtype=float) for a in args]
        for i, a in enumerate(arrays):
            self.buffer.set_arg(i, memoryview(a))
        self.buffer.set_res(0, memoryview(out))
        self.evaluate()
        return out


def _accumulated(step, name: str, length: int):
    """``(z0, U (rw, length), h (1, length), ξ) -> z (width, length)``: ``step`` applied
    ``length`` times, ``ξ`` shared by all steps (CasADi's ``mapaccum`` would map it too)."""
    ca = _casadi()
    z, c = ca.MX.sym("z", step.size1_in(0)), ca.MX.sym("p", step.size1_in(3))
    stages, h = ca.MX.sym("U", step.size1_in(1), length), ca.MX.sym("h", 1, length)
    out = step.mapaccum(length)(z, stages, h, c)
    return ca.Function(name, [z, stages, h, c], [out])


def _sensitive_substep(rhs, n: int, r: int, n_coef: int, parameters):
    """One RK4 substep of the state and its forward sensitivities, as one carried vector
    ``[x, vec(S_x0), vec(S_coef)]`` (column-major). The sensitivities follow the stages:
    ``K_i = f_x(z_i) S_i + f_ξ(z_i)``, ``S_{i+1} = S + a_i dt K_i``, ``S ← S + dt/6 (K_1
    + 2 K_2 + 2 K_3 + K_4)``: the exact derivative of the substep (the same arithmetic as
    :func:`~discrepancy.models.casadi_form.rk4_substep`). ``f_x`` and ``f_ξ`` are taken
    of :func:`~discrepancy.models.casadi_form.nan_safe`'s form of ``f``, and entries that
    are still not finite count as 0 (a slope that is infinite at a point is flat there)."""
    ca = _casadi()
    q = len(parameters)
    x, u, c = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("c", n_coef)
    value = rhs(x, u, c)
    safe = nan_safe(value)
    chosen = ca.vertcat(*[c[int(i)] for i in parameters]) if q else ca.SX(0, 1)
    f_x = _flat_where_undefined(ca.jacobian(safe, x))
    f_c = _flat_where_undefined(ca.jacobian(safe, chosen)) if q else ca.SX(n, 0)
    parts = ca.Function("f_and_jacobians", [x, u, c], [value, f_x, f_c])
    z = ca.SX.sym("z", n * (1 + n + q))
    stages, dt = ca.SX.sym("U", 3 * r), ca.SX.sym("dt")
    state = z[:n]
    sens = ca.reshape(z[n:], n, n + q)                   # [S_x0 | S_coef]
    zero = ca.SX(n, n)

    def stage(point, tangent, j):
        f, fx, fc = parts(point, ca.vertcat(*[stages[3 * i + j] for i in range(r)]), c)
        return f, ca.mtimes(fx, tangent) + ca.horzcat(zero, fc)

    k1, t1 = stage(state, sens, 0)
    k2, t2 = stage(state + dt / 2 * k1, sens + dt / 2 * t1, 1)
    k3, t3 = stage(state + dt / 2 * k2, sens + dt / 2 * t2, 1)
    k4, t4 = stage(state + dt * k3, sens + dt * t3, 2)
    out = ca.vertcat(state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4),
                     ca.vec(sens + dt / 6 * (t1 + 2 * t2 + 2 * t3 + t4)))
    return ca.Function("sensitive_substep", [z, stages, dt, c], [out])


def _flat_where_undefined(jacobian):
    """Entries that are infinite or NaN (``sqrt`` at 0, ``0 * inf`` at a kink such as
    ``sqrt(max(x, 0))`` below 0) count as 0 for this substep: otherwise the forward
    recursion ``S ← A S`` would carry the NaN through every later sample."""
    ca = _casadi()
    return ca.if_else(ca.fabs(jacobian) < 1e300, jacobian, 0)


def _uses(jacobian) -> np.ndarray:
    """Structural nonzeros of a CasADi Jacobian as a bool array."""
    pattern = jacobian.sparsity()
    out = np.zeros(pattern.shape, bool)
    rows, cols = pattern.get_triplet()
    out[rows, cols] = True
    return out
