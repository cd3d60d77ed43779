"""Van der Pol oscillator (paper Section IV.A) and its two flawed priors."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..constraints import Interval, Real, validate_params
from ..data.validation import check_array
from ..errors import ParameterError
from ..symbolic import symbol
from .base import System

CASES = ("parameter", "structure")


@dataclass(frozen=True)
class VanDerPol(System):
    """``x1' = x2``, ``x2' = α (1 − x1²) x2 − x1`` (dimensionless time).

    Args:
        alpha: damping parameter α of the true system (paper: 0.5).
        alpha_model: α of the flawed prior in the parameter-mismatch case (paper: 0.1).
    """

    alpha: float = 0.5
    alpha_model: float = 0.1
    state_names = ("x1", "x2")
    input_names = ()

    def __post_init__(self):
        validate_params("VanDerPol", {"alpha": self.alpha, "alpha_model": self.alpha_model},
                        {"alpha": [Interval(Real)], "alpha_model": [Interval(Real)]})

    def rhs(self, x, u=None):
        return _vdp(check_array("x", np.atleast_2d(x), n_cols=2), self.alpha, linear=True)

    def flawed_model(self, case: str = "parameter"):
        """The paper's prior: ``"parameter"`` (α = alpha_model) or ``"structure"`` (no −x1)."""
        _check(case)
        a, linear = (self.alpha_model, True) if case == "parameter" else (self.alpha, False)
        return lambda x, u=None: _vdp(x, a, linear=linear)

    def flawed_equations(self, case: str = "parameter") -> list[sp.Expr]:
        """The flawed prior as sympy expressions in the symbols ``x1``, ``x2``."""
        _check(case)
        x1, x2 = symbol("x1"), symbol("x2")
        a = sp.nsimplify(self.alpha_model if case == "parameter" else self.alpha)
        return [x2, a * (1 - x1**2) * x2 - (x1 if case == "parameter" else 0)]

    def true_discrepancy(self, case: str = "parameter") -> dict[str, dict[str, float]]:
        """The exact discrepancy ``f − f_m`` as ``{state: {term name: coefficient}}``."""
        _check(case)
        if case == "parameter":
            d = self.alpha - self.alpha_model
            return {"x1": {}, "x2": {"x2": d, "x1^2 x2": -d}}
        return {"x1": {}, "x2": {"x1": -1.0}}


def _vdp(x, alpha, *, linear):
    x1, x2 = x[:, 0], x[:, 1]
    return np.column_stack([x2, alpha * (1 - x1**2) * x2 - (x1 if linear else 0.0)])


def _check(case):
    if case not in CASES:
        raise ParameterError(f"case must be one of {CASES}; got {case!r}")
