"""The region a model's terms were fitted on, and the warning when it is left.

A learned term is only known where the data were: a cubic fitted on ``|x| < 1`` may do
anything at ``x = 3``. :class:`FittedRegion` keeps the range (lowest and highest value) of
every state and input the fit saw; :meth:`FittedRegion.warn_outside` is called by
``simulate``, ``predict`` and ``predict_ahead`` and warns once per call
(:class:`~discrepancy.errors.ExtrapolationWarning`) naming each variable that left the
range, how far and in which direction. Excursions within :data:`MARGIN` of a variable's
range are not reported (the range itself is a noisy estimate). Only the variables the
learned terms depend on are watched, less those every such term sees through 2π-periodic
functions (``sin(q)`` of an angle that turns over is known everywhere): the prior is the
user's, and a model without learned terms (the prior alone) never warns.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import sympy as sp

from ...errors import ExtrapolationWarning

#: excursions smaller than this fraction of a variable's range are not reported
MARGIN = 0.01


@dataclass(frozen=True)
class FittedRegion:
    """Range of each variable of ``z = [x, u]`` over the fitted data.

    Attributes:
        names: the variables' names; low, high: ``(len(names),)`` their extremes.
    """

    names: tuple
    low: np.ndarray
    high: np.ndarray

    def excursions(self, z: np.ndarray, only=None) -> list[tuple[str, float, float]]:
        """``(name, extreme value reached, distance outside)`` of the variables (columns of
        ``z``: the first ``z.shape[1]`` variables; of them ``only`` those named, when given)
        that leave the range by more than :data:`MARGIN` of it."""
        out = []
        width = self.high - self.low
        tol = MARGIN * np.where(width > 0, width, np.maximum(np.abs(self.high), 1.0))
        with np.errstate(invalid="ignore"):
            top, bottom = np.nanmax(z, axis=0), np.nanmin(z, axis=0)
        for j, name in enumerate(self.names[:z.shape[1]]):
            if only is not None and name not in only:
                continue
            above, below = top[j] - self.high[j], self.low[j] - bottom[j]
            if above > tol[j] and above >= below:
                out.append((name, float(top[j]), float(above)))
            elif below > tol[j]:
                out.append((name, float(bottom[j]), -float(below)))
        return out

    def warn_outside(self, z: np.ndarray, where: str, *, only=None,
                     stacklevel: int = 3) -> None:
        """One ExtrapolationWarning listing every variable of ``z`` ``(m, v)`` (of them
        ``only`` those named, when given) that left the range (nothing when none did)."""
        if z.size == 0:
            return
        found = self.excursions(z, only)
        if not found:
            return
        parts = []
        for name, value, distance in found:
            j = self.names.index(name)
            width = self.high[j] - self.low[j]
            share = f", {100 * abs(distance) / width:.0f} % of its range" if width > 0 else ""
            side = "above" if distance > 0 else "below"
            parts.append(f"{name} reached {value:.4g}, {abs(distance):.3g} {side} the fitted "
                         f"range [{self.low[j]:.4g}, {self.high[j]:.4g}]{share}")
        warnings.warn(f"{where} left the region the model's terms were fitted on: "
                      + "; ".join(parts) + ". Its learned terms are extrapolated there.",
                      ExtrapolationWarning, stacklevel=stacklevel)

    def to_data(self) -> dict:
        """JSON-ready ``{"variables": names, "low": [...], "high": [...]}`` (what the model file
        keeps; :meth:`from_data` reads it back)."""
        return {"variables": list(self.names), "low": self.low.tolist(),
                "high": self.high.tolist()}

    @classmethod
    def from_data(cls, data, names: list[str]) -> FittedRegion:
        """From :meth:`to_data`'s dict, checked against the model's variable ``names``
        (raises ValueError with what is wrong)."""
        if not isinstance(data, dict) or set(data) != {"variables", "low", "high"} or \
                data["variables"] != list(names):
            raise ValueError(f"region must be {{'variables': {list(names)}, 'low': [...], "
                             "'high': [...]}")
        bounds = []
        for key in ("low", "high"):
            values = data[key]
            if not isinstance(values, list) or len(values) != len(names) or not all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    for v in values):
                raise ValueError(f"region {key} must be {len(names)} finite numbers")
            bounds.append(np.array(values, dtype=float))
        if np.any(bounds[0] > bounds[1]):
            raise ValueError("region low must not exceed high")
        return cls(tuple(names), *bounds)


def guard(model, z: np.ndarray, where: str, stacklevel: int = 4) -> None:
    """Warn (once per call) when ``z`` = ``[x, u]`` (or its first columns) given to a
    fitted model leaves its region where its learned terms depend on it."""
    if model.region_ is not None and not model.prior_only_:
        model.region_.warn_outside(z, where, only=_watched(model), stacklevel=stacklevel)


def _watched(model) -> tuple:
    """:func:`watched_names` of the model's active terms, kept while its support stays."""
    support = np.any(np.asarray(model.coef_) != 0, axis=0)
    key = support.tobytes()
    kept = getattr(model, "_watched_names", None)
    if kept is None or kept[0] != key:
        terms = [e for e, on in zip(model.feature_expressions_, support, strict=True) if on]
        kept = (key, watched_names(terms, model.region_.names))
        model._watched_names = kept
    return kept[1]


def watched_names(terms, names) -> tuple:
    """The variables ``names`` that the sympy expressions ``terms`` depend on, less those
    every term using them sees through 2π-periodic functions (``sin(q)``, ``cos(2 q)``:
    unchanged, as sympy evaluates it, when ``q`` moves by 2π)."""
    out = []
    for name in names:
        using = [(e, s) for e in terms for s in e.free_symbols if s.name == name]
        if any(e.subs(s, s + 2 * sp.pi) != e for e, s in using):
            out.append(name)
    return tuple(out)


def guard_run(model, states: np.ndarray, u, where: str) -> None:
    """The same for a simulated run and its sampled input (a callable input: the states
    alone)."""
    if model.n_inputs_ and u is not None and not callable(u):
        u = np.asarray(u, dtype=float).reshape(len(u), -1)
        states = np.hstack([states, u]) if len(u) == len(states) else states
    guard(model, states, where, stacklevel=5)


def region_of(held_out, names) -> FittedRegion | None:
    """The region recorded beside a fit's statistics (None when nothing was recorded)."""
    if held_out is None or held_out.low is None or len(held_out.low) != len(names):
        return None
    return FittedRegion(tuple(names), held_out.low.copy(), held_out.high.copy())
