"""The innovations' negative log-likelihood of a hybrid model whose coefficients and noise
levels are free, with its exact gradient (CasADi reverse mode through the whole filter).

The model is ``x' = f_m(x, u) + Ξ θ(x, u)`` with the coefficients of one support as symbols
(the terms off the support are not in the expressions, so sparse supports step faster),
augmented by the disturbance states of
:mod:`~discrepancy.estimation.disturbances`; process noise ``Q = diag(q²)`` per second and
measurement noise ``R = diag(r²)``. One step of the extended Kalman filter
(:mod:`~discrepancy.estimation.kalman_math`) is written once in CasADi symbols with
``(Ξ, q, r)`` as inputs and ``mapaccum`` runs ``BLOCK`` samples per call; a record's
objective is an MX graph of its blocks with the data as inputs, so its gradient costs
about three evaluations of the filter whatever the number of parameters. From
:data:`COMPILE_SAMPLES` samples the block and its reverse-mode derivative are compiled to C
(:func:`~discrepancy.hybrid.codegen.compiled`): one library per support, whatever the
records, cached on disk. The EKF's
covariance depends on the model's Jacobian, so the gradient needs second derivatives of
``f``: CasADi takes them from the same expressions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..hybrid.casadi_form import casadi_module, library_columns, prior_expression
from ..hybrid.codegen import compiled
from .backends import CasadiOps
from .compiled import BLOCK, flat_update, layout, run_blocks, step_expressions
from .disturbances import augment_casadi
from .dynamics import check_points

#: samples (over all records) from which an objective's blocks are compiled to C. Measured
#: on the prediction-error experiment's oscillator (3 filter states): an evaluation with its
#: gradient costs about 30 us per sample in CasADi's virtual machine and 2-3 us compiled,
#: compiling a support's blocks about a second, and a fit evaluates each support's objective
#: 15 to 20 times, so compiling pays from about 1,000 samples (sooner when a support comes
#: back: the library is cached). Whole fits, CPU with the compiler, cold cache: 6000 samples
#: 42 s -> 20 s, the quick experiment (1500-sample records) 43 s -> 21 s, identical
#: coefficients. Both costs grow with the filter's size, so the break-even in samples hardly
#: depends on the model
COMPILE_SAMPLES = 1000


@dataclass
class LikelihoodRecord:
    """One record's filter data ``(m, data)`` (see :mod:`~discrepancy.estimation.compiled`),
    its prior belief and the samples whose innovations count."""

    data: np.ndarray
    x0: np.ndarray
    P0: np.ndarray
    weights: np.ndarray


class InnovationLikelihood:
    """The filter of a set-up's hybrid model with free ``(Ξ, q, r)``.

    Args:
        setup: the model's :class:`~discrepancy.models.FitSetup`.
        measurement: a :class:`~discrepancy.estimation.measurement.Measurement`.
        equations: indices of the equations with a disturbance state.
        substeps: RK4 steps per sample interval.
        support: ``(n, p)`` bool, the free coefficients (row-major order in ``Ξ``'s input).
    """

    def __init__(self, setup, measurement, equations, substeps: int, support: np.ndarray):
        ca = casadi_module()
        n, r = setup.n_states, setup.n_inputs
        self.n, self.k, self.support = n, measurement.k, support
        self.N = n + len(equations)
        self.substeps = substeps
        rows, cols = np.nonzero(support)
        x, u, xi = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("xi", len(rows))
        used = sorted(set(cols.tolist()))
        theta = library_columns([setup.library.feature_expressions_[j] for j in used],
                                setup.variable_names, x, u) if used else ca.SX(0, 1)
        rhs = prior_expression(setup.prior, x, u, check_points=check_points(n, r))
        for i, (row, col) in enumerate(zip(rows, cols, strict=True)):
            rhs[int(row)] += xi[i] * theta[used.index(int(col))]
        f = augment_casadi(ca.Function("f", [x, u, xi], [rhs]), n, equations) \
            if equations else ca.Function("f", [x, u, xi], [rhs])
        self.f, self.r = f, r
        q, r_std = ca.SX.sym("q", self.N), ca.SX.sym("r", self.k)
        ops = CasadiOps(ca, f, xi, measurement.casadi, self.N, r, substeps)
        sym = step_expressions(ca, "ekf", ops, self.N, self.k, Q=ca.diag(q ** 2),
                               R=ca.diag(r_std ** 2), substeps=substeps, discrete=False)
        xp, Pp, C = sym["predict"]
        args = [sym["carry"], sym["data"], xi, q, r_std]
        carry_next = ca.vertcat(xp, ca.vec(Pp))
        self._full = ca.Function("step", args, [carry_next, ca.vertcat(
            flat_update(ca, sym["update"]), ca.vec(C))]).mapaccum("filter", BLOCK)
        self._nll = ca.Function("step_nll", args, [carry_next, sym["update"][4]]).mapaccum(
            "filter_nll", BLOCK)
        self.sizes = layout(self.N, self.k, r, substeps)
        self._compiled = None

    def objective(self, records: list[LikelihoodRecord], *, compile: bool | None = None):
        """The mean negative log-likelihood over the weighted samples of ``records`` (the
        mean over their total weight) and its gradient, as an :class:`Objective`
        ``(ξ (support), q (N), r (k)) -> (value, gradient)``; its filter blocks compiled to
        C when ``compile`` is True, or when None and the records hold
        :data:`COMPILE_SAMPLES` samples."""
        ca = casadi_module()
        parts = [(*_used_blocks(rec.data, rec.weights),
                  np.concatenate([rec.x0, rec.P0.ravel(order="F")])) for rec in records]
        if compile is None:
            compile = sum(len(w) for _, w, _ in parts) >= COMPILE_SAMPLES
        blocks = self._compiled_blocks() if compile else self._nll
        xi, q, r = ca.MX.sym("xi", int(self.support.sum())), ca.MX.sym("q", self.N), \
            ca.MX.sym("r", self.k)
        total, weight = ca.MX(0), sum(float(rec.weights.sum()) for rec in records)
        inputs = []
        for j, (columns, weights, start) in enumerate(parts):
            data, w = ca.MX.sym(f"data{j}", *columns.shape), ca.MX.sym(f"w{j}", len(weights))
            carry = ca.MX.sym(f"start{j}", len(start))
            inputs += [data, w, carry]
            for i in range(0, columns.shape[1], BLOCK):
                after, nll = blocks(carry, data[:, i:i + BLOCK], xi, q, r)
                total = total + ca.mtimes(nll, w[i:i + BLOCK])
                carry = after[:, -1]
        total = total / max(weight, 1.0)
        grads = ca.gradient(total, ca.vertcat(xi, q, r))
        return Objective(ca.Function("objective", [xi, q, r, *inputs], [total, grads]),
                         [v for part in parts for v in part])

    def _compiled_blocks(self):
        """The likelihood's filter blocks and their reverse-mode derivative as compiled C,
        built on first use (one library per support, whatever the records)."""
        if self._compiled is None:
            self._compiled = compiled(self._nll, reverse=True)
        return self._compiled

    def run(self, record: LikelihoodRecord, coef, q, r):
        """Step outputs and predictions of the filter over ``record`` (numeric), as
        :func:`~discrepancy.estimation.records.assemble_result` takes them; ``coef``: the
        full ``(n, p)`` coefficients (those of the support are used)."""
        extra = [np.asarray(coef, dtype=float)[self.support], np.asarray(q, dtype=float),
                 np.asarray(r, dtype=float)]
        return run_blocks(self._full, record.x0, record.P0, record.data,
                          self.sizes["out"], extra)


class Objective:
    """An objective bound to its records' data: ``objective(ξ, q, r)`` returns CasADi's
    ``(value, gradient)``; ``function`` is the CasADi Function (compiled or not) whose
    inputs after ``(ξ, q, r)`` are ``data``."""

    def __init__(self, function, data: list[np.ndarray]):
        self.function, self.data = function, data

    def __call__(self, xi, q, r):
        return self.function(xi, q, r, *self.data)


def _used_blocks(data, weights):
    """The record's data as columns ``(d, L)`` and its weights ``(L,)``: whole blocks up to
    the last one with a weighted sample, zero-padded past the record's end."""
    seen = np.flatnonzero(weights)
    used = 0 if not len(seen) else -(-(int(seen[-1]) + 1) // BLOCK) * BLOCK
    kept = min(len(data), used)
    columns, w = np.zeros((data.shape[1], used)), np.zeros(used)
    columns[:, :kept] = data[:kept].T
    w[:kept] = weights[:kept]
    return columns, w
