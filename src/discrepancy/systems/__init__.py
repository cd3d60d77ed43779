"""Example systems with true dynamics, flawed priors and energies.

Loaded lazily: the pendulum dynamics are derived with sympy on first use.
"""
from importlib import import_module

from .base import System

_LAZY = {
    "VanDerPol": "van_der_pol",
    "DoublePendulum": "double_pendulum",
    "DoublePendulumParameters": "double_pendulum",
    "DoublePendulumOnCart": "double_pendulum_on_cart",
    "CartPendulumParameters": "double_pendulum_on_cart",
    "LagrangianSystem": "lagrangian",
    "PendulumOnCart": "pendulum_on_cart",
    "PendulumOnCartParameters": "pendulum_on_cart",
}

__all__ = ["System", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        return getattr(import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
