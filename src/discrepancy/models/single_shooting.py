"""Single shooting with scipy's ``least_squares``: the reference for the output-error fit.

The same problem as :meth:`OutputErrorFit.solve` (scaled coefficients of a support and
the initial state of every record; the simulation error of the outputs, with the fit's
scales and ridge), solved the way it was before multiple shooting: each record simulated
from its initial state, the whole Jacobian ``(samples × outputs, coefficients + states)``
formed from the sensitivities, scipy's trust-region reflective method. Tests and
``benchmarks/bench_output_error.py`` compare the two answers; fits do not use it.
"""
from __future__ import annotations

import numpy as np
import scipy.optimize


def residuals(fit, theta, index, rows, ridge, *, jacobian: bool = True):
    """Scaled residuals (and Jacobian) at ``theta`` = [scaled coefficients of ``index``,
    initial state of every record]."""
    coef = fit.coefficients(theta[:len(index)], index)
    x0s = theta[len(index):].reshape(len(fit.records), fit.n)
    total = sum(int(w.sum()) for w in rows) * fit.out_map.k
    parts, jacobians = [], []
    width = len(index) + x0s.size
    for i, (record, w) in enumerate(zip(fit.records, rows, strict=True)):
        if not jacobian:
            states = fit.shooting.simulate(x0s[i], record.stages, record.h, coef)[w]
        else:
            sens = fit.shooting.sensitivities(x0s[i], record.stages, record.h, coef, index)
            states = sens.states[w]
            dh = fit.out_map.jacobian(states) / fit.y_scale[None, :, None]
            jac = np.zeros((len(states), fit.out_map.k, width))
            jac[:, :, :len(index)] = np.einsum("mkn,mnc->mkc", dh, sens.d_coef[w]) * \
                fit.coef_scale[index]
            jac[:, :, len(index) + i * fit.n:len(index) + (i + 1) * fit.n] = \
                np.einsum("mkn,mnj->mkj", dh, sens.d_x0[w])
            jacobians.append(jac.reshape(-1, width))
        parts.append(((fit.out_map(states) - record.y[w]) / fit.y_scale).ravel())
    scale = 1 / np.sqrt(max(total, 1))
    r = np.concatenate(parts) * scale
    if ridge and len(index):
        r = np.concatenate([r, np.sqrt(ridge) * theta[:len(index)]])
    if not np.all(np.isfinite(r)):
        r = np.full_like(r, 1e6)                        # a diverging trial is rejected
    if not jacobian:
        return r
    J = np.vstack(jacobians) * scale
    if ridge and len(index):
        J = np.vstack([J, np.sqrt(ridge) * np.eye(len(index), width)])
    return r, np.nan_to_num(J, nan=0.0, posinf=0.0, neginf=0.0)


def solve(fit, support, coef, x0s, rows, ridge, *, max_evaluations: int = 200,
          tolerance: float = 1e-9):
    """scipy's ``least_squares`` (``trf``, exact Jacobian) from ``coef`` ``(n, p)`` and
    ``x0s``; returns ``(coef, x0s, cost)`` with ``cost`` the sum of squared residuals."""
    index = np.flatnonzero(support.ravel())
    lower = np.concatenate([np.full(len(index), -np.inf), np.tile(fit.bounds[0], len(x0s))])
    upper = np.concatenate([np.full(len(index), np.inf), np.tile(fit.bounds[1], len(x0s))])
    theta0 = np.clip(np.concatenate([coef.ravel()[index] / fit.coef_scale[index],
                                     np.ravel(x0s)]), lower, upper)
    with np.errstate(all="ignore"):
        result = scipy.optimize.least_squares(
            lambda th: residuals(fit, th, index, rows, ridge, jacobian=False), theta0,
            jac=lambda th: residuals(fit, th, index, rows, ridge)[1], method="trf",
            bounds=(lower, upper), x_scale="jac", max_nfev=max_evaluations, xtol=tolerance,
            ftol=tolerance, gtol=tolerance)
    coef = fit.coefficients(result.x[:len(index)], index)
    return coef, result.x[len(index):].reshape(-1, fit.n), float(2 * result.cost)
