"""The one-step prediction-error regression of smoothed logs (see
:mod:`~discrepancy.control.reidentification`).

From smoothed states ``x̂_k`` of logs sampled every ``dt`` with the input held, the
discrepancy ``g = Ξ θ(x, u)`` is fitted so that the hybrid model's RK4 step over each
interval lands on the next smoothed state. The fit iterates ``target_k = (x̂_{k+1} -
Φ_Ξ(x̂_k, u_k)) / dt + Ξ θ̄_k`` on ``θ̄_k`` (θ averaged over the interval's two ends) to a
fixed point, each iteration one sparse regression of the model's own optimizer on Gram
statistics (or, for a support already chosen, least squares on it).
"""
from __future__ import annotations

import copy
import warnings

import numpy as np

from ..errors import ConvergenceWarning
from ..hybrid.casadi_form import casadi_module, library_columns, prior_expression
from ..optimizers.base import refit_on_support
from ..runge_kutta import runge_kutta_step

FOLDS = 5


class OneStepFit:
    """The fixed-point fit for a model's set-up.

    Args:
        setup: the model's frozen :class:`~discrepancy.fitting.setup.FitSetup`.
        template: the unfitted model whose ``fit_statistics`` chooses the terms.
        substeps: RK4 steps per interval; max_sweeps: most fixed-point iterations.
    """

    def __init__(self, setup, template, substeps: int, max_sweeps: int):
        self.setup, self.template, self.max_sweeps = setup, template, max_sweeps
        self._flow, self._theta = _flow_functions(setup, substeps)

    def fit(self, logs, coef=None, chosen=None):
        """``(fitted model, iterations)`` from ``logs`` ``[(x̂ (m, n), u (m, r), dt)]``,
        starting from ``coef`` ``(n, p)`` (default 0): terms chosen by the optimizer, or,
        given the model ``chosen`` of an earlier pass, its terms refitted."""
        from ..optimizers import GramStatistics

        setup = self.setup
        n, p = setup.n_states, setup.n_features
        coef = np.zeros((n, p)) if coef is None else coef
        rows = sum(len(x) - 1 for x, _, _ in logs)
        fitted, sweeps = None, 0
        for _ in range(self.max_sweeps):
            sweeps += 1
            stats = GramStatistics(p, n, FOLDS, max(4, rows // (2 * FOLDS)))
            first = 0
            for x, u, dt in logs:
                theta, target, signal = self.rows(x, u, dt, coef)
                stats.add(theta, target, signal, first_row=first)
                first += len(theta)
            if chosen is None:
                fitted = copy.deepcopy(self.template).fit_statistics(stats, setup)
            else:
                fitted = chosen.with_coefficients(refit_on_support(
                    stats.gram, stats.rhs, chosen.coefficients() != 0, minimum_norm=True))
            new = fitted.coefficients()
            change = np.max(np.abs(new - coef)) / max(np.max(np.abs(new)), 1e-12)
            coef = new
            if change < 1e-9:
                break
        else:
            warnings.warn(f"the one-step fit did not reach a fixed point in {self.max_sweeps} "
                          f"iterations (last relative change {change:.2g})", ConvergenceWarning,
                          stacklevel=3)
        return fitted, sweeps

    def rows(self, x, u, dt, coef):
        """``θ̄ (m-1, p)``, targets and ``(x̂_{k+1} - x̂_k) / dt`` of one log."""
        m = len(x)
        xi = np.tile(coef.T.reshape(-1, 1), (1, m - 1))
        stepped = self._flow.map(m - 1)(x[:-1].T, u[:-1].T, xi, np.full((1, m - 1), dt))
        theta_map = self._theta.map(m - 1)
        theta = 0.5 * (theta_map(x[:-1].T, u[:-1].T) + theta_map(x[1:].T, u[:-1].T)).full().T
        target = (x[1:] - stepped.full().T) / dt + theta @ coef.T
        return theta, target, (x[1:] - x[:-1]) / dt


def _flow_functions(setup, substeps: int):
    """CasADi ``flow(x, u, vec(Ξ), dt)`` (the hybrid model's held-input RK4 step with
    coefficients ``Ξ``) and ``theta(x, u)`` (the library's columns), for one sample each."""
    ca = casadi_module()
    n, r, p = setup.n_states, setup.n_inputs, setup.n_features
    x, u = ca.SX.sym("x", n), ca.SX.sym("u", r)
    xi, dt = ca.SX.sym("xi", n * p), ca.SX.sym("dt")
    theta = library_columns(setup.library.feature_expressions_, setup.variable_names, x, u)
    rhs = prior_expression(setup.prior, x, u) + ca.mtimes(ca.reshape(xi, n, p), theta)
    f = ca.Function("f", [x, u, xi], [rhs])
    h, z = dt / substeps, x
    for _ in range(substeps):
        z = runge_kutta_step(lambda state, held: f(state, held, xi), z, h, u, u, u)
    return ca.Function("flow", [x, u, xi, dt], [z]), ca.Function("theta", [x, u], [theta])
