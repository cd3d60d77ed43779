"""How far forecasts are scored: where the reference model's forecasts stop meaning
anything.

Two limits, both read from the reference model's own forecasts from the windows (the prior,
or the equation-error choice when it forecasts better): its RMS scaled error reaching one
standard deviation of the states (saturation: as bad as forecasting their mean), and, per
window, its sensitivity to the initial state reaching :data:`GAIN_LIMIT` (a chaotic or
unstable stretch, where a forecast depends more on its start than on the model). A stable
system the reference forecasts well is scored over the whole window.
"""
from __future__ import annotations

import numpy as np

from .forecast import Origins, Scores

#: the prior's RMS scaled forecast error at which its forecasts count as saturated
SATURATION = 1.0
#: shortest horizon (steps), when the windows are that long
MIN_STEPS = 8


#: a window's forecasts are scored until the prior's sensitivity to its initial state
#: (RMS of the scaled Jacobian, 1 at the origin) reaches this: further on, a chaotic or
#: unstable forecast depends more on its start than on the model
GAIN_LIMIT = 20.0


def sensitive_leads(origins: Origins, prior: Scores) -> Origins:
    """The origins with each window's samples beyond the lead where the prior's sensitivity
    reaches :data:`GAIN_LIMIT` dropped (NaN), so every candidate is scored on the same
    leads."""
    truth = origins.truth.copy()
    for w, gain in enumerate(prior.gain):
        over = np.flatnonzero(gain >= GAIN_LIMIT)
        if over.size:
            truth[w, max(int(over[0]), MIN_STEPS + 1):] = np.nan
    return Origins(origins.x0, truth, origins.h, origins.stages, origins.fold,
                   origins.scale, origins.centre, origins.stride)


def choose_steps(prior_lead: np.ndarray) -> int:
    """Steps to forecast: the first lead at which the prior's RMS scaled error (from the
    origins as given) over the windows reaches :data:`SATURATION` (one standard deviation
    of the states: as bad as forecasting their mean), at least :data:`MIN_STEPS`, at most
    the windows' length. Further on, a chaotic or unstable system's forecasts say nothing;
    on one the prior forecasts well, the horizon is as long as the windows."""
    seen = np.isfinite(prior_lead[:, 1:])
    count = seen.sum(axis=0)
    longest = int(np.sum(count > 0))
    total = np.where(seen, prior_lead[:, 1:], 0.0).sum(axis=0)[:longest]
    rms = np.sqrt(total / count[:longest])
    over = np.flatnonzero(rms >= SATURATION)
    steps = longest if not over.size else int(over[0]) + 1
    return int(min(longest, max(steps, MIN_STEPS)))
