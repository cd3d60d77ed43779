"""DissipationDiscrepancy: the energy a conservative model misses, as sparse friction laws."""
from __future__ import annotations

import numpy as np

from ..constraints import Integral, Interval, Options, Predicate, Real
from ..data.trajectory import as_2d, as_times
from ..errors import ParameterError
from ..symbolic import feature_name
from .base import DIFFERENTIATION, ENERGY, NAMES, EnergyModel
from .dissipation import (
    FrictionTerm,
    default_friction_library,
    fit_dissipation,
    integrated_powers,
    torque_bounds,
)
from .uncertainty import DissipationUncertainty, bootstrap_dissipation, quantile_band

TERMS = [None, Predicate(lambda v: isinstance(v, (list, tuple)) and len(v) > 0 and all(
    isinstance(term, FrictionTerm) for term in v), "a non-empty list of FrictionTerm")]


#: fewest blocks a block fit compares (the energy lost between consecutive blocks)
MIN_BLOCKS = 3


class DissipationDiscrepancy(EnergyModel):
    """``dH(t) = c + Σ_j ξ_j ∫_0^t θ_j dt`` with ``ξ >= 0``: friction laws from a swing.

    Each ``θ_j`` is the power (per unit coefficient) of a friction law, a non-negative
    function of the state, so the learned model always dissipates and its coefficients are
    the laws' constants; ``c`` absorbs the error of the reference energy ``E0``.

    Args:
        energy, differentiation_method, position_names: see
            :class:`~discrepancy.energy.base.EnergyModel`.
        friction_terms: candidate :class:`~discrepancy.energy.FrictionTerm` (default
            :func:`~discrepancy.energy.default_friction_library` for every coordinate, each
            coordinate its own joint; pass ``default_friction_library(..., joints=...)`` for
            relative joints such as a double pendulum's elbow).
        max_terms: most terms in the law (clipped to the number of candidates).
        holdout, tolerance: term selection (:func:`~discrepancy.energy.select_terms`).
        block_seconds: ``None``: least squares on the cumulative curve; a length (s): the
            energy lost per block of that length, with relative weights.
        torque_limit: the largest torque (N m, or N for a linear coordinate) any friction
            law may exert in the data, a constraint of the fit: ``"auto"`` (default) the
            largest conservative torque ``|∂H_m(q, 0)/∂q|`` along the recording (a larger
            static friction would hold the system at its turning points), a number, or
            ``None`` for no bound. Mount losses and other terms without a joint speed are
            not bounded.
        fit_window: fit on the last ``fit_window`` seconds of the data only (``None``: all
            of it): the regime a forecast continues, when a decay passes through regimes
            that one law of a small library does not describe equally well. ``fit_start_``
            records where the fitted data begin; :meth:`anchored` compares there.
    """

    _parameter_constraints = {
        "energy": ENERGY, "friction_terms": TERMS,
        "max_terms": [Interval(Integral, 1, None)],
        "holdout": [Interval(Real, 0, 0.9, closed="left")],
        "tolerance": [Interval(Real, 0, 1)],
        "block_seconds": [None, Interval(Real, 0, None, closed="neither")],
        "torque_limit": [None, Options({"auto"}), Interval(Real, 0, None, closed="neither")],
        "fit_window": [None, Interval(Real, 0, None, closed="neither")],
        "differentiation_method": DIFFERENTIATION, "position_names": NAMES}

    def __init__(self, energy=None, *, friction_terms=None, max_terms: int = 4,
                 holdout: float = 0.0, tolerance: float = 0.02, block_seconds: float | None = None,
                 torque_limit="auto", fit_window: float | None = None,
                 differentiation_method=None, position_names=None):
        self.energy = energy
        self.friction_terms = friction_terms
        self.max_terms = max_terms
        self.holdout = holdout
        self.tolerance = tolerance
        self.block_seconds = block_seconds
        self.torque_limit = torque_limit
        self.fit_window = fit_window
        self.differentiation_method = differentiation_method
        self.position_names = position_names

    @classmethod
    def from_system(cls, system, **kwargs) -> DissipationDiscrepancy:
        """A model of ``system`` (e.g. a :class:`~discrepancy.systems.LagrangianSystem` or
        :class:`~discrepancy.systems.DoublePendulum`): its energy, its coordinates' names and
        the default friction laws of its joints (``system.joints()``, relative joints
        included); other keyword arguments as for the constructor."""
        for needed in ("energy", "position_names", "joints"):
            if not hasattr(system, needed):
                raise ParameterError(f"system must have energy, position_names and joints() "
                                     f"(a mechanical system); {type(system).__name__} has no "
                                     f"{needed}")
        names = list(system.position_names)
        kwargs.setdefault("friction_terms", list(default_friction_library(
            [f"d{n}" for n in names], joints=system.joints())))
        return cls(system.energy, position_names=names, **kwargs)

    def _terms(self, k: int) -> tuple[FrictionTerm, ...]:
        if self.friction_terms is not None:
            return tuple(self.friction_terms)
        return default_friction_library(self.variable_names(k)[k:])

    def _block(self, t) -> int | None:
        if self.block_seconds is None:
            return None
        block = max(2, int(round(self.block_seconds / np.median(np.diff(t)))))
        if len(t) // block < MIN_BLOCKS:
            raise ParameterError(f"block_seconds = {self.block_seconds} s leaves "
                                 f"{len(t) // block} blocks of a {t[-1] - t[0]:.4g} s record; "
                                 f"the fit needs at least {MIN_BLOCKS} (use shorter blocks)")
        return block

    def _window(self, q, t, dq):
        """The last ``fit_window`` seconds of ``(q, t, dq)`` (all of them for ``None``)."""
        q = as_2d("q", q, allow_1d=True)
        t = as_times("t", t, len(q))
        if self.fit_window is None:
            return q, t, dq
        keep = t >= t[-1] - self.fit_window
        return q[keep], t[keep], None if dq is None else as_2d(
            "dq", dq, n_rows=len(keep), n_cols=q.shape[1], allow_1d=True)[keep]

    def fit(self, q, t, *, dq=None) -> DissipationDiscrepancy:
        """Fit on one trajectory of positions ``q`` ``(m, k)`` at times ``t`` (s or a step)."""
        self._validate_params()
        q, t, dq = self._window(q, t, dq)
        x, t = self.states(q, t, dq=dq)
        self.fit_start_ = float(t[0])
        k = x.shape[1] // 2
        self.variable_names_ = self.variable_names(k)
        terms = self._terms(k)
        delta_h = self.measured_delta_h(x)
        self.e0_ = float(self._energy(x[:1])[0])
        features = integrated_powers(terms, x, t, self.variable_names_)
        self.torque_limit_ = self._torque_limit(x)
        upper = torque_bounds(terms, x, self.variable_names_, self.torque_limit_)
        self.fit_ = fit_dissipation(features, delta_h, terms, block=self._block(t),
                                    max_terms=min(self.max_terms, len(terms)),
                                    holdout=self.holdout, tolerance=self.tolerance, upper=upper)
        self.terms_, self.coef_, self.offset_ = self.fit_.terms, self.fit_.coefficients, \
            self.fit_.offset
        return self

    def anchored(self, x, t) -> tuple[np.ndarray, np.ndarray]:
        """``(dH, model)`` (J), each ``(m,)``, over states ``x`` ``(m, 2k)`` at times ``t`` of
        the training recording (continued past its end, or begun before a ``fit_window``),
        both anchored where the fitted data begin (``fit_start_``): ``dH = H_m(x(fit_start_))
        - H_m(x)`` and ``model = offset_ + Σ ξ_j ∫_{fit_start_}^t θ_j dt``. Samples before
        ``fit_start_`` are the law run backwards."""
        self.check_is_fitted()
        t = np.asarray(t, float)
        k = int(np.argmin(np.abs(t - self.fit_start_)))
        dh = self.measured_delta_h(x, e0=float(self._energy(x[k:k + 1])[0]))
        model = self._predict(x, t, 0.0)
        return dh, model - model[k] + self.offset_

    def _torque_limit(self, x) -> float:
        """The bound of every friction torque (N m): see ``torque_limit``; ``inf`` for none
        (also when the model energy has no potential to compare with)."""
        if self.torque_limit is None:
            return np.inf
        if self.torque_limit != "auto":
            return float(self.torque_limit)
        torques = conservative_torques(self._energy, x)
        largest = float(np.max(np.abs(torques)))
        return largest if largest > 0 else np.inf

    def _predict(self, x, t, start: float) -> np.ndarray:
        """``start + Σ ξ_j ∫ θ_j dt``: ``start = 0`` on a new trajectory (``dH(t0) = 0``),
        ``offset_`` to reproduce the training fit, or the model's value where a continued
        recording resumes."""
        return start + integrated_powers(self.terms_, x, t, self.variable_names_) @ self.coef_

    def bootstrap(self, q, t, *, dq=None, n_resamples: int = 200, block_seconds: float = 1.0,
                  seed: int = 0) -> DissipationUncertainty:
        """Uncertainty of every learned coefficient: a wild block bootstrap of the fit on
        these (training) data, blocks of ``block_seconds`` (s); see
        :mod:`discrepancy.energy.uncertainty`."""
        self.check_is_fitted()
        if not self.terms_:
            raise ParameterError("the fit chose no friction term: nothing to bootstrap")
        if not isinstance(block_seconds, (int, float)) or not np.isfinite(block_seconds) or \
                block_seconds <= 0:
            raise ParameterError(f"block_seconds must be > 0 s; got {block_seconds!r}")
        q, t, dq = self._window(q, t, dq)
        x, t = self.states(q, t, dq=dq)
        dt = float(np.median(np.diff(t)))
        features = integrated_powers(self.terms_, x, t, self.variable_names_)
        return bootstrap_dissipation(
            features, self.measured_delta_h(x), self.coef_, self.offset_,
            [term.name for term in self.terms_], fit_block=self._block(t), upper=self.fit_.upper,
            n_resamples=n_resamples, samples_per_block=max(2, int(round(block_seconds / dt))),
            seed=seed)

    def predict_interval(self, q, t, uncertainty, *, dq=None, level: float = 0.95,
                         continued: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Pointwise ``level`` band ``(low, high)`` of the model ``dH`` (J), each ``(m',)``.

        ``uncertainty``: this model's :meth:`bootstrap`. ``continued=False``: a new
        trajectory (as ``predict(start=0)``); ``True``: the training recording continued
        past its end (each resample with its own offset), so ``t`` starts where training
        did. The band holds the coefficients' noise, not the error of the law's form."""
        return quantile_band(self.resampled_predictions(q, t, uncertainty, dq=dq,
                                                        continued=continued), level)

    def resampled_predictions(self, q, t, uncertainty, *, dq=None,
                              continued: bool = False) -> np.ndarray:
        """Every bootstrap resample's model ``dH`` (J) along the trajectory, ``(R, m')``."""
        self.check_is_fitted()
        names = [term.name for term in self.terms_]
        if not isinstance(uncertainty, DissipationUncertainty) or \
                list(uncertainty.feature_names) != names:
            raise ParameterError("uncertainty must be this model's bootstrap(...) (terms "
                                 f"{names}); got {type(uncertainty).__name__}")
        x, t = self.states(q, t, dq=dq)
        features = integrated_powers(self.terms_, x, t, self.variable_names_)
        return uncertainty.curves(features, continued=continued)

    def identified_terms(self) -> list[dict]:
        """Active terms: name, power, torque law, coefficient and unit."""
        self.check_is_fitted()
        return [{"name": term.name, "power": feature_name(term.power), "torque": term.torque,
                 "coefficient": float(c), "unit": term.unit}
                for term, c in zip(self.terms_, self.coef_, strict=True)]

    def equation(self) -> str:
        """The learned law as text, e.g. ``P_loss = 7.2e-04 [N m s] dq1^2 + ...``."""
        body = " + ".join(f"{t['coefficient']:.4g} [{t['unit']}] {t['power']}"
                          for t in self.identified_terms())
        return f"P_loss = {body or '0'}  (W)"


def conservative_torques(energy, x, *, max_rows: int = 5000) -> np.ndarray:
    """``-∂H(q, 0)/∂q`` ``(m', k)`` at (up to ``max_rows`` evenly spaced) states ``x = [q, dq]``
    ``(m, 2k)``: the conservative torques, by central differences of the energy at rest (for a
    mechanical energy ``T + V`` with ``T = 0`` at rest this is ``-∂V/∂q``)."""
    k = x.shape[1] // 2
    rest = x[::max(1, len(x) // max_rows)].copy()
    rest[:, k:] = 0.0
    torques = np.empty((len(rest), k))
    for i in range(k):
        h = 1e-6 * max(1.0, float(np.max(np.abs(rest[:, i]))))
        up, down = rest.copy(), rest.copy()
        up[:, i] += h
        down[:, i] -= h
        torques[:, i] = -(energy(up) - energy(down)) / (2 * h)
    return torques
