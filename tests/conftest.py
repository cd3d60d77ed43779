"""Shared fixtures: reference systems simulated independently of the package.

Truth here never comes from ``discrepancy`` itself: trajectories are integrated with
scipy's ``solve_ivp`` (DOP853, tolerances 1e-12) from hand-written right-hand sides,
and derivatives are the analytic right-hand sides evaluated on the states.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from scipy.integrate import solve_ivp

# derandomize: CI sees the same examples every run, so a red build is reproducible
settings.register_profile("discrepancy", deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("discrepancy")

TIGHT = dict(method="DOP853", rtol=1e-12, atol=1e-12)


def integrate(rhs, x0, t, u=None):
    """States ``(k, n)`` of ``dx/dt = rhs(x, u(t))`` at ``t``, by scipy (reference solution)."""
    def f(tau, x):
        return rhs(x, None if u is None else u(tau))
    sol = solve_ivp(f, (t[0], t[-1]), np.asarray(x0, float), t_eval=t, **TIGHT)
    assert sol.success, sol.message
    return sol.y.T


def vdp_rhs(alpha: float, *, linear: bool = True):
    """Van der Pol ``x1' = x2, x2' = alpha (1 - x1^2) x2 - x1`` (without ``-x1`` if not linear),
    vectorised over rows: ``f(x (m, 2)) -> (m, 2)``; also accepts a single state ``(2,)``."""
    def f(x, u=None):
        x = np.asarray(x, float)
        x1, x2 = x[..., 0], x[..., 1]
        return np.stack([x2, alpha * (1 - x1**2) * x2 - (x1 if linear else 0 * x1)], axis=-1)
    return f


def lorenz_rhs(x, u=None, sigma=10.0, rho=28.0, beta=8.0 / 3.0):
    x = np.asarray(x, float)
    a, b, c = x[..., 0], x[..., 1], x[..., 2]
    return np.stack([sigma * (b - a), a * (rho - c) - b, a * b - beta * c], axis=-1)


@dataclass(frozen=True)
class Data:
    t: np.ndarray
    x: np.ndarray
    x_dot: np.ndarray

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])


@pytest.fixture(scope="session")
def vdp_data() -> Data:
    """The paper's Van der Pol data: alpha 0.5, x0 (0.5, 0), 25 time units, dt 0.01 (noise-free)."""
    t = np.arange(2501) * 0.01
    f = vdp_rhs(0.5)
    x = integrate(f, [0.5, 0.0], t)
    return Data(t, x, f(x))


@pytest.fixture(scope="session")
def vdp_validation() -> Data:
    """Validation trajectory of the true Van der Pol system from x0 (-0.2, -0.3)."""
    t = np.arange(2501) * 0.01
    f = vdp_rhs(0.5)
    x = integrate(f, [-0.2, -0.3], t)
    return Data(t, x, f(x))


@pytest.fixture(scope="session")
def lorenz_data() -> Data:
    """Lorenz (10, 28, 8/3) from (-8, 8, 27), 10 time units sampled every 0.002."""
    t = np.arange(5001) * 0.002
    x = integrate(lorenz_rhs, [-8.0, 8.0, 27.0], t)
    return Data(t, x, lorenz_rhs(x))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240611)


@pytest.fixture(scope="session")
def helpers():
    """Plain functions for tests (integrate, vdp_rhs, lorenz_rhs)."""
    return SimpleNamespace(integrate=integrate, vdp_rhs=vdp_rhs, lorenz_rhs=lorenz_rhs)


@pytest.fixture
def run_quick_start(tmp_path, monkeypatch, vdp_data):
    """``run(markdown_text) -> namespace``: the text's "## Quick start" Python block run in
    ``tmp_path``, where ``run.csv`` holds the paper's Van der Pol data with noise 0.01."""
    import re
    import runpy

    def run(text: str) -> dict:
        code = re.search(r"## Quick start\n\n```python\n(.*?)```", text, re.S).group(1)
        x = vdp_data.x + 0.01 * np.random.default_rng(0).standard_normal(vdp_data.x.shape)
        np.savetxt(tmp_path / "run.csv", np.c_[vdp_data.t, x], delimiter=",",
                   header="t,x1,x2", comments="")
        (tmp_path / "quick_start.py").write_text(code)
        monkeypatch.chdir(tmp_path)
        return runpy.run_path(str(tmp_path / "quick_start.py"))
    return run
