"""The dissipation form: energy lost as the time integral of sparse, non-negative friction power.

``dH(t) = c + sum_j xi_j * int_0^t theta_j(dq) dt`` with ``xi_j >= 0``. Each ``theta_j`` is the
power (per unit coefficient) of one friction law, a non-negative function of the joint speeds,
so every learned model dissipates (passivity) and its coefficients are the friction laws.
The integral needs velocities only, never accelerations. ``c`` absorbs the error of the
reference energy ``E0 = H_m(x(0))``, which comes from a single noisy sample.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np
import sympy as sp
from scipy.integrate import cumulative_trapezoid
from scipy.ndimage import uniform_filter1d
from scipy.optimize import lsq_linear, nnls

from ..errors import ParameterError
from ..symbolic import compile_numpy, symbol


@dataclass(frozen=True)
class FrictionTerm:
    """One candidate friction law.

    Attributes:
        name: short label, e.g. ``"viscous joint 1"``.
        power: sympy expression of the dissipated power per unit coefficient (W / [unit]),
            non-negative, in the state symbols (usually the velocities only).
        unit: SI unit of the coefficient, e.g. ``"N m s"``.
        torque: the torque (or loss) law it stands for, for printing.
        functions: numpy callables for undefined sympy functions in ``power`` (name ->
            callable of the function's arguments, each ``(m,)``), e.g. a force computed by
            the system model.
        speed: the joint speed ``w`` the law acts at (sympy), when it is a torque: its torque
            per unit coefficient is ``power / |w|``, which :func:`torque_bounds` limits.
    """

    name: str
    power: sp.Expr
    unit: str
    torque: str
    functions: Mapping[str, Callable] | None = field(default=None, compare=False)
    speed: sp.Expr | None = field(default=None, compare=False)


def default_friction_library(velocity_names, *, joints=None, stribeck_speed: float = 0.1,
                             coulomb_smoothing: float | None = None) -> tuple[FrictionTerm, ...]:
    """Friction laws a tribologist would try, for any number of coordinates.

    Args:
        velocity_names: the velocity variables (e.g. ``["dq1", "dq2"]``).
        joints: ``{label: relative speed}``: what each joint turns at, as sympy expressions
            of the velocity symbols or velocity names (default: each coordinate is its own
            joint, ``{"joint i": dq_i}``). A double pendulum with absolute angles has
            ``{"joint 1": dphi1, "joint 2": dphi1 - dphi2}``.
        stribeck_speed: ``v_s`` (rad/s) of the Stribeck excess.
        coulomb_smoothing: ``eps`` (rad/s): Coulomb friction as ``F tanh(w / eps)``.

    Per joint at speed ``w``: viscous ``k w`` (power ``k w^2``), Coulomb ``F sign(w)``
    (power ``F |w|``, or ``F w tanh(w/eps)`` smoothed) and a Stribeck excess
    ``F_s exp(-(w/v_s)^2) sign(w)``; per coordinate, quadratic air drag ``c dq |dq|``
    (power ``c |dq|^3``).
    """
    if not isinstance(stribeck_speed, (int, float)) or not stribeck_speed > 0:
        raise ParameterError(f"stribeck_speed must be > 0 rad/s; got {stribeck_speed!r}")
    if coulomb_smoothing is not None and not (isinstance(coulomb_smoothing, (int, float))
                                              and coulomb_smoothing > 0):
        raise ParameterError("coulomb_smoothing must be > 0 rad/s or None; "
                             f"got {coulomb_smoothing!r}")
    if isinstance(velocity_names, str) or not velocity_names:
        raise ParameterError(f"velocity_names must be a non-empty list of names; got "
                             f"{velocity_names!r}")
    speeds = [symbol(n) for n in velocity_names]
    joints = joint_speeds(joints, speeds)
    terms = [FrictionTerm(f"viscous {label}", w ** 2, "N m s", f"k ({w})", speed=w)
             for label, w in joints.items()]
    for label, w in joints.items():
        if coulomb_smoothing is None:
            power, law = sp.Abs(w), f"F sign({w})"
        else:
            eps = sp.Float(coulomb_smoothing)
            power, law = w * sp.tanh(w / eps), f"F tanh(({w})/{coulomb_smoothing:g})"
        terms.append(FrictionTerm(f"Coulomb {label}", power, "N m", law, speed=w))
    for d in speeds:
        terms.append(FrictionTerm(f"air drag {d.name}", sp.Abs(d) ** 3, "N m s^2",
                                  f"c {d} |{d}|", speed=d))
    vs = sp.Float(stribeck_speed)
    for label, w in joints.items():
        terms.append(FrictionTerm(f"Stribeck {label}", sp.Abs(w) * sp.exp(-(w / vs) ** 2), "N m",
                                  f"F_s exp(-(({w})/{stribeck_speed:g})^2) sign({w})",
                                  speed=w))
    return tuple(terms)


def without_stribeck(terms) -> tuple[FrictionTerm, ...]:
    """The library without its Stribeck terms (those of :func:`default_friction_library`)."""
    return tuple(term for term in terms if not term.name.startswith("Stribeck "))


def joint_speeds(joints, speeds) -> dict[str, sp.Expr]:
    """``{label: relative speed}`` checked against the velocity symbols ``speeds`` (default:
    each coordinate its own joint)."""
    if joints is None:
        return {f"joint {i + 1}": d for i, d in enumerate(speeds)}
    if not isinstance(joints, Mapping) or not joints:
        raise ParameterError(f"joints must be a mapping of labels to relative speeds; got "
                             f"{joints!r:.80}")
    names = {d.name for d in speeds}
    out = {}
    for label, w in joints.items():
        expr = symbol(w) if isinstance(w, str) and w in names else w
        if not isinstance(expr, sp.Expr) or not expr.free_symbols or \
                not {s.name for s in expr.free_symbols} <= names:
            raise ParameterError(f"joints[{label!r}] must be a velocity name or a sympy "
                                 f"expression of {sorted(names)}; got {w!r:.60}")
        out[str(label)] = expr.xreplace({s: symbol(s.name) for s in expr.free_symbols})
    return out


def support_loss_terms(pivot_force: Callable, state_names, *,
                       static_vertical: float = 0.0) -> tuple[FrictionTerm, ...]:
    """Energy absorbed by a rig's mount: ``c Fx^2`` and ``c (Fy - W)^2``.

    ``pivot_force(x)`` ``(m, n)`` -> ``(m, 2)`` is the force (N) between pivot and pendulum,
    e.g. :meth:`~discrepancy.systems.DoublePendulum.pivot_force`; ``static_vertical`` is its
    value at rest (the weight ``W``), so that only the dynamic part counts. A mount whose
    motion under that force is dominated by damping moves at ``F / c_m`` and dissipates
    ``F^2 / c_m``; the coefficient ``c = 1 / c_m`` has the unit m / (N s).
    """
    args = [symbol(n) for n in state_names]

    def component(j, offset):
        return lambda *cols: pivot_force(np.column_stack(cols))[:, j] - offset

    terms = []
    for label, j, offset in (("horizontal", 0, 0.0), ("vertical", 1, static_vertical)):
        name = f"F{'xy'[j]}"
        force = sp.Function(name)(*args)
        terms.append(FrictionTerm(f"support loss {label}", force ** 2, "m/(N s)",
                                  f"mount moving under the pivot's {label} force {name}",
                                  functions={name: component(j, offset)}))
    return tuple(terms)


def integrated_powers(terms, values: np.ndarray, t: np.ndarray, names) -> np.ndarray:
    """``int_0^t theta_j dt`` (trapezoid) for every term: ``(m, p)`` (J per unit coefficient).

    ``values`` ``(m, len(names))`` holds the variables the terms' powers use (the joint
    speeds, or the whole state for terms such as :func:`support_loss_terms`).
    """
    columns = [compile_numpy(term.power, list(names), term.functions)(values) for term in terms]
    return cumulative_trapezoid(np.column_stack(columns), t, axis=0, initial=0.0)


def torque_bounds(terms, values: np.ndarray, names, limit: float) -> np.ndarray:
    """Largest coefficient ``(p,)`` each term may take so that its torque stays within
    ``limit`` (N m) at every sample of ``values`` (``inf`` for terms without a ``speed``).

    A term's torque per unit coefficient is ``power / |speed|``; where the speed is ~0 its
    limit (e.g. a Coulomb or Stribeck torque's full size) is taken from the samples nearby.
    """
    upper = np.full(len(terms), np.inf)
    if not np.isfinite(limit):
        return upper
    for j, term in enumerate(terms):
        if term.speed is None:
            continue
        power = compile_numpy(term.power, list(names), term.functions)(values)
        speed = np.abs(compile_numpy(term.speed, list(names))(values))
        moving = speed > 1e-6 * max(float(np.max(speed)), 1e-300)
        per_unit = np.max(np.broadcast_to(power, speed.shape)[moving] / speed[moving],
                          initial=0.0)
        if per_unit > 0:
            upper[j] = limit / per_unit
    return upper


def block_means(values: np.ndarray, block: int) -> np.ndarray:
    """Means over consecutive blocks of ``block`` samples (a last partial block is dropped):
    ``(m, ...)`` -> ``(m // block, ...)``."""
    n = len(values) // block
    return values[:n * block].reshape(n, block, *values.shape[1:]).mean(axis=1)


def block_weights(target: np.ndarray, block: int) -> np.ndarray:
    """Relative weights ``1 / |energy lost per block|`` of the block fit (see below)."""
    loss = np.diff(block_means(target, block))
    return 1.0 / np.maximum(np.abs(loss), 1e-3 * np.max(np.abs(loss)))


def nonnegative_fit(features: np.ndarray, target: np.ndarray, block: int | None = None,
                    weights: np.ndarray | None = None, upper: np.ndarray | None = None
                    ) -> np.ndarray:
    """``[c, xi]`` of ``target ~ c + features @ xi`` with ``0 <= xi <= upper``.

    ``block=None``: least squares on the cumulative curves. ``block=b`` (samples): the energy
    lost from one block of ``b`` samples to the next is fitted with *relative* weights
    ``1 / loss`` (or the given ``weights``, e.g. a bootstrap keeping the original fit's), so
    late, low-energy blocks count as much as early ones (an absolute fit is dominated by the
    first seconds of a decaying swing); ``c`` is then the mean residual. The loss is taken
    between the blocks' mean levels, not between single samples at their edges: a single
    sample carries the full pointwise noise of ``H_m``, which in the relative weights of the
    small late losses picked wrong laws on simulated encoder data (see the tests).
    ``upper`` ``(p,)``: physical limits of the coefficients (:func:`torque_bounds`).
    """
    k = features.shape[1]
    upper = np.full(k, np.inf) if upper is None else np.asarray(upper, float)
    if block is not None:
        loss = np.diff(block_means(target, block))
        gained = np.diff(block_means(features, block), axis=0)
        w = block_weights(target, block) if weights is None else weights
        scale = np.maximum(np.max(np.abs(gained), axis=0), 1e-300)
        design = gained * w[:, None] / scale
        if np.all(np.isinf(upper)):
            xi, _ = nnls(design, loss * w)
        else:
            xi = lsq_linear(design, loss * w, bounds=(0.0, upper * scale), method="bvls").x
        xi = xi / scale
        return np.concatenate([[np.mean(target - features @ xi)], xi])
    design = np.column_stack([np.ones(len(target)), features])
    scale = np.maximum(np.max(np.abs(design), axis=0), 1e-300)
    sol = lsq_linear(design / scale, target,
                     bounds=([-np.inf] + [0.0] * k, np.r_[np.inf, upper * scale[1:]]),
                     method="bvls")
    return sol.x / scale


def _predict(coef: np.ndarray, features: np.ndarray) -> np.ndarray:
    return coef[0] + features @ coef[1:]


def select_terms(features: np.ndarray, delta_h: np.ndarray, *, max_terms: int = 4,
                 holdout: float = 0.0, tolerance: float = 0.02, block: int | None = None,
                 upper: np.ndarray | None = None) -> tuple[tuple[int, ...], list]:
    """Best non-negative subset of at most ``max_terms`` columns (exhaustive search).

    Score of a subset: with ``holdout = 0`` the RMS training error (J) after a moving average
    over 1 % of the samples (the cumulative model is smooth; the pointwise noise of ``H_m``
    from differentiated angles would otherwise hide what a term adds); with ``holdout = h``
    the subset is fitted on the first ``1 - h`` of the samples and scored by the largest error
    with which it continues over the last ``h``, relative to that part's own ``dH`` range
    (the task a later validation window poses). Subsets in which a coefficient hits the
    bound 0 duplicate a smaller subset and are skipped. The size grows from 1 while the best
    score of the next size is lower by more than the fraction ``tolerance`` (an elbow rule:
    the cumulative features are strongly correlated, so noise alone lowers the error a little
    with every term). ``block`` chooses the fit and ``upper`` bounds the coefficients (see
    ``nonnegative_fit``).

    Returns ``(support, candidates)`` with ``candidates`` the sorted ``(score, subset)`` list;
    ``support`` is empty when no law fits with positive coefficients (no dissipation seen).
    """
    m, p = features.shape
    if not isinstance(max_terms, (int, np.integer)) or max_terms < 1:
        raise ParameterError(f"max_terms must be an integer >= 1; got {max_terms!r}")
    max_terms = min(int(max_terms), p)
    if not 0 <= holdout < 0.9:
        raise ParameterError(f"holdout must be a fraction in [0, 0.9); got {holdout}")
    cut = int(round(m * (1 - holdout)))
    upper = np.full(p, np.inf) if upper is None else np.asarray(upper, float)
    smooth = max(1, m // 100)
    candidates = []
    for k in range(1, max_terms + 1):
        for subset in combinations(range(p), k):
            cols = features[:, subset]
            coef = nonnegative_fit(cols[:cut], delta_h[:cut], block, upper=upper[list(subset)])
            if np.any(coef[1:] == 0):
                continue
            error = delta_h - _predict(coef, cols)
            if holdout > 0:
                score = np.max(np.abs(error[cut:])) / max(np.ptp(delta_h[cut:]), 1e-300)
            else:
                score = np.sqrt(np.mean(uniform_filter1d(error, smooth) ** 2))
            candidates.append((float(score), subset))
    candidates.sort()
    best = {}
    for score, subset in candidates:
        best.setdefault(len(subset), (score, subset))
    if not best:    # every law needs a negative coefficient: the data show no dissipation
        return (), candidates
    # errors below ~1e-5 of dH's spread are the trapezoid rule's, not information
    floor = 1e-5 if holdout > 0 else 1e-5 * float(np.std(delta_h))
    sizes = sorted(best)
    chosen = sizes[0]
    for k in sizes[1:]:
        if best[chosen][0] > floor and best[k][0] < best[chosen][0] * (1 - tolerance):
            chosen = k
        else:
            break
    return best[chosen][1], candidates


@dataclass(frozen=True)
class DissipationFit:
    """Result of :func:`fit_dissipation`: the chosen terms, their coefficients and the offset."""

    terms: tuple[FrictionTerm, ...]
    coefficients: np.ndarray     # (k,), in each term's unit
    offset: float                # J
    candidates: list             # (score, names) of every subset tried
    upper: np.ndarray | None = None   # (k,) physical limits of the coefficients


def fit_dissipation(features: np.ndarray, delta_h: np.ndarray, terms,
                    **selection) -> DissipationFit:
    """Select terms (:func:`select_terms`) and refit them on all samples."""
    support, candidates = select_terms(features, delta_h, **selection)
    upper = selection.get("upper")
    upper = np.full(features.shape[1], np.inf) if upper is None else np.asarray(upper, float)

    def refit(subset):
        return nonnegative_fit(features[:, subset], delta_h, selection.get("block"),
                               upper=upper[list(subset)])

    coef = refit(support) if support else np.array([np.mean(delta_h)])
    kept = [k for k in range(len(support)) if coef[1 + k] > 0]  # refitted to 0: dropped
    if len(kept) < len(support):
        support = tuple(support[k] for k in kept)
        coef = refit(support) if support else np.array([np.mean(delta_h)])
    named = [(s, [terms[i].name for i in sub]) for s, sub in candidates]
    return DissipationFit(terms=tuple(terms[i] for i in support), coefficients=coef[1:],
                          offset=float(coef[0]), candidates=named,
                          upper=upper[list(support)])
