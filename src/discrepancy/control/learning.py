"""Learning between attempts: attempt, record, update the discrepancy, plan again.

A fit is a function of Gram statistics, which are sums over samples
(:class:`~discrepancy.fitting.setup.FitSetup`), so learning from one more attempt is adding
that attempt's statistics to the running sum and refitting: the model after ``k`` attempts
is exactly the model fitted to all ``k`` logs at once, without keeping the logs.
"""
from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..constraints import Integral, Interval, check_argument
from ..data.trajectory import as_trajectories
from ..errors import ParameterError, describe


class DiscrepancyUpdater:
    """Accumulates the logs of successive attempts and refits the discrepancy after each.

    Args:
        model: an unfitted :class:`~discrepancy.DiscrepancyModel` (prior, library, optimizer,
            differentiation); it is copied, never changed. A differentiation method chosen
            from the data (the default) is chosen on the first log and then kept, so every
            log's statistics are made the same way.

    Attributes:
        setup_: the frozen :class:`~discrepancy.fitting.setup.FitSetup` (after the first
            :meth:`update`).
        statistics_: the summed Gram statistics.
        models_: the model after each update.
    """

    def __init__(self, model):
        self.model = model

    def update(self, x, t, *, u=None):
        """Add one attempt's log and refit; returns the new fitted model (a copy).

        Args:
            x: states ``(m, n)`` or a list of trajectories (e.g. one per hold interval, as
                :meth:`~.closed_loop.ClosedLoopRun.measured_trajectories` gives them).
            t: time step or times, or a list per trajectory; u: inputs likewise.
        """

        if not hasattr(self.model, "make_setup"):
            raise ParameterError(f"model must be an unfitted DiscrepancyModel; got "
                                 f"{describe(self.model)}")
        trajectories = as_trajectories(x, t, u, None, None)
        if not hasattr(self, "setup_"):
            first = trajectories[0]
            self.setup_ = self.model.make_setup(
                first.x.shape[1], 0 if first.u is None else first.u.shape[1],
                sample=trajectories)
            self.statistics_ = self.setup_.new_statistics()
            self.models_ = []
        for trajectory in trajectories:
            self.setup_.statistics(trajectory, into=self.statistics_)
        fitted = copy.deepcopy(self.model).fit_statistics(self.statistics_, self.setup_)
        self.models_.append(fitted)
        return fitted


@dataclass(frozen=True)
class Attempt:
    """One attempt of :func:`learn_by_attempts`.

    Attributes:
        number: 1, 2, ...; success: what the attempt function judged.
        model: the model the attempt planned and controlled with (the first model, then
            a fitted hybrid model).
        result: whatever the attempt function returned besides success (e.g. its plan and
            closed-loop run).
        learned: the model fitted after this attempt's log was added (None after a
            success: nothing more is learned).
    """

    number: int
    success: bool
    model: object
    result: object
    learned: object = None

    def coefficients(self) -> dict:
        """``{state: {term: coefficient}}`` of the learned discrepancy (nonzero terms)."""
        if self.learned is None:
            return {}
        names = self.learned.get_feature_names()
        return {s: {n: float(c) for n, c in zip(names, row, strict=True) if c != 0}
                for s, row in zip(self.learned.state_names_, self.learned.coefficients(),
                                  strict=True)}


def learn_by_attempts(attempt: Callable, updater: DiscrepancyUpdater, *, first,
                      max_attempts: int = 5) -> list[Attempt]:
    """Attempt, record, learn, attempt again, until an attempt succeeds.

    Args:
        attempt: ``attempt(model) -> (success, log, result)``: plan with ``model`` and run
            the controller on the system; ``log`` is ``(x, t, u)`` as
            :meth:`DiscrepancyUpdater.update` takes them (what was recorded), ``result``
            anything to keep.
        updater: accumulates the logs and refits.
        first: the model of the first attempt (e.g. the prior's equations).
        max_attempts: give up after this many.

    Returns:
        the attempts in order; the last succeeded unless ``max_attempts`` ran out.
    """
    check_argument("max_attempts", max_attempts, Interval(Integral, 1))
    max_attempts = int(max_attempts)
    if not callable(attempt):
        raise ParameterError(f"attempt must be a callable attempt(model) -> (success, "
                             f"log, result); got {describe(attempt)}")
    attempts, model = [], first
    for number in range(1, max_attempts + 1):
        success, log, result = attempt(model)
        learned = None
        if not success:
            x, t, u = log
            learned = updater.update(x, t, u=u)
        attempts.append(Attempt(number, bool(success), model, result, learned))
        if success:
            break
        model = learned
    return attempts


def coefficient_table(attempts: list[Attempt]) -> list[dict]:
    """The learned coefficients after each failed attempt, for reports (JSON-ready)."""
    return [{"attempt": a.number, "success": a.success,
             "coefficients_after": a.coefficients(),
             "active_terms_after": int(np.sum(a.learned.coefficients() != 0))
             if a.learned is not None else None} for a in attempts]
