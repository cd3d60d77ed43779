"""Physical limits of a friction law, as linear constraints on its coefficients.

A law is *sound* on a recording when (1) at every sample, the torque of the whole law at
each joint (the sum of its terms there, not each term alone) stays within the bound
``torque_limit`` (by default the largest conservative torque of the recording), and (2) at
every turning point actually observed (a joint's speed changes sign), the law's torque at
that joint is below the torque the conservative model exerts on the joint there; a larger
static (Coulomb, Stribeck break-away) torque would have held the joint at rest, and it did
not stop. Both are linear in the coefficients ``xi >= 0`` (``rows @ xi <= bounds``), so they
are constraints of the fit, not filters after it.

The torque at a turning point is the *holding torque*: the torque the joint must exert to
stay at rest while every other joint moves freely under the conservative model (gravity,
springs, and the inertial coupling of the moving links). For a single pendulum it is the
gravity torque ``m g l sin q``; in a chain it adds the centrifugal and Coriolis torques of
the other links. It is computed from the energy ``H(q, dq) = T + V`` alone (``T`` quadratic
in the rates): ``M(q)`` from ``T``, the velocity terms by central differences, and the lock
as a Lagrange multiplier ``lambda = a^T M^-1 f / (a^T M^-1 a)`` for the joint speed ``a . dq``.
Written here because no library derives constraint torques from an energy function.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..symbolic import compile_numpy, symbol

#: share of the holding torque a static friction may reach at a turning point
STATIC_MARGIN = 0.98
#: a turning point needs the joint speed beyond this share of its RMS on both sides
TURN_THRESHOLD = 0.02
#: ... reached within this share of the median time between that joint's turning points
MAX_DWELL = 0.25


@dataclass(frozen=True)
class JointAxis:
    """The terms of a library that act at one joint speed.

    Attributes:
        label: e.g. ``"joint 1"``.
        speed: the joint speed (sympy, in the velocity symbols).
        terms: indices of the library's terms acting at this speed.
        direction: ``a`` ``(k,)`` with ``speed = a . dq`` (``None`` if not linear in ``dq``).
    """

    label: str
    speed: sp.Expr
    terms: tuple[int, ...]
    direction: np.ndarray | None


def joint_axes(terms, velocity_names) -> list[JointAxis]:
    """Group the terms that have a ``speed`` by that speed (up to its sign)."""
    velocities = [symbol(n) for n in velocity_names]
    groups: dict = {}
    for j, term in enumerate(terms):
        if term.speed is None:
            continue
        speed = sp.expand(term.speed)
        direction = _linear_direction(speed, velocities)
        if direction is not None:
            first = direction[np.flatnonzero(np.abs(direction) > 1e-12)[0]]
            key = tuple(np.round(direction * np.sign(first), 12))
        else:
            key = min(sp.srepr(speed), sp.srepr(-speed))
        label = term.name.split(" ", 1)[-1].split(" (")[0] if " " in term.name else \
            f"speed {speed}"
        entry = groups.setdefault(key, [label, speed, [], direction])
        entry[2].append(j)
    return [JointAxis(label, speed, tuple(idx), direction)
            for label, speed, idx, direction in groups.values()]


def _linear_direction(speed, velocities) -> np.ndarray | None:
    try:
        poly = sp.Poly(speed, *velocities)
    except sp.PolynomialError:
        return None
    if poly.total_degree() != 1 or any(sum(m) != 1 for m in poly.monoms()):
        return None
    coefficients = [speed.coeff(v) for v in velocities]
    if not all(c.is_number for c in coefficients):
        return None
    return np.array([float(c) for c in coefficients])


def per_unit_torques(terms, x: np.ndarray, names) -> np.ndarray:
    """Torque per unit coefficient ``power / |speed|`` of every term at every sample,
    ``(m, p)`` (N m per unit; ``nan`` for terms without a speed). Where the speed is ~0
    (a Coulomb torque is 0/0 there) the value of the nearest moving sample is taken."""
    out = np.full((len(x), len(terms)), np.nan)
    for j, term in enumerate(terms):
        if term.speed is None:
            continue
        power = np.broadcast_to(compile_numpy(term.power, list(names), term.functions)(x),
                                (len(x),))
        speed = np.abs(np.broadcast_to(compile_numpy(term.speed, list(names))(x), (len(x),)))
        moving = speed > 1e-9 * max(float(np.max(speed)), 1e-300)
        if not np.any(moving):
            out[:, j] = 0.0
            continue
        index = np.flatnonzero(moving)
        torque = power[moving] / speed[moving]
        nearest = np.clip(np.searchsorted(index, np.arange(len(x))), 0, len(index) - 1)
        left = np.clip(nearest - 1, 0, len(index) - 1)
        closer = np.abs(index[left] - np.arange(len(x))) < np.abs(index[nearest]
                                                                 - np.arange(len(x)))
        out[:, j] = torque[np.where(closer, left, nearest)]
    return out


def turning_points(speed: np.ndarray) -> np.ndarray:
    """Indices ``(n,)`` where a joint speed ``(m,)`` reverses: it goes from beyond
    ``TURN_THRESHOLD`` of its RMS on one side to beyond it on the other, within
    ``MAX_DWELL`` of the median time between reversals (a longer dwell may be a stop, which
    says nothing against static friction). Each is the sample of smallest ``|speed|`` in
    between; noise around a joint at rest is no turning point."""
    return reversals(speed)[0]


def reversals(speed: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`turning_points` with the first and last sample of each reversal's passage
    through the band ``|speed| <= threshold``: ``(index, first, last)``, each ``(n,)``."""
    none = (np.zeros(0, dtype=int),) * 3
    threshold = TURN_THRESHOLD * float(np.sqrt(np.mean(speed ** 2)))
    if threshold <= 0:
        return none
    side = np.where(speed > threshold, 1, np.where(speed < -threshold, -1, 0))
    beyond = np.flatnonzero(side)
    if len(beyond) < 2:
        return none
    flips = np.flatnonzero(side[beyond[1:]] != side[beyond[:-1]])
    left, right = beyond[flips], beyond[flips + 1]
    if len(left) == 0:
        return none
    spacing = np.median(np.diff(left)) if len(left) > 2 else np.inf
    keep = right - left <= max(MAX_DWELL * spacing, 2)
    left, right = left[keep], right[keep]
    index = np.array([a + int(np.argmin(np.abs(speed[a:b + 1])))
                      for a, b in zip(left, right, strict=True)], dtype=int)
    return index, left, right


def _kinetic_and_potential(energy, x):
    k = x.shape[1] // 2
    rest = x.copy()
    rest[:, k:] = 0.0
    potential = energy(rest)
    return energy(x) - potential, potential


def mass_matrix(energy, q: np.ndarray) -> np.ndarray:
    """``M(q)`` ``(m, k, k)`` of ``T = dq^T M dq / 2`` from ``H = T + V`` (exact for a
    kinetic energy quadratic in the rates)."""
    m, k = q.shape

    def kinetic(v):
        state = np.hstack([q, np.broadcast_to(v, (m, k))])
        return _kinetic_and_potential(energy, state)[0]

    eye = np.eye(k)
    single = [kinetic(eye[a]) for a in range(k)]
    out = np.empty((m, k, k))
    for a in range(k):
        out[:, a, a] = 2 * single[a]
        for b in range(a + 1, k):
            out[:, a, b] = out[:, b, a] = kinetic(eye[a] + eye[b]) - single[a] - single[b]
    return out


def kinetic_is_quadratic(energy, x: np.ndarray) -> bool:
    """Whether ``H(q, dq) - H(q, 0)`` at states ``x`` ``(m, 2k)`` is quadratic in ``dq`` (a
    mechanical kinetic energy), which :func:`holding_torques` needs."""
    if len(x) == 0:
        return True
    k = x.shape[1] // 2
    double = x.copy()
    double[:, k:] *= 2
    single = _kinetic_and_potential(energy, x)[0]
    return bool(np.allclose(_kinetic_and_potential(energy, double)[0], 4 * single,
                            rtol=1e-6, atol=1e-9 * max(float(np.max(np.abs(single))), 1e-300)))


def holding_torques(energy, x: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """``|lambda|`` ``(m,)`` (N m): the torque a joint of speed ``(direction * dq).sum(-1)``
    must exert to stay at rest at states ``x`` ``(m, 2k)`` while the other joints move freely
    under the conservative model ``energy`` (see the module's docstring)."""
    k = x.shape[1] // 2
    q, v = x[:, :k], x[:, k:]
    h = 1e-6 * max(1.0, float(np.max(np.abs(q))))
    mass = mass_matrix(energy, q)
    moving_mass = (mass_matrix(energy, q + h * v) - mass_matrix(energy, q - h * v)) / (2 * h)
    force = -np.einsum("mab,mb->ma", moving_mass, v)
    for i in range(k):
        up, down = x.copy(), x.copy()
        up[:, i] += h
        down[:, i] -= h
        t_up, v_up = _kinetic_and_potential(energy, up)
        t_down, v_down = _kinetic_and_potential(energy, down)
        force[:, i] += (t_up - t_down) / (2 * h) - (v_up - v_down) / (2 * h)
    a = np.broadcast_to(np.asarray(direction, float), (len(x), k))
    inv_a = np.linalg.solve(mass, a[..., None])[..., 0]
    return np.abs(np.einsum("ma,ma->m", inv_a, force) / np.einsum("ma,ma->m", inv_a, a))


@dataclass(frozen=True)
class Limits:
    """``rows @ xi <= bounds``: the soundness constraints of a library's coefficients.

    Attributes:
        rows: ``(n, p)`` torque per unit coefficient of every term.
        bounds: ``(n,)`` N m.
        kinds: ``(n,)`` labels, e.g. ``"whole law <= 1.96 N m (joint 1)"`` or
            ``"static torque < holding torque at turning points (joint 1)"``.
    """

    rows: np.ndarray
    bounds: np.ndarray
    kinds: tuple[str, ...]

    def constraints(self, columns) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, bounds)`` on the terms ``columns`` alone (rows without them dropped)."""
        rows = self.rows[:, list(columns)]
        keep = np.any(rows > 0, axis=1)
        return rows[keep], self.bounds[keep]

    def restricted(self, columns) -> Limits:
        """The constraints on the terms ``columns`` alone, as :class:`Limits`."""
        rows = self.rows[:, list(columns)]
        keep = np.any(rows > 0, axis=1)
        return Limits(rows[keep], self.bounds[keep],
                      tuple(k for k, kept in zip(self.kinds, keep, strict=True) if kept))

    def active(self, columns, xi, tolerance: float = 1e-6) -> list[str]:
        """Kinds of the constraints that hold ``xi`` (coefficients of the terms ``columns``)
        at their bound."""
        if len(self.bounds) == 0:
            return []
        at = self.rows[:, list(columns)] @ np.asarray(xi, float) >= self.bounds * (1 - tolerance)
        return sorted({kind for kind, hit in zip(self.kinds, at, strict=True) if hit})



def envelope_rows(torques: np.ndarray, speed: np.ndarray, bins: int = 128) -> np.ndarray:
    """Per bin of ``|speed|`` (quantiles), the largest per-unit torque of each column:
    ``(n_bins, g)`` rows whose constraints imply those of every sample (``xi >= 0``)."""
    order = np.argsort(np.abs(speed), kind="stable")
    chunks = np.array_split(order, min(bins, len(order)))
    return np.array([np.max(torques[c], axis=0) for c in chunks if len(c)])
