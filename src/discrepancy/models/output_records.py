"""The data and options of an output-error fit, checked before any work.

Records (times, outputs, inputs at the RK4 stage times), the number of states, initial
guesses and bounds, the split into training and held-out samples, and the size-like
options (``substeps``, ``segment_length``, ``n_jobs``, ``max_terms``, ``holdout``,
``tolerance``, ``jit``): each is refused with a :mod:`discrepancy.errors` exception naming
it before anything is built or allocated. ``substeps`` has a cost bound: the input at the
stage times takes ``(m - 1) (2 substeps + 1) r`` numbers, so ``substeps=10**5`` on 25,000
samples is refused with the 40 GB it would need instead of running out of memory.
"""
from __future__ import annotations

import numpy as np

from ..data.trajectory import as_trajectories
from ..errors import DataError, ParameterError, ShapeError
from ..resources import check_memory, n_bytes
from .inputs import check_hold, stage_inputs

#: most RK4 steps per sample interval (as ``simulate`` allows)
MAX_SUBSTEPS = 10_000


class Record:
    """One trajectory: times, outputs ``(m, k)``, stage inputs and step lengths."""

    def __init__(self, trajectory, n_inputs, substeps, hold):
        self.t, self.y, self.u = trajectory.t, trajectory.x, trajectory.u
        self.h = np.diff(self.t)
        self.stages = None if not n_inputs else stage_inputs(self.u, self.t, n_inputs,
                                                              substeps, hold=hold)
        self.m = len(self.t)


def _is_int(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def check_substeps(substeps) -> int:
    """``substeps`` as an int, or :class:`~discrepancy.errors.ParameterError` unless it is a
    positive integer (RK4 steps per sample interval)."""
    if not _is_int(substeps) or substeps < 1:
        raise ParameterError(f"substeps must be a positive integer (RK4 steps per sample "
                             f"interval); got {substeps!r}")
    return int(substeps)


def records_of(y, t, u, substeps, hold) -> tuple[list[Record], int]:
    """The records of ``y``, ``t``, ``u`` with their stage inputs, and the input count;
    ``substeps`` is checked against the memory its stage inputs would take first."""
    substeps, hold = check_substeps(substeps), check_hold(hold)
    trajectories = as_trajectories(y, t, u, x_name="y")
    r = 0 if trajectories[0].u is None else trajectories[0].u.shape[1]
    steps = sum(len(tr.t) - 1 for tr in trajectories)
    check_memory(f"the input at the RK4 stage times ({steps} steps x (2 substeps + 1) = "
                 f"{2 * substeps + 1} stages x {r} inputs, substeps={substeps})",
                 n_bytes((steps, 2 * substeps + 1, r)),
                 "Use fewer substeps (4 is accurate for most sampled systems)")
    if substeps > MAX_SUBSTEPS:
        raise ParameterError(f"substeps must be at most {MAX_SUBSTEPS} (RK4 steps per "
                             f"sample interval); got {substeps}")
    return [Record(tr, r, substeps, hold) for tr in trajectories], r


def check_options(*, max_terms=None, holdout=0.25, tolerance=None, segment_length="auto",
                  n_jobs=1, jit="auto"):
    """Refuse, with a :class:`~discrepancy.errors.ParameterError` naming the option, a
    ``max_terms`` that is not a positive integer or ``None``, a ``holdout`` outside
    ``[0.05, 0.5]``, a ``tolerance`` outside ``[0, 1]`` (or ``None``), a ``segment_length``
    other than ``"auto"`` or a positive integer (samples), an ``n_jobs`` other than ``None``
    or a positive integer, and a ``jit`` other than ``True``, ``False`` or ``"auto"``."""
    if max_terms is not None and (not _is_int(max_terms) or max_terms < 1):
        raise ParameterError(f"max_terms must be a positive integer or None; got {max_terms!r}")
    if not isinstance(holdout, (int, float)) or isinstance(holdout, bool) or \
            not 0.05 <= holdout <= 0.5:
        raise ParameterError(f"holdout must be a fraction in [0.05, 0.5]; got {holdout!r}")
    if tolerance is not None and (not isinstance(tolerance, (int, float))
                                  or isinstance(tolerance, bool) or not 0 <= tolerance <= 1):
        raise ParameterError(f"tolerance must be None (one standard error) or a number in "
                             f"[0, 1]; got {tolerance!r}")
    if segment_length != "auto" and (not _is_int(segment_length) or segment_length < 1):
        raise ParameterError(f"segment_length must be 'auto' or a positive integer (samples "
                             f"per shooting segment); got {segment_length!r}")
    if n_jobs is not None and (not _is_int(n_jobs) or n_jobs < 1):
        raise ParameterError(f"n_jobs must be None or a positive integer (threads that run "
                             f"the shooting segments); got {n_jobs!r}")
    if jit not in (True, False, "auto"):
        raise ParameterError(f"jit must be True, False or 'auto'; got {jit!r}")


def n_states_of(model, x0) -> int:
    """The number of states ``n``: from ``model.state_names``, else the length of a prior given
    as a list of expressions, else the last axis of ``x0``; a
    :class:`~discrepancy.errors.ParameterError` when none of them says."""
    if model.state_names is not None:
        return 1 if isinstance(model.state_names, str) else len(model.state_names)
    if isinstance(model.prior, (list, tuple)):
        return len(model.prior)
    if x0 is not None:
        return int(np.shape(x0)[-1])
    raise ParameterError("the number of states is unknown: give state_names, a prior as a "
                         "list of sympy expressions, or x0")


def given_states(x0, n_records: int, n: int) -> np.ndarray:
    """``(records, n)`` from a given ``x0`` (one row for all records, or one per record)."""
    x0s = np.asarray(x0, dtype=float).reshape(-1, n) if np.size(x0) % n == 0 else None
    if x0s is None or len(x0s) not in (1, n_records) or not np.all(np.isfinite(x0s)):
        raise ShapeError(f"x0 must be {n} finite numbers (one per state), or one such row per "
                         f"trajectory; got shape {np.shape(x0)}")
    return np.repeat(x0s, n_records, axis=0) if len(x0s) == 1 else x0s


def split_rows(records, holdout) -> tuple[list, list]:
    """Training rows (the first part of each record) and held-out rows (the rest)."""
    train, test = [], []
    for r in records:
        cut = int(round(r.m * (1 - holdout)))
        if cut < 2 or r.m - cut < 2:
            raise DataError(f"a record of {r.m} samples is too short to hold out its last "
                            f"{holdout:.0%} for choosing terms; give threshold= a number or "
                            "longer records")
        w = np.zeros(r.m, bool)
        w[:cut] = True
        train.append(w)
        test.append(~w)
    return train, test


def x0_bounds(bounds, n):
    """``(lower (n,), upper (n,))`` from ``None`` or a pair of numbers or sequences."""
    if bounds is None:
        return np.full(n, -np.inf), np.full(n, np.inf)
    try:
        lower, upper = (np.broadcast_to(np.asarray(b, dtype=float), (n,)).copy()
                        for b in bounds)
    except (TypeError, ValueError):
        raise ParameterError(f"x0_bounds must be (lower, upper), each a number or {n} "
                             f"numbers; got {bounds!r:.80}") from None
    if np.any(np.isnan(lower)) or np.any(np.isnan(upper)) or np.any(lower >= upper):
        raise ParameterError(f"x0_bounds must have lower < upper for every state; got "
                             f"{lower} and {upper}")
    return lower, upper


def check_identifiable(fit, structure):
    """Every state must be able to move a measured output, through the prior or a term of
    ``structure`` ``(n, p)`` (a chain of dependencies in the model's structure); one that
    cannot is unidentifiable and is refused by name."""
    influences = fit.shooting.influences(structure)
    reached = set(fit.out_map.measured)
    grew = True
    while grew:
        new = {i for j in reached for i in np.flatnonzero(influences[j])} - reached
        reached |= new
        grew = bool(new)
    dead = [name for i, name in enumerate(fit.setup.state_names) if i not in reached]
    if dead:
        raise DataError(f"state(s) {dead} cannot influence the measured outputs "
                        f"{fit.out_map.names} through the prior or any allowed term, so they "
                        "cannot be estimated (unidentifiable): measure them or a quantity "
                        "they affect, or leave them out of the model")
