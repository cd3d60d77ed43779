"""DissipationDiscrepancy: the energy a conservative model misses, as sparse friction laws."""
from __future__ import annotations

import numpy as np

from ..constraints import Integral, Interval, Options, Predicate, Real
from ..data.trajectory import as_2d, as_times
from ..errors import ParameterError, ShapeError
from ..symbolic import feature_name
from .base import DIFFERENTIATION, ENERGY, NAMES, EnergyModel
from .dissipation import FrictionTerm, default_friction_library, integrated_powers
from .record import PreparedRecording
from .subsets import fit_dissipation
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
        torque_limit: the largest torque (N m, or N for a linear coordinate) the whole law
            at a joint (the sum of its terms there) may exert at any sample, a constraint of
            the fit: ``"auto"`` (default) the largest conservative torque
            ``|∂H_m(q, 0)/∂q|`` along the recording, a number, or ``None`` for no bound.
            Mount losses and other terms without a joint speed are not bounded.
        turning_points: also constrain the law's torque at every turning point the
            recording shows (a joint's speed changes sign) below the torque holding that
            joint there (:mod:`~discrepancy.energy.soundness`): a larger static friction
            would have stopped it.
        fit_window: fit on the last ``fit_window`` seconds of the data only (``None``: all
            of it): the regime a forecast continues, when a decay passes through regimes
            that one law of a small library does not describe equally well. The
            constraints still come from all the data. ``fit_start_`` records where the
            fitted data begin; :meth:`anchored` compares there.

    Fitted attributes: ``terms_``, ``coef_``, ``offset_``, ``fit_`` (with the constraints
    that hold the law at its bound, ``fit_.active``), ``torque_limit_`` (N m) and
    ``soundness_``: the law checked on all the data it was fitted from (per joint, its
    largest torque over the limit and over the holding torque at the turning points).
    """

    _parameter_constraints = {
        "energy": ENERGY, "friction_terms": TERMS,
        "max_terms": [Interval(Integral, 1, None)],
        "holdout": [Interval(Real, 0, 0.9, closed="left")],
        "tolerance": [Interval(Real, 0, 1)],
        "block_seconds": [None, Interval(Real, 0, None, closed="neither")],
        "torque_limit": [None, Options({"auto"}), Interval(Real, 0, None, closed="neither")],
        "turning_points": [bool],
        "fit_window": [None, Interval(Real, 0, None, closed="neither")],
        "differentiation_method": DIFFERENTIATION, "position_names": NAMES}

    def __init__(self, energy=None, *, friction_terms=None, max_terms: int = 4,
                 holdout: float = 0.0, tolerance: float = 0.02, block_seconds: float | None = None,
                 torque_limit="auto", turning_points: bool = True,
                 fit_window: float | None = None, differentiation_method=None,
                 position_names=None):
        self.energy = energy
        self.friction_terms = friction_terms
        self.max_terms = max_terms
        self.holdout = holdout
        self.tolerance = tolerance
        self.block_seconds = block_seconds
        self.torque_limit = torque_limit
        self.turning_points = turning_points
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

    def fit(self, q, t, *, dq=None) -> DissipationDiscrepancy:
        """Fit on one trajectory of positions ``q`` ``(m, k)`` at times ``t`` (s or a step)."""
        self._validate_params()
        x, t = self.states(q, t, dq=dq)
        return self.fit_prepared(self.prepare(x, t), len(t))

    def prepare(self, x, t) -> PreparedRecording:
        """The states ``x`` ``(m, 2k)`` at times ``t`` ready for fits of this model's library
        (:class:`~discrepancy.energy.record.PreparedRecording`)."""
        x = as_2d("x", x)
        if x.shape[1] % 2:
            raise ShapeError(f"x must hold positions then velocities, (m, 2k); got shape "
                             f"{x.shape}")
        t = as_times("t", t, len(x))
        k = x.shape[1] // 2
        return PreparedRecording(self._energy, x, t, self._terms(k), self.variable_names(k))

    def fit_prepared(self, record: PreparedRecording, stop: int, *, check: bool = True,
                     constrain_to: int | None = None) -> DissipationDiscrepancy:
        """Fit on the samples ``[0, stop)`` of a prepared recording (whose library must hold
        this model's terms), e.g. one shared by the procedures of
        :func:`~discrepancy.energy.blind_fit`; ``check=False`` skips ``soundness_`` (the
        constraints hold the law anyway; the check reports on it). ``constrain_to``: the
        torque bound, the turning points and the check come from ``[0, constrain_to)``
        (default ``stop``), e.g. the whole recording when only its moving part is fitted."""
        self._validate_params()
        if not isinstance(record, PreparedRecording):
            raise ParameterError(f"record must be a PreparedRecording (from prepare); got "
                                 f"{type(record).__name__}")
        _check_stop("stop", stop, 3, len(record.t))
        bounds_stop = stop if constrain_to is None else constrain_to
        _check_stop("constrain_to", bounds_stop, stop, len(record.t))
        k = record.x.shape[1] // 2
        terms = self._terms(k)
        columns = _columns(record.terms, terms)
        start = record.window_start(stop, self.fit_window)
        self.variable_names_ = self.variable_names(k)
        self.fit_start_ = float(record.t[start])
        self.e0_ = float(record.h0 - record.delta_h[start])
        self.torque_limit_ = record.torque_limit(bounds_stop, self.torque_limit)
        limits = record.limits(bounds_stop, self.torque_limit,
                               self.turning_points).restricted(columns)
        rows = slice(start, stop)       # integrals and dH restart where the fitted data begin
        block = self._block(record.t[rows])
        self.fit_ = fit_dissipation(
            record.features[rows][:, columns] - record.features[start, columns],
            record.delta_h[rows] - record.delta_h[start], terms, block=block,
            max_terms=min(self.max_terms, len(terms)), holdout=self.holdout,
            tolerance=self.tolerance, limits=limits,
            statistics_of=lambda n: record.statistics(start, start + n, block, columns))
        self.terms_, self.coef_, self.offset_ = self.fit_.terms, self.fit_.coefficients, \
            self.fit_.offset
        if check:
            chosen = [columns[terms.index(term)] for term in self.terms_]
            self.soundness_ = {**record.check(bounds_stop, chosen, self.coef_),
                               "active_constraints": list(self.fit_.active)}
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
        x, t = self.states(q, t, dq=dq)
        if self.fit_window is not None:
            keep = t >= t[-1] - self.fit_window
            x, t = x[keep], t[keep]
        dt = float(np.median(np.diff(t)))
        features = integrated_powers(self.terms_, x, t, self.variable_names_)
        return bootstrap_dissipation(
            features, self.measured_delta_h(x), self.coef_, self.offset_,
            [term.name for term in self.terms_], fit_block=self._block(t), limits=self.fit_.limits,
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


def _columns(library, terms) -> list[int]:
    """Indices of ``terms`` in ``library``."""
    index = {term: i for i, term in enumerate(library)}
    missing = [term.name for term in terms if term not in index]
    if missing:
        raise ParameterError(f"the prepared recording lacks the terms {missing}")
    return [index[term] for term in terms]


def _check_stop(name: str, stop, low: int, high: int) -> None:
    if isinstance(stop, (bool, np.bool_)) or not isinstance(stop, (int, np.integer)) \
            or not low <= stop <= high:
        raise ParameterError(f"{name} must be an integer in [{low}, {high}] (samples of the "
                             f"recording); got {stop!r}")
