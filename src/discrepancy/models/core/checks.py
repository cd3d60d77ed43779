"""Checks of what is given to a fitted model: data with the columns it was fitted on, lists
of trajectories, and learned terms that must be finite where they are evaluated."""
from __future__ import annotations

import numpy as np

from ...data.trajectory import Trajectory, as_trajectories
from ...errors import ShapeError, describe
from ...fitting.accumulate import Names, not_finite


def model_data(model, x, t=None, u=None, x_dot=None, sample_weight=None) -> list[Trajectory]:
    """Validated trajectories with the columns ``model`` was fitted on (for score and
    bootstrap): ShapeError naming ``x`` or ``u`` before any work otherwise."""
    model.check_is_fitted()
    trajectories = as_trajectories(x, t, u, x_dot, sample_weight)
    first = trajectories[0]
    if first.x.shape[1] != model.n_states_:
        raise ShapeError(f"x must have {model.n_states_} columns (the model's states "
                         f"{model.state_names_}); got shape {first.x.shape}")
    r = 0 if first.u is None else first.u.shape[1]
    if r != model.n_inputs_:
        raise ShapeError(f"u must have {model.n_inputs_} columns (the model's inputs "
                         f"{model.input_names_}); got "
                         f"{'none' if first.u is None else first.u.shape}")
    return trajectories


def checked_discrepancy(model, z: np.ndarray) -> np.ndarray:
    """``g(z)`` of a fitted model, or FeatureError naming the first active term that is not
    finite there (its row and the variables)."""
    with np.errstate(all="ignore"):
        g = model._g(z)
    if not np.all(np.isfinite(g)):
        active = np.flatnonzero(np.any(model.coef_ != 0, axis=0))
        theta = np.column_stack(model._active_terms(z))
        names = model.get_feature_names()
        raise not_finite(theta.T, z, 0, len(active), Names([names[j] for j in active],
                                                           model.variable_names_))
    return g


def pairs(x: list, u):
    """``(x_i, u_i)`` of a list of trajectories (``u`` a matching list or None)."""
    if any(np.ndim(xi) == 0 for xi in x):
        raise ShapeError("x is a list holding numbers; a list means one array per trajectory: "
                         "pass one trajectory as a 2-D array, np.array(x), of shape (samples, "
                         "states)")
    if u is None:
        return [(xi, None) for xi in x]
    if not isinstance(u, (list, tuple)) or len(u) != len(x):
        raise ShapeError(f"u must be a list of {len(x)} arrays like x; got {describe(u)}")
    return list(zip(x, u, strict=True))
