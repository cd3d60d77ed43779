"""One classical Runge-Kutta (RK4) step, written once for every arithmetic the library uses.

Every fixed-step integration in the library (``simulate(method="rk4")``, batched forecasts,
the compiled CasADi maps of simulation, output error, MPC and the Kalman filters, the
reference data of the paper's examples) takes this step. The step uses only ``+`` and
multiplication by a step length, so ``x`` may be a numpy array (one state or a batch of
rows), a CasADi ``SX``/``MX`` expression, or any object with those two operations (the
filters move a state, its Jacobian and its noise together).

The input of a stage is whatever ``rates`` takes as its second argument: the input at the
step's start, middle and end (``u0``, ``um``, ``u1``, the stage times of the samples'
interpolation, see :func:`discrepancy.models.inputs.stage_inputs`), the same value three
times for a held input, stage indices, or ``(time, input)`` pairs. Written out because
scipy has no fixed-step RK4 and the CasADi graphs need the same formula on symbols.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any


def runge_kutta_step(rates: Callable[[Any, Any], Any], x, h, u0=None, um=None, u1=None):
    """``x`` after one classical RK4 step of length ``h`` of ``x' = rates(x, u)``.

    Args:
        rates: ``rates(x, u) -> x'`` (same shape and kind as ``x``).
        x: the state: ``(n,)``, a batch ``(B, n)``, or a CasADi column ``(n, 1)``.
        h: the step length (s): a number, a ``(B, 1)`` column for a batch of steps, or a
            CasADi symbol.
        u0, um, u1: the inputs passed to ``rates`` at the step's start (stage 1), middle
            (stages 2 and 3) and end (stage 4); None for a model without inputs.

    Returns:
        The state at ``t + h`` (the error of one step is ``O(h⁵)``, of a fixed span
        ``O(h⁴)``).
    """
    k1 = rates(x, u0)
    k2 = rates(x + h / 2 * k1, um)
    k3 = rates(x + h / 2 * k2, um)
    k4 = rates(x + h * k3, u1)
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
