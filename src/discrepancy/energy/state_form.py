"""The paper's form of the energy discrepancy: ``dH = E0 - H_m`` regressed on state terms."""
from __future__ import annotations

import copy

import numpy as np

from ..constraints import InstanceOf
from ..libraries import FeatureLibrary
from ..optimizers import Optimizer
from .base import DIFFERENTIATION, ENERGY, NAMES, EnergyModel
from .hamiltonian import check_span


class EnergyDiscrepancy(EnergyModel):
    """The paper's eq. (40): ``dH = E0 - H_m(x) ≈ Θ(x) ξ`` with a library of the states.

    ``dH(t)`` is a path integral of dissipated power, not a function of the state, so this
    form learns friction only by accident: a library that spans ``H_m``'s own terms fits it
    exactly as ``E0 - H_m`` (warned: :class:`~discrepancy.energy.EnergyTautologyWarning`).
    :class:`~discrepancy.energy.DissipationDiscrepancy` is the form that learns friction laws.

    Args:
        energy, differentiation_method, position_names: see
            :class:`~discrepancy.energy.base.EnergyModel`.
        feature_library: the state library Θ (copied at fit).
        optimizer: the sparse regression (copied at fit).
    """

    _parameter_constraints = {
        "energy": ENERGY, "feature_library": [InstanceOf(FeatureLibrary, "a feature library")],
        "optimizer": [InstanceOf(Optimizer, "an Optimizer")],
        "differentiation_method": DIFFERENTIATION, "position_names": NAMES}

    def __init__(self, energy=None, *, feature_library=None, optimizer=None,
                 differentiation_method=None, position_names=None):
        self.energy = energy
        self.feature_library = feature_library
        self.optimizer = optimizer
        self.differentiation_method = differentiation_method
        self.position_names = position_names

    def fit(self, q, t, *, dq=None) -> EnergyDiscrepancy:
        """Fit on one trajectory of positions ``q`` ``(m, k)`` at times ``t`` (s or a step)."""
        self._validate_params()
        x, t = self.states(q, t, dq=dq)
        self.e0_ = float(self._energy(x[:1])[0])
        self.feature_library_ = copy.deepcopy(self.feature_library).fit(
            self.variable_names(x.shape[1] // 2))
        theta = self.feature_library_.transform(x)
        self.span_residual_ = check_span(theta, self._energy(x))
        self.optimizer_ = copy.deepcopy(self.optimizer).fit(theta, self.measured_delta_h(x))
        self.coef_ = np.asarray(self.optimizer_.coef_).reshape(-1)
        return self

    def _predict(self, x, t, start: float) -> np.ndarray:
        """``Θ(x) ξ`` (``start`` is not used: the state form has no integration constant)."""
        return self.feature_library_.transform(x) @ self.coef_

    def identified_terms(self) -> list[dict]:
        """Active terms and their coefficients."""
        self.check_is_fitted()
        names = self.feature_library_.get_feature_names()
        return [{"term": n, "coefficient": float(c)}
                for n, c in zip(names, self.coef_, strict=True) if c != 0]

    def equation(self) -> str:
        """The learned ``dH`` as text."""
        body = " + ".join(f"{t['coefficient']:.4g} {t['term']}" for t in self.identified_terms())
        return f"dH = {body or '0'}"
