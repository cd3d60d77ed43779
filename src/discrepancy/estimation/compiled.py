"""The filters' steps as CasADi Functions, built once per filter from
:mod:`~discrepancy.estimation.kalman_math` on CasADi symbols.

Every Function takes and returns one flat column, so a call from Python converts one
array each way (the overhead of a call is then a few tens of microseconds, which is most
of an online step). Layouts (``vec`` is column-major):

* predict: ``[x; vec P; U; h] -> [x⁺; vec P⁺; vec C]`` (``U``: the input at the
  ``2S + 1`` stage times of the interval, input by input; ``C = Cov(x, x⁺)``);
* update: ``[x; vec P; y; w] -> [x; vec P; e; vec S; nll]`` (``w``: 1 where ``y`` is
  measured);
* step (update then predict, for whole records): carry ``[x; vec P]`` of the prediction,
  data ``[y; w; U; h]``, output ``[x; vec P; e; vec S; nll; vec C]`` of the update and the
  carry of the next prediction; ``mapaccum`` runs ``BLOCK`` of them per call.

The noise covariances and model parameters are inputs of :func:`step_expressions`, so a
prediction-error fit builds the same step with them as symbols.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..hybrid.codegen import BufferedFunction
from . import kalman_math as km
from .backends import CasadiOps

#: samples per compiled call of a whole-record filter
BLOCK = 128


def layout(n: int, k: int, r: int, substeps: int) -> dict:
    """Sizes of the flat columns."""
    width = r * (2 * substeps + 1)
    return {"carry": n + n * n, "data": 2 * k + width + 1, "stages": width,
            "out": n + n * n + k + k * k + 1 + n * n}


def step_expressions(ca, kind: str, ops: CasadiOps, n: int, k: int, *, Q, R, substeps: int,
                     discrete: bool, weights=None):
    """Symbols and expressions of one update and one prediction: a dict with ``carry``,
    ``data`` (symbols), ``update`` (``x, P, e, S, nll``), ``predict`` (``x, P, C``) from
    the updated state, and the separate symbols ``x, P, U, h, y, w``."""
    sizes = layout(n, k, ops.r, substeps)
    carry, data = ca.SX.sym("carry", sizes["carry"]), ca.SX.sym("data", sizes["data"])
    x, P = carry[:n], ca.reshape(carry[n:], n, n)
    y, w = data[:k], data[k:2 * k]
    U, h = data[2 * k:2 * k + sizes["stages"]], data[-1]
    if kind == "ekf":
        update = km.ekf_update(ops, x, P, y, w, R)
        predict = km.ekf_predict(ops, update[0], update[1], U, h, Q, substeps, discrete)
    else:
        update = km.ukf_update(ops, x, P, y, w, R, weights)
        predict = km.ukf_predict(ops, update[0], update[1], U, h, Q, substeps, discrete,
                                 weights)
    return {"carry": carry, "data": data, "x": x, "P": P, "U": U, "h": h, "y": y, "w": w,
            "update": update, "predict": predict}


def flat_update(ca, update):
    """The update's ``(x, P, e, S, nll)`` as one CasADi column ``[x; vec P; e; vec S; nll]``
    (the update layout of the module docstring)."""
    x, P, e, S, nll = update
    return ca.vertcat(x, ca.vec(P), e, ca.vec(S), nll)


class CompiledSteps:
    """The predict, update and block Functions of one filter (constants baked in). The
    block, which whole records use, is built at once; the online ``predict`` and ``update``
    when first called (a filter that only runs records, as in a search over noise levels,
    never builds them)."""

    def __init__(self, kind, dynamics, measurement, Q, R, substeps, weights):
        import casadi as ca

        n, k, r = dynamics.n, measurement.k, dynamics.r
        self.n, self.k, self.r, self.substeps = n, k, r, substeps
        self._kind, self._discrete, self._weights = kind, dynamics.discrete_time, weights
        self._Q, self._R = ca.DM(Q), ca.DM(R)
        self._ops = CasadiOps(ca, dynamics.casadi, ca.DM(dynamics.parameters),
                              measurement.casadi, n, r, substeps)
        sym = step_expressions(ca, kind, self._ops, n, k, Q=self._Q, R=self._R,
                               substeps=substeps, discrete=dynamics.discrete_time,
                               weights=weights)
        self._sym = sym
        xp, Pp, C = sym["predict"]
        step = ca.Function("step", [sym["carry"], sym["data"]],
                           [ca.vertcat(xp, ca.vec(Pp)),
                            ca.vertcat(flat_update(ca, sym["update"]), ca.vec(C))])
        self.block = step.mapaccum("filter", BLOCK)

    @cached_property
    def predict(self):
        """``[x; vec P; U; h] -> [x⁺; vec P⁺; vec C]`` (a flat call, see :func:`fast_call`)."""
        import casadi as ca

        x, P, U, h = (self._sym[name] for name in ("x", "P", "U", "h"))
        if self._kind == "ekf":
            alone = km.ekf_predict(self._ops, x, P, U, h, self._Q, self.substeps,
                                   self._discrete)
        else:
            alone = km.ukf_predict(self._ops, x, P, U, h, self._Q, self.substeps,
                                   self._discrete, self._weights)
        return fast_call(ca.Function(
            "predict", [ca.vertcat(x, ca.vec(P), U, h)],
            [ca.densify(ca.vertcat(alone[0], ca.vec(alone[1]), ca.vec(alone[2])))]))

    @cached_property
    def update(self):
        """``[x; vec P; y; w] -> [x; vec P; e; vec S; nll]`` (a flat call)."""
        import casadi as ca

        x, P, y, w = (self._sym[name] for name in ("x", "P", "y", "w"))
        if self._kind == "ekf":
            update = km.ekf_update(self._ops, x, P, y, w, self._R)
        else:
            update = km.ukf_update(self._ops, x, P, y, w, self._R, self._weights)
        return fast_call(ca.Function("update", [ca.vertcat(x, ca.vec(P), y, w)],
                                     [ca.densify(flat_update(ca, update))]))

    def run(self, x0, P0, data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """See :func:`run_blocks`."""
        return run_blocks(self.block, x0, P0, data,
                          layout(self.n, self.k, self.r, self.substeps)["out"])


def fast_call(function):
    """``call(flat (in,)) -> (out,)``: ``function`` (one input, one output, both columns)
    through CasADi's buffer interface (:class:`~discrepancy.hybrid.codegen.BufferedFunction`),
    the result copied. Not thread-safe: one filter object per thread."""
    buffered = BufferedFunction(function)

    def call(values):
        return buffered(values)[:, 0].copy()

    return call


def run_blocks(block, x0, P0, data: np.ndarray, width: int, extra=()):
    """Outputs ``(m, width)`` of every step of ``block`` (a ``mapaccum`` of ``BLOCK`` steps,
    called with the carry, the data columns and ``extra``) over ``data`` ``(m, data)``, and
    the carry after each ``(m, n + n²)``; padding steps (``h = 0``, nothing measured)
    change nothing. Stops at a carry that is not finite (the rest stays NaN)."""
    m = len(data)
    padded = -(-m // BLOCK) * BLOCK
    columns = np.zeros((data.shape[1], padded))
    columns[:, :m] = data.T
    carry = np.concatenate([x0, P0.ravel(order="F")])
    out = np.full((padded, width), np.nan)
    carries = np.full((padded, len(carry)), np.nan)
    for i in range(0, padded, BLOCK):
        after, outputs = block(carry, columns[:, i:i + BLOCK], *extra)
        out[i:i + BLOCK] = np.asarray(outputs).T
        carries[i:i + BLOCK] = np.asarray(after).T
        carry = carries[i + BLOCK - 1]
        if not np.all(np.isfinite(carry)):
            break
    return out[:m], carries[:m]
