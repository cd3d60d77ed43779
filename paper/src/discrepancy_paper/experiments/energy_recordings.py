"""Simulated free swings of one-, two- and three-link pendulums with known friction.

Each chain is written as ``T`` and ``V`` of uniform rods in relative joint angles
(:class:`~discrepancy.systems.LagrangianSystem`); its true friction acts at the joints as
generalised forces (viscous ``k w``, Coulomb ``F_c sign(w)``, a Stribeck excess
``F_s exp(-(|w|/v_s)^d) sign(w)`` with ``d`` 1 or 2 and ``v_s`` not always one of the library's,
quadratic ``c w |w|``), signs smoothed over 1 mrad/s, and optionally as air drag on each
link's absolute rate (``c_i |omega_i|^3``, which the default library, written in joint
speeds, does not contain). Angles are read by encoders of 2048-5000 counts per revolution at
500 Hz or 1 kHz; a recording ends when 15 % of the initial energy above rest is left.
Every friction torque at rest is below 1.5 % of the link's gravity torque scale, so the
pendulums never stick while they swing. Parameters are drawn per ``(links, family, seed)``.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import sympy as sp

from discrepancy.systems import LagrangianSystem

G = 9.81
EPS = 1e-3                 # rad/s: smoothing of the simulated sign functions
FAMILIES = ("viscous + Coulomb", "Stribeck", "quadratic drag", "mixed", "strong Stribeck")
_CODE = {"viscous + Coulomb": "vc", "Stribeck": "stribeck", "quadratic drag": "drag",
         "mixed": "mixed", "strong Stribeck": "lowspeed"}


@dataclass(frozen=True)
class Recording:
    """A simulated recording and its truth.

    Attributes:
        name: e.g. ``"2 links, Stribeck, seed 0"``.
        system: the true system (with friction); model: the conservative prior (``T + V``).
        q: encoder angles ``(m, k)`` (rad); t: times (s); x: exact states ``(m, 2k)``.
        laws: per joint ``{"k", "Fc", "Fs", "vs", "delta"}``; drag: link drag coefficients.
    """

    name: str
    system: LagrangianSystem
    model: LagrangianSystem
    q: np.ndarray
    t: np.ndarray
    x: np.ndarray
    laws: tuple
    drag: tuple | None

    def dissipated_power(self, x: np.ndarray) -> np.ndarray:
        """The true friction's power (W) at states ``x`` ``(m, 2k)``, ``(m,)``."""
        k = x.shape[1] // 2
        w = x[:, k:]
        power = np.zeros(len(x))
        for i, law in enumerate(self.laws):
            speed = np.abs(w[:, i])
            torque = law.get("k", 0) * speed + law.get("Fc", 0) + law.get("c", 0) * speed ** 2
            if law.get("Fs"):
                torque = torque + law["Fs"] * np.exp(-(speed / law["vs"]) ** law["delta"])
            power += torque * speed
        for i, c in enumerate(self.drag or ()):
            power += c * np.abs(np.sum(w[:, :i + 1], axis=1)) ** 3
        return power

    def static_friction(self) -> np.ndarray:
        """True break-away torque per joint (N m): Coulomb plus Stribeck excess."""
        return np.array([law.get("Fc", 0) + law.get("Fs", 0) for law in self.laws])


def rods(masses, lengths, q, w):
    """``T`` and ``V`` of uniform rods (inertia ``m l^2 / 12`` about the centre) chained by
    the relative angles ``q`` (the first from hanging down) with rates ``w``."""
    angle, x, y, omega, kinetic, potential = 0, 0, 0, 0, 0, 0
    for i in range(len(masses)):
        angle, omega = angle + q[i], omega + w[i]
        cx, cy = x + lengths[i] / 2 * sp.sin(angle), y - lengths[i] / 2 * sp.cos(angle)
        vx = sum(sp.diff(cx, a) * b for a, b in zip(q, w, strict=True))
        vy = sum(sp.diff(cy, a) * b for a, b in zip(q, w, strict=True))
        kinetic += masses[i] * (vx ** 2 + vy ** 2) / 2 + masses[i] * lengths[i] ** 2 / 24 \
            * omega ** 2
        potential += masses[i] * G * cy
        x, y = x + lengths[i] * sp.sin(angle), y - lengths[i] * sp.cos(angle)
    return kinetic, potential


def _torque(w, law):
    sign = w / sp.sqrt(w ** 2 + EPS ** 2)
    torque = law.get("k", 0) * w + law.get("Fc", 0) * sign + law.get("c", 0) * w * sp.sqrt(
        w ** 2 + EPS ** 2)
    if law.get("Fs"):
        torque += law["Fs"] * sp.exp(-(sp.sqrt(w ** 2 + EPS ** 2) / law["vs"])
                                     ** law["delta"]) * sign
    return torque


def chain(masses, lengths, laws, drag=None) -> tuple[LagrangianSystem, LagrangianSystem]:
    """The true chain (friction as joint forces, link drag as a dissipation function) and
    its conservative model."""
    n = len(masses)
    q, w = sp.symbols(f"q1:{n + 1}"), sp.symbols(f"dq1:{n + 1}")
    kinetic, potential = rods(masses, lengths, q, w)
    dissipation, omega = 0, 0
    for i in range(n if drag else 0):
        omega += w[i]
        dissipation += drag[i] * (omega ** 2 + EPS ** 2) ** sp.Rational(3, 2) / 3
    names = [s.name for s in q]
    true = LagrangianSystem(kinetic, potential, names, dissipation=dissipation,
                            forces=[-_torque(w[i], laws[i]) for i in range(n)])
    return true, LagrangianSystem(kinetic, potential, names)


def draw(links: int, family: str, seed: int) -> dict:
    """Random realistic rods, friction of ``family`` and recording settings."""
    code = _CODE[family]
    rng = np.random.default_rng(seed)
    masses = rng.uniform(0.15, 0.8, links) * (0.7 ** np.arange(links))
    lengths = rng.uniform(0.2, 0.5, links)
    laws, drag = [], None
    for i in range(links):
        gravity = masses[i] * G * lengths[i] / 2
        law = {"k": gravity * rng.uniform(1e-4, 4e-3)}
        if code in ("vc", "mixed", "stribeck"):
            law["Fc"] = gravity * rng.uniform(1e-3, 8e-3)
        if code == "lowspeed":
            law["Fc"] = gravity * rng.uniform(1e-3, 3e-3)
            law["Fs"] = gravity * rng.uniform(5e-3, 1.5e-2)
            law["vs"] = float(rng.choice([0.2, 0.4, 0.8]))
            law["delta"] = int(rng.choice([1, 2]))
        if code in ("stribeck", "mixed"):
            law["Fs"] = gravity * rng.uniform(2e-3, 1e-2)
            law["vs"] = float(rng.choice([0.03, 0.1, 0.3, 0.6]))
            law["delta"] = int(rng.choice([1, 2]))
        laws.append(law)
    if code in ("drag", "mixed"):
        drag = [masses[i] * lengths[i] ** 2 * rng.uniform(2e-3, 1.5e-2) for i in range(links)]
    amplitude = {1: rng.uniform(1.5, 2.8), 2: rng.uniform(1.0, 2.2),
                 3: rng.uniform(0.8, 1.8)}[links]
    start = np.r_[amplitude, rng.uniform(-1, 1, links - 1)]
    seconds = {1: rng.uniform(40, 90), 2: rng.uniform(30, 60), 3: rng.uniform(20, 45)}[links]
    return {"masses": masses, "lengths": lengths, "laws": laws, "drag": drag,
            "start": start, "seconds": seconds,
            "rate": float(rng.choice([500.0, 1000.0])),
            "counts": int(rng.choice([2048, 4096, 5000]))}


@functools.lru_cache(maxsize=16)
def simulate(links: int, family: str, seed: int, *, tolerance: float = 1e-10,
             seconds: float | None = None) -> Recording:
    """The recording ``(links, family, seed)``: simulated, read by encoders, cut where 15 %
    of the initial energy above rest is left. Kept for the process (a chain with Stribeck
    friction takes about a minute of CPU at the tolerances used): treat it as read-only.

    ``tolerance`` (the integrator's ``rtol`` and ``atol``) and ``seconds`` (the simulated
    span, default the drawn one; the recording ends there if the energy has not yet fallen
    to 15 %) exist for quick tests: the experiments use the defaults. A shorter span leaves
    the states before its last step unchanged (scipy's adaptive steps do not look ahead)."""
    spec = draw(links, family, seed)
    true, model = chain(spec["masses"], spec["lengths"], spec["laws"], spec["drag"])
    span = spec["seconds"] if seconds is None else min(seconds, spec["seconds"])
    t = np.arange(int(span * spec["rate"]) + 1) / spec["rate"]
    x = true.simulate(np.r_[spec["start"], np.zeros(links)], t, rtol=tolerance, atol=tolerance)
    step = 2 * np.pi / spec["counts"]
    q = np.round(x[:, :links] / step) * step
    rest = float(model.energy(np.zeros((1, 2 * links)))[0])
    above = model.energy(x) - rest
    low = np.flatnonzero(above < 0.15 * above[0])
    end = low[0] if len(low) else len(t)
    return Recording(f"{links} link{'s' if links > 1 else ''}, {family}, seed {seed}", true,
                     model, q[:end], t[:end], x[:end], tuple(spec["laws"]),
                     None if spec["drag"] is None else tuple(spec["drag"]))
