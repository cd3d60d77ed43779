"""A recording made ready for energy fits, once, so that many fits can share it.

States, ``dH = H_m(x_0) - H_m(x)``, every library term's integrated power and torque per
unit coefficient, the joint speeds and the largest conservative torque up to each sample:
a fit of any procedure on any prefix or window of the recording only selects rows of these
arrays (the integrated powers restart at a window's start up to a constant, which the fit's
offset absorbs). The soundness constraints of a fit on ``[0, stop)`` come from the same
arrays (:mod:`.soundness`), as does the check of a fitted law.
"""
from __future__ import annotations

import numpy as np

from ..data.validation import check_array, check_times
from ..errors import ParameterError, ShapeError
from ..symbolic import compile_numpy
from .dissipation import integrated_powers
from .regression import Statistics, statistics
from .soundness import (
    STATIC_MARGIN,
    Limits,
    envelope_rows,
    holding_torques,
    joint_axes,
    kinetic_is_quadratic,
    per_unit_torques,
    reversals,
)

#: turning points kept as single constraints (the lowest holding torques); the rest merged
SINGLE_TURNS = 32
#: samples of a reversal's slow passage at which the holding torque is evaluated
PASSAGE_SAMPLES = 9


class PreparedRecording:
    """Arrays of one recording for energy fits (see the module docstring).

    Args:
        energy: ``H_m(x)`` ``(m, 2k)`` -> ``(m,)`` (J).
        x: states ``[q, dq]`` ``(m, 2k)``; t: times (s) ``(m,)``.
        terms: the friction library (:class:`~discrepancy.energy.FrictionTerm`).
        names: the ``2k`` variable names.
    """

    def __init__(self, energy, x: np.ndarray, t: np.ndarray, terms, names):
        x = check_array("x", x)
        if x.shape[1] % 2 or len(list(names)) != x.shape[1]:
            raise ShapeError(f"x must hold positions then velocities (m, 2k), one column per "
                             f"name of {list(names)}; got shape {x.shape}")
        t = check_times("t", t, len(x))
        self.energy, self.x, self.t = energy, x, t
        self.terms, self.names = tuple(terms), list(names)
        k = x.shape[1] // 2
        h = energy(x)
        self.h0, self.delta_h = float(h[0]), h[0] - h
        self.features = integrated_powers(self.terms, x, t, self.names)
        self.torques = per_unit_torques(self.terms, x, self.names)
        self.axes = joint_axes(self.terms, self.names[k:])
        self.speeds = [np.broadcast_to(compile_numpy(axis.speed, self.names)(x), (len(x),))
                       for axis in self.axes]
        self.largest_conservative = np.maximum.accumulate(
            np.max(np.abs(conservative_torques(energy, x)), axis=1))
        self._holding: dict = {}
        self._limits: dict = {}
        self._turns: dict = {}
        self._statistics: dict = {}

    def statistics(self, start: int, stop: int, block: int | None, columns) -> Statistics:
        """Statistics (:mod:`.regression`) of the fit on ``[start, stop)`` of the terms
        ``columns``, with integrals and dH restarting at ``start``; each range is reduced
        once for every term and shared by all procedures that fit it."""
        key = (start, stop, block)
        if key not in self._statistics:
            self._statistics[key] = statistics(self.features[start:stop],
                                               self.delta_h[start:stop], block)
        return self._statistics[key].restricted(columns, shift_y=self.delta_h[start],
                                                shift_f=self.features[start, columns])

    def window_start(self, stop: int, seconds: float | None) -> int:
        """First sample of the last ``seconds`` before ``stop`` (0 for ``None``)."""
        if isinstance(stop, (bool, np.bool_)) or not isinstance(stop, (int, np.integer)) \
                or not 1 <= stop <= len(self.t):
            raise ParameterError(f"stop must be a sample count in [1, {len(self.t)}]; got "
                                 f"{stop!r}")
        if seconds is None:
            return 0
        return int(np.searchsorted(self.t[:stop], self.t[stop - 1] - seconds))

    def torque_limit(self, stop: int, torque_limit) -> float:
        """The whole-law bound (N m) for a fit on ``[0, stop)``: ``"auto"`` the largest
        conservative torque there (``inf`` if none), a number, or ``inf`` for ``None``."""
        if torque_limit is None:
            return np.inf
        if torque_limit != "auto":
            return float(torque_limit)
        largest = float(self.largest_conservative[stop - 1])
        return largest if largest > 0 else np.inf

    def turns(self, stop: int, axis: int) -> tuple[np.ndarray, np.ndarray]:
        """Turning points of joint ``axis`` in ``[0, stop)`` and their holding torques (N m):
        the largest over the reversal's passage through slow speeds, since a joint that
        sticks for a moment while the other links move breaks free once the torque holding
        it exceeds its static friction. None when the joint speed is not linear in the rates
        or the energy's kinetic part is not quadratic in them (no mechanical holding torque
        exists to compare with)."""
        if (stop, axis) not in self._turns:
            self._turns[stop, axis] = self._find_turns(stop, axis)
        return self._turns[stop, axis]

    def _find_turns(self, stop: int, axis: int) -> tuple[np.ndarray, np.ndarray]:
        direction = self.axes[axis].direction
        index, first, last = reversals(self.speeds[axis][:stop])
        if direction is None or not kinetic_is_quadratic(self.energy, self.x[index]):
            return np.zeros(0, dtype=int), np.zeros(0)   # no holding torque to compare with
        cache = self._holding.setdefault(axis, {})
        passages = [np.unique(np.linspace(a, b, min(b - a + 1, PASSAGE_SAMPLES)).round()
                              .astype(int)) for a, b in zip(first, last, strict=True)]
        new = sorted({int(i) for p in passages for i in p} - set(cache))
        if new:
            cache.update(zip(new, holding_torques(self.energy, self.x[new], direction),
                             strict=True))
        return index, np.array([max(cache[int(i)] for i in p) for p in passages])

    def limits(self, stop: int, torque_limit="auto", at_turns: bool = True) -> Limits:
        """Soundness constraints (:class:`~discrepancy.energy.soundness.Limits`, over every
        term) of a fit on ``[0, stop)``; computed once per argument set."""
        key = (stop, torque_limit, at_turns)
        if key not in self._limits:
            self._limits[key] = self._build_limits(stop, torque_limit, at_turns)
        return self._limits[key]

    def _build_limits(self, stop, torque_limit, at_turns) -> Limits:
        p = len(self.terms)
        rows, bounds, kinds = [np.zeros((0, p))], [np.zeros(0)], []
        limit = self.torque_limit(stop, torque_limit)
        for a, axis in enumerate(self.axes):
            cols = list(axis.terms)
            if np.isfinite(limit):
                env = envelope_rows(self.torques[:stop, cols], self.speeds[a][:stop])
                rows.append(_widen(env, cols, p))
                bounds.append(np.full(len(env), limit))
                kinds += [f"whole law <= {limit:.4g} N m ({axis.label})"] * len(env)
            index, holding = self.turns(stop, a) if at_turns else ((), ())
            if len(index):
                static, bound = _turn_rows(self.torques[index][:, cols], STATIC_MARGIN * holding)
                rows.append(_widen(static, cols, p))
                bounds.append(bound)
                kinds += [f"static torque < holding torque at turning points "
                          f"({axis.label})"] * len(bound)
        return Limits(np.vstack(rows), np.concatenate(bounds), tuple(kinds))

    def check(self, stop: int, columns, coef, torque_limit="auto") -> dict:
        """How a law (terms ``columns``, coefficients ``coef``) meets the constraints on
        ``[0, stop)``: per joint, its largest whole-law torque over the bound and its largest
        torque at a turning point over the holding torque there (sound: both <= 1)."""
        coef = np.asarray(coef, float)
        limit = self.torque_limit(stop, torque_limit)
        joints = {}
        for a, axis in enumerate(self.axes):
            used = [(i, c) for i, c in zip(columns, coef, strict=True) if i in axis.terms]
            if not used:
                continue
            idx, c = [i for i, _ in used], np.array([c for _, c in used])
            law = self.torques[:stop, idx] @ c
            index, holding = self.turns(stop, a)
            at_turns = law[index] / np.maximum(holding, 1e-300) if len(index) else np.zeros(0)
            joints[axis.label] = {
                "largest_torque_N_m": float(np.max(law)),
                "torque_limit_N_m": limit,
                "largest_torque_over_limit": float(np.max(law) / limit),
                "turning_points": len(index),
                "largest_static_over_holding_torque": float(np.max(at_turns, initial=0.0)),
                "smallest_holding_torque_N_m": float(np.min(holding, initial=np.inf))}
        sound = all(j["largest_torque_over_limit"] <= 1 + 1e-6 and
                    j["largest_static_over_holding_torque"] < 1 for j in joints.values())
        return {"sound": bool(sound), "joints": joints}


def _widen(rows: np.ndarray, cols, p: int) -> np.ndarray:
    out = np.zeros((len(rows), p))
    out[:, cols] = rows
    return out


def _turn_rows(static: np.ndarray, bound: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ``SINGLE_TURNS`` turning points of lowest bound as single rows, the others
    merged into one row (bound 1) that implies all of theirs."""
    order = np.argsort(bound)
    single, rest = order[:SINGLE_TURNS], order[SINGLE_TURNS:]
    rows, bounds = static[single], bound[single]
    if len(rest):
        merged = np.max(static[rest] / np.maximum(bound[rest], 1e-300)[:, None], axis=0)
        rows, bounds = np.vstack([rows, merged]), np.r_[bounds, 1.0]
    return rows, bounds


def conservative_torques(energy, x, *, max_rows: int | None = None) -> np.ndarray:
    """``-dH(q, 0)/dq`` ``(m', k)`` at states ``x = [q, dq]`` ``(m, 2k)`` (every sample, or
    ``max_rows`` evenly spaced): the conservative torques, by central differences of the
    energy at rest (for ``T + V`` with ``T = 0`` at rest this is ``-dV/dq``)."""
    k = x.shape[1] // 2
    rest = x if max_rows is None else x[::max(1, len(x) // max_rows)]
    rest = rest.copy()
    rest[:, k:] = 0.0
    torques = np.empty((len(rest), k))
    for i in range(k):
        h = 1e-6 * max(1.0, float(np.max(np.abs(rest[:, i]))))
        up, down = rest.copy(), rest.copy()
        up[:, i] += h
        down[:, i] -= h
        torques[:, i] = -(energy(up) - energy(down)) / (2 * h)
    return torques
