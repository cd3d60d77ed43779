"""EnergyDiscrepancy: learn the energy a mechanical system loses, from measured positions."""
from __future__ import annotations

import numpy as np

from ..data.trajectory import as_2d, as_times
from ..differentiation import SavitzkyGolay, get_differentiation_method
from ..errors import NotFittedError, ParameterError, ShapeError, UnknownNameError
from ..symbolic import feature_name
from .dissipation import default_friction_library, fit_dissipation, integrated_powers
from .hamiltonian import check_span
from .metrics import error_summary
from .uncertainty import DissipationUncertainty, bootstrap_dissipation, quantile_band

FORMS = ("dissipation", "state")


class EnergyDiscrepancy:
    """Model of ``dH = E0 - H_m(x(t))``, the energy the conservative model ``H_m`` misses.

    Args:
        energy: ``H_m(x)`` for ``x = [q, dq]`` ``(m, 2k)`` -> ``(m,)`` (J), e.g.
            ``DoublePendulum().energy``.
        form: ``"dissipation"`` (recommended): ``dH(t) = c + sum xi_j int_0^t theta_j(dq) dt``
            with ``xi >= 0`` over ``friction_terms``; ``"state"`` (the paper's):
            ``dH = Theta(x) xi`` with ``feature_library`` and ``optimizer`` (e.g. STLSQ).
        feature_library, optimizer: for ``form="state"``.
        friction_terms: :class:`~discrepancy.energy.dissipation.FrictionTerm` candidates
            (default :func:`default_friction_library`).
        max_terms, holdout, tolerance: term selection of the dissipation form
            (:func:`~discrepancy.energy.dissipation.select_terms`).
        block_seconds: ``None`` (default): least squares on the cumulative curve; a length
            (s): fit the energy lost per block of that length with relative weights, so the
            low-energy end of a decaying swing counts as much as its start.
        differentiation_method: turns measured positions into ``(q_smooth, dq)``
            (default Savitzky-Golay, window 31, cubic).
        position_names, velocity_names: names of ``q`` and ``dq`` (library variables).
    """

    def __init__(self, energy=None, *, form: str = "dissipation", feature_library=None,
                 optimizer=None, friction_terms=None, max_terms: int = 4, holdout: float = 0.0,
                 tolerance: float = 0.02, block_seconds: float | None = None,
                 differentiation_method=None,
                 position_names=("phi1", "phi2"), velocity_names=("dphi1", "dphi2")):
        self.energy = energy
        self.form = form
        self.feature_library = feature_library
        self.optimizer = optimizer
        self.friction_terms = friction_terms
        self.max_terms = max_terms
        self.holdout = holdout
        self.tolerance = tolerance
        self.block_seconds = block_seconds
        self.differentiation_method = differentiation_method
        self.position_names = position_names
        self.velocity_names = velocity_names

    # -- data -------------------------------------------------------------------------------
    def states(self, q, t, *, dq=None) -> tuple[np.ndarray, np.ndarray]:
        """``(x, t)``: ``x = [q_smooth, dq]`` ``(m', 2k)`` from positions ``q`` ``(m, k)`` (rad).

        When ``dq`` is not given it is estimated with ``differentiation_method`` and the
        samples within the method's half window (``halo``) of either end are dropped: there
        the derivative is a one-sided extrapolation, and its error in ``H_m`` would set ``E0``.
        """
        k = len(self.position_names)
        q = as_2d("q", q, n_cols=k, allow_1d=k == 1)
        t = as_times("t", t, q.shape[0])
        if dq is not None:
            return np.hstack([q, as_2d("dq", dq, n_rows=q.shape[0], n_cols=k)]), t
        method = self.differentiation_method
        method = SavitzkyGolay(window_length=31, polyorder=3) if method is None \
            else get_differentiation_method(method)
        q_smooth, dq = method(q, t)
        h = method.edge
        keep = slice(h, q.shape[0] - h)
        return np.hstack([q_smooth, dq])[keep], t[keep]

    def _energy(self, x) -> np.ndarray:
        if not callable(self.energy):
            raise ParameterError(f"energy must be a callable H_m(x) -> (m,); got {self.energy!r}")
        h = np.asarray(self.energy(x), dtype=float).reshape(-1)
        if h.shape != (x.shape[0],):
            raise ShapeError(f"energy(x) must return ({x.shape[0]},); got {h.shape}")
        return h

    def measured_delta_h(self, x, *, e0: float | None = None) -> np.ndarray:
        """``E0 - H_m(x)`` (J), ``(m,)``, with ``E0 = H_m(x[0])`` unless given."""
        h = self._energy(np.asarray(x, float))
        return (h[0] if e0 is None else e0) - h

    # -- fit / predict ----------------------------------------------------------------------
    def _terms(self):
        if self.friction_terms is not None:
            return tuple(self.friction_terms)
        return default_friction_library(self.velocity_names)

    def _state_names(self) -> list[str]:
        return [*self.position_names, *self.velocity_names]

    def _theta(self, x) -> np.ndarray:
        return self.feature_library_.transform(x)

    def fit(self, q, t, *, dq=None) -> EnergyDiscrepancy:
        """Fit on one trajectory of positions ``q`` ``(m, k)`` at times ``t`` (s or a step)."""
        if self.form not in FORMS:
            raise UnknownNameError(f"form {self.form!r} is not known; valid forms: {FORMS}")
        x, t = self.states(q, t, dq=dq)
        delta_h = self.measured_delta_h(x)
        self.e0_ = float(self._energy(x[:1])[0])
        if self.form == "state":
            if self.feature_library is None or self.optimizer is None:
                raise ParameterError("form='state' needs feature_library and optimizer")
            self.feature_library_ = self.feature_library.fit(
                self._state_names())
            theta = self._theta(x)
            self.span_residual_ = check_span(theta, self._energy(x))
            self.coef_ = np.asarray(self.optimizer.fit(theta, delta_h[:, None]).coef_).reshape(-1)
        else:
            terms = self._terms()
            features = integrated_powers(terms, x, t, self._state_names())
            block = None if self.block_seconds is None else \
                max(2, int(round(self.block_seconds / np.median(np.diff(t)))))
            self.fit_ = fit_dissipation(features, delta_h, terms, max_terms=self.max_terms,
                                        holdout=self.holdout, tolerance=self.tolerance,
                                        block=block)
            self.terms_ = self.fit_.terms
            self.coef_ = self.fit_.coefficients
            self.offset_ = self.fit_.offset
        return self

    def bootstrap(self, q, t, *, dq=None, n_resamples: int = 200, block_seconds: float = 1.0,
                  seed: int = 0):
        """Uncertainty of every learned friction coefficient (dissipation form): a wild block
        bootstrap of the fit on these (training) data, blocks of ``block_seconds`` (s); see
        :mod:`discrepancy.energy.uncertainty`.

        Returns a :class:`~discrepancy.energy.uncertainty.DissipationUncertainty` (one row,
        ``"dH"``; one column per term, in the terms' units) with ``std``, ``interval()`` and
        ``table()``, and the resampled offsets, for :meth:`predict_interval`.
        """
        self._check_fitted()
        if self.form != "dissipation":
            raise ParameterError("bootstrap is for the dissipation form; the state form is a "
                                 "DiscrepancyModel-like regression (use its optimizer's tools)")
        if not self.terms_:
            raise ParameterError("the fit chose no friction term: nothing to bootstrap")
        x, t = self.states(q, t, dq=dq)
        dt = float(np.median(np.diff(t)))
        if not np.isfinite(block_seconds) or block_seconds <= 0:
            raise ParameterError(f"block_seconds must be > 0 s; got {block_seconds!r}")
        features = integrated_powers(self.terms_, x, t, self._state_names())
        fit_block = None if self.block_seconds is None else \
            max(2, int(round(self.block_seconds / dt)))
        return bootstrap_dissipation(
            features, self.measured_delta_h(x), self.coef_, self.offset_,
            [term.name for term in self.terms_], fit_block=fit_block, n_resamples=n_resamples,
            samples_per_block=max(2, int(round(block_seconds / dt))), seed=seed)

    def _check_fitted(self):
        if not hasattr(self, "coef_"):
            raise NotFittedError("EnergyDiscrepancy is not fitted; call fit(q, t) first")

    def predict(self, q, t, *, dq=None, start: float = 0.0) -> np.ndarray:
        """Model ``dH`` (J) along a trajectory, ``(m,)``.

        Dissipation form: ``start + sum xi_j int_{t0}^t theta_j dt``; ``start = 0`` on a new
        trajectory (``dH(t0) = 0`` by definition), ``offset_`` to reproduce the training fit,
        or the model's value where a continued recording resumes. State form: ``Theta(x) xi``.
        """
        self._check_fitted()
        x, t = self.states(q, t, dq=dq)
        return self.predict_states(x, t, start=start)

    def predict_states(self, x, t, *, start: float = 0.0) -> np.ndarray:
        """:meth:`predict` from states ``x = [q, dq]`` ``(m, 2k)`` already differentiated."""
        self._check_fitted()
        if self.form == "state":
            return self._theta(x) @ self.coef_
        return start + integrated_powers(self.terms_, x, t, self._state_names()) @ self.coef_

    def predict_interval(self, q, t, uncertainty, *, dq=None, level: float = 0.95,
                         continued: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Pointwise ``level`` band ``(low, high)`` of the model ``dH`` (J), each ``(m,)``.

        ``uncertainty`` is this model's :meth:`bootstrap`. ``continued=False``: a new
        trajectory (``dH(t0) = 0``, as ``predict(start=0)``); ``continued=True``: the training
        recording continued past its end (each resample with its own offset, as
        ``predict(start=offset_)``), so ``t`` must start where the training data started.
        The band holds the noise-driven uncertainty of the chosen law's coefficients, not
        that of the choice of terms.
        """
        x, t = self.states(q, t, dq=dq)
        return self.predict_interval_states(x, t, uncertainty, level=level, continued=continued)

    def predict_interval_states(self, x, t, uncertainty, *, level: float = 0.95,
                                continued: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`predict_interval` from states ``x = [q, dq]`` ``(m, 2k)``."""
        return quantile_band(
            self.resampled_predictions_states(x, t, uncertainty, continued=continued), level)

    def resampled_predictions_states(self, x, t, uncertainty, *,
                                     continued: bool = False) -> np.ndarray:
        """Every bootstrap resample's model ``dH`` (J) along states ``x`` ``(m, 2k)``:
        ``(R, m)``; see :meth:`predict_interval`."""
        self._check_fitted()
        names = [term.name for term in getattr(self, "terms_", ())]
        if not isinstance(uncertainty, DissipationUncertainty) or \
                list(uncertainty.feature_names) != names:
            raise ParameterError("uncertainty must be this model's bootstrap(...) (terms "
                                 f"{names}); got {type(uncertainty).__name__} with terms "
                                 f"{list(getattr(uncertainty, 'feature_names', []))}")
        features = integrated_powers(self.terms_, np.asarray(x, float), t, self._state_names())
        return uncertainty.curves(features, continued=continued)

    def score(self, q, t, *, dq=None, start: float = 0.0) -> dict[str, float]:
        """Percentage errors (paper's ``max|dH|`` and the window's ``dH`` range) on a trajectory."""
        x, t = self.states(q, t, dq=dq)
        return error_summary(self.measured_delta_h(x), self.predict_states(x, t, start=start))

    # -- reporting --------------------------------------------------------------------------
    def identified_terms(self) -> list[dict]:
        """Active terms: name, expression, coefficient and unit (dissipation form)."""
        self._check_fitted()
        if self.form == "state":
            names = self.feature_library_.get_feature_names()
            return [{"term": n, "coefficient": float(c)} for n, c in zip(names, self.coef_,
                                                                         strict=True) if c != 0]
        return [{"name": term.name, "power": feature_name(term.power), "torque": term.torque,
                 "coefficient": float(c), "unit": term.unit}
                for term, c in zip(self.terms_, self.coef_, strict=True)]

    def equation(self) -> str:
        """The learned law as text, e.g. ``P_loss = 7.2e-04 [N m s] dphi1^2 + ...``."""
        terms = self.identified_terms()
        if self.form == "state":
            body = " + ".join(f"{t['coefficient']:.4g} {t['term']}" for t in terms)
            return f"dH = {body or '0'}"
        body = " + ".join(f"{t['coefficient']:.4g} [{t['unit']}] {t['power']}" for t in terms)
        return f"P_loss = {body or '0'}  (W)"
