"""Fixed-step simulation compiled once: the hybrid model's RK4 map run by CasADi.

Stepping a small model in Python costs tens of microseconds per right-hand-side call, so a
long record with a measured input (1e5 samples, four RK4 stages, a few substeps) takes
tens of seconds. Here the model is turned into CasADi expressions once
(:mod:`discrepancy.hybrid.casadi_form`), one step of RK4 with the input at its stage times
becomes a CasADi Function, and ``mapaccum`` runs all steps in CasADi's virtual machine:
the same arithmetic as the Python stepper (equal to rounding), about a hundred times
faster. Written here because no library we use compiles a model given as sympy terms plus
a numpy callable; CasADi does the compiling.
"""
from __future__ import annotations

import numpy as np

from ..._optional import missing
from ...errors import ExportError
from ...hybrid.casadi_form import (
    chained_step,
    hybrid_function,
    rk4_step,
    rk4_substep,
    stage_columns,
)

#: steps per compiled call (building CasADi's map costs time in proportion to its length,
#: so one map of this length is built once and called block after block); with many
#: substeps fewer, so that a call does at most ``CHUNK * 4`` RK4 steps (the last block is
#: padded with steps of length 0, which are work too)
CHUNK = 512
#: most substeps unrolled into one expression; beyond, the substeps run as a CasADi loop
#: whose size does not grow with ``substeps`` (unrolling 10,000 took 25 s to build)
MAX_UNROLLED = 32


def compiled_stepper(model, x0, u, substeps: int):
    """``run(x0, stages (k, 2S+1, r), h (k,)) -> (k, n)`` for ``integrate(compiled=...)``, or
    ``None`` when CasADi is missing or the model cannot be expressed in it (a prior that
    branches on values, a numpy-only library term): the caller then steps in Python."""
    if missing("casadi"):
        return None
    cache = model._compiled_steps
    if substeps not in cache:
        try:
            f = hybrid_function(model, check_points=_check_points(model, x0, u))
        except ExportError:
            cache[substeps] = None
        else:
            step = _step(f, model.n_states_, model.n_inputs_, substeps)
            cache[substeps] = step.mapaccum("simulate", _chunk(substeps))
    chunk = cache[substeps]
    if chunk is None:
        return None
    block = _chunk(substeps)

    def run(start, stages, h):
        k = len(h)
        padded = -(-k // block) * block               # steps of length 0 change nothing
        columns = np.zeros((stages.shape[2] * stages.shape[1] if model.n_inputs_ else 0,
                            padded))
        if model.n_inputs_:
            columns[:, :k] = stage_columns(stages)
        lengths = np.zeros((1, padded))
        lengths[0, :k] = h
        out, x = np.empty((padded, model.n_states_)), np.asarray(start, dtype=float)
        for i in range(0, padded, block):
            done = np.asarray(chunk(x, columns[:, i:i + block], lengths[:, i:i + block]))
            out[i:i + block] = done.T
            x = done[:, -1]
            if not np.all(np.isfinite(x)):
                out[i + block:] = np.nan
                break
        return out[:k]

    return run


def _chunk(substeps: int) -> int:
    """Steps per compiled call for ``substeps`` RK4 steps per step."""
    return max(1, min(CHUNK, 4 * CHUNK // substeps))


def _step(f, n_states: int, n_inputs: int, substeps: int):
    """``step(x, U, h) -> x_next`` of ``substeps`` RK4 steps: unrolled when few (fastest to
    run), a loop when many (its build time does not grow with ``substeps``)."""
    if substeps <= MAX_UNROLLED:
        return rk4_step(f, n_states, n_inputs, substeps)
    import casadi as ca

    substep = rk4_substep(lambda z, u, p: f(z, u), n_states, n_inputs, 0)
    chained = chained_step(substep, n_inputs, substeps)
    x, h = ca.MX.sym("x", n_states), ca.MX.sym("h")
    stages = ca.MX.sym("U", n_inputs * (2 * substeps + 1))
    return ca.Function("step", [x, stages, h], [chained(x, stages, h, ca.MX(0, 1))])


def _check_points(model, x0, u):
    """A few states around ``x0`` and inputs from the first rows of ``u`` to check a traced
    prior on (malformed arguments give zeros here: integrate reports them)."""
    rng = np.random.default_rng(0)
    n, r = model.n_states_, model.n_inputs_
    try:
        x0 = np.asarray(x0, dtype=float).ravel()[:n]
        u = np.zeros((1, r)) if u is None else np.asarray(u, dtype=float).reshape(-1, r)[:5]
    except (TypeError, ValueError):
        x0, u = np.zeros(n), np.zeros((1, r))
    x0 = np.resize(np.nan_to_num(x0), n)
    spread = 0.1 * (np.abs(x0) + 1.0)
    xs = np.vstack([x0, x0 + spread * rng.standard_normal((4, n))])
    if r == 0:
        return xs, None
    return xs, np.nan_to_num(u[np.arange(len(xs)) % len(u)])
