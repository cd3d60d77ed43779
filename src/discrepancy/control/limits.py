"""Limits a controller must respect: state bounds (a cart's rail), input bounds, input rates.

One :class:`Limits` object goes to the planner, the MPC and the closed loop (which
saturates any law as an actuator would), and judges a run afterwards
(:meth:`Limits.check`), so "success" means the same thing everywhere.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError, ShapeError, describe

#: default slack when judging a run's states against ``x_bounds`` (in the state's units): the
#: planner and the MPC bound the states at the grid times only, the plant moves in between
STATE_TOLERANCE = 1e-3


def _box(name, value, size):
    if value is None:
        return None
    b = np.array(value, dtype=float)
    if size is not None and b.shape != (size, 2) or b.ndim != 2 or b.shape[1:] != (2,) \
            or np.any(np.isnan(b)) or np.any(b[:, 0] > b[:, 1]):
        want = f"({size}, 2)" if size is not None else "(k, 2)"
        raise ShapeError(f"{name} must be {want} rows of (lower, upper) with lower <= upper "
                         f"(+-inf for none); got {b.tolist() if b.size < 20 else describe(b)}")
    return b


def _rates(name, value, size):
    if value is None:
        return None
    d = np.array(value, dtype=float).ravel()
    if size is not None and d.shape != (size,) or np.any(~(d > 0)):
        raise ShapeError(f"{name} must be {size if size is not None else 'r'} positive rates "
                         f"(input units per second, +inf for none); got {d.tolist()}")
    return d


@dataclass(frozen=True)
class Limits:
    """Box limits on the states and inputs and a limit on how fast the inputs change.

    Attributes:
        x_bounds: ``(n, 2)`` (lower, upper) per state, ``±inf`` for none; or None.
        u_bounds: ``(r, 2)`` (lower, upper) per input; or None.
        du_max: ``(r,)`` largest ``|u[k] - u[k-1]| / dt`` between consecutive held inputs
            (input units per second); ``u[-1]`` is the input before the run (0 at rest).
    """

    x_bounds: np.ndarray | None = None
    u_bounds: np.ndarray | None = None
    du_max: np.ndarray | None = None

    def __post_init__(self):
        object.__setattr__(self, "x_bounds", _box("x_bounds", self.x_bounds, None))
        object.__setattr__(self, "u_bounds", _box("u_bounds", self.u_bounds, None))
        object.__setattr__(self, "du_max", _rates("du_max", self.du_max, None))
        if self.u_bounds is not None and self.du_max is not None and \
                len(self.u_bounds) != len(self.du_max):
            raise ShapeError(f"u_bounds has {len(self.u_bounds)} inputs but du_max "
                             f"{len(self.du_max)}")

    @classmethod
    def named(cls, state_names: Sequence[str], input_names: Sequence[str], *,
              states: Mapping | None = None, inputs: Mapping | None = None,
              rates: Mapping | None = None) -> Limits:
        """Limits by variable name; a number ``a`` means ``(-a, a)``.

        Example: ``Limits.named(system.state_names, system.input_names, states={"s": 0.5},
        inputs={"u": 20}, rates={"u": 500})``: a ±0.5 m rail, ``|u| <= 20``, ``|du/dt| <= 500``.
        """
        def table(arg, given, names):
            unknown = sorted(set(given or {}) - set(names))
            if unknown:
                raise ParameterError(f"{arg} names unknown variables {unknown}; valid: "
                                     f"{list(names)}")
            out = np.tile([-np.inf, np.inf], (len(names), 1))
            for k, v in (given or {}).items():
                v = np.asarray(v, dtype=float)
                out[list(names).index(k)] = [-abs(float(v)), abs(float(v))] if v.ndim == 0 \
                    else v
            return out

        rate = None
        if rates:
            unknown = sorted(set(rates) - set(input_names))
            if unknown:
                raise ParameterError(f"rates names unknown inputs {unknown}; valid: "
                                     f"{list(input_names)}")
            rate = [float(rates.get(n, np.inf)) for n in input_names]
        return cls(x_bounds=table("states", states, state_names) if states else None,
                   u_bounds=table("inputs", inputs, input_names) if inputs else None,
                   du_max=rate)

    def sized(self, n: int, r: int):
        """``(x_lower, x_upper, u_lower, u_upper, du_max)`` arrays for ``n`` states and ``r``
        inputs, unlimited where not given; ShapeError if the limits are for other sizes."""
        xb = _box("limits.x_bounds", self.x_bounds, n) if self.x_bounds is not None else \
            np.tile([-np.inf, np.inf], (n, 1))
        ub = _box("limits.u_bounds", self.u_bounds, r) if self.u_bounds is not None else \
            np.tile([-np.inf, np.inf], (r, 1))
        du = _rates("limits.du_max", self.du_max, r) if self.du_max is not None else \
            np.full(r, np.inf)
        return xb[:, 0], xb[:, 1], ub[:, 0], ub[:, 1], du

    def saturate(self, u, u_prev, dt: float) -> np.ndarray:
        """``u`` ``(r,)`` clipped to the input bounds and to ``u_prev ± du_max dt`` (an
        actuator's limits); ``u_prev`` itself is within the bounds."""
        u = np.asarray(u, dtype=float).ravel()
        lo, hi = (-np.inf, np.inf) if self.u_bounds is None else self.u_bounds.T
        step = np.inf if self.du_max is None else self.du_max * dt
        u = np.clip(u, np.asarray(u_prev) - step, np.asarray(u_prev) + step)
        return np.clip(u, lo, hi)

    def check(self, run, *, u_initial=None, state_tol: float = STATE_TOLERANCE,
              rel_tol: float = 1e-9) -> dict:
        """Whether ``run`` (a :class:`~.replay.Run`) kept the limits.

        States are checked at every output sample (``run.x_dense``) with ``state_tol`` of
        slack, inputs and rates on the held inputs ``run.u`` (``u_initial`` before the first,
        default 0). Returns ``{"within_state_bounds", "within_input_bounds",
        "within_rate_limits", "respected", "max_state_excess", "max_input_excess",
        "max_rate_ratio"}`` (excess beyond the bound, in the variable's units; rate ratio:
        largest ``|du/dt| / du_max``).
        """
        n, r = run.x.shape[1], run.u.shape[1]
        xl, xu, ul, uu, du = self.sized(n, r)
        x = run.x_dense.reshape(-1, n)
        x_excess = float(np.max(np.maximum(x - xu, xl - x), initial=-np.inf))
        u_excess = float(np.max(np.maximum(run.u - uu, ul - run.u), initial=-np.inf))
        u0 = np.zeros(r) if u_initial is None else np.asarray(u_initial, dtype=float).ravel()
        rates = np.abs(np.diff(np.vstack([u0, run.u]), axis=0)) / (run.t[1] - run.t[0])
        ratio = float(np.max(rates / du, initial=0.0))
        out = {"within_state_bounds": bool(x_excess <= state_tol),
               "within_input_bounds": bool(u_excess <= rel_tol * max(1.0, np.max(np.abs(run.u)))),
               "within_rate_limits": bool(ratio <= 1 + 1e-6),
               "max_state_excess": max(x_excess, 0.0), "max_input_excess": max(u_excess, 0.0),
               "max_rate_ratio": ratio}
        out["respected"] = out["within_state_bounds"] and out["within_input_bounds"] \
            and out["within_rate_limits"]
        return out
