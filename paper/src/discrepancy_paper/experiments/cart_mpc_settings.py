"""Settings of ``cart-mpc`` shared by the run and its report (the rig's limits, sensor noise,
what the encoders measure) and the score of a learned model against the exact discrepancy."""
from __future__ import annotations

import numpy as np

RAIL, U_MAX, DU_MAX = 0.5, 20.0, 500.0   # m, m/s², m/s³
#: measurement noise std: angles (rad), cart (m), angle rates (rad/s), cart speed (m/s)
NOISE = (1e-3, 1e-3, 5e-4, 2e-2, 2e-2, 5e-3)
X_HANG = np.array([np.pi, np.pi, 0.0, 0.0, 0.0, 0.0])
#: output feedback: the encoders measure the angles and the cart, not the rates
MEASURED = ("phi1", "phi2", "s")
KINEMATICS = {"phi1": "dphi1", "phi2": "dphi2", "s": "ds"}
#: belief about the start (the perturbed cases start within 0.02 rad of hanging, at rest)
INITIAL_STD = (0.02, 0.02, 1e-3, 0.01, 0.01, 0.01)
MAX_ATTEMPTS = 4                          # MPC attempts on a perturbed system, re-id between


#: the exact discrepancy of the paper's flawed model: [-sin(phi1), 0, 0, 0, 0, 0.05 u]
EXACT_TERMS = {"phi1": {"sin(phi1)": -1.0}, "ds": {"u": 0.05}}


def identification(model, exact=None) -> dict:
    """The learned terms against the exact discrepancy: every term, how many are spurious
    (not in the exact discrepancy) or missing, and the exact terms' learned coefficients."""
    exact = EXACT_TERMS if exact is None else exact
    names = model.get_feature_names()
    terms = {s: {n: float(c) for n, c in zip(names, row, strict=True) if c != 0}
             for s, row in zip(model.state_names_, model.coefficients(), strict=True)}
    wanted = {(s, t) for s, ts in exact.items() for t in ts}
    found = {(s, t) for s, ts in terms.items() for t in ts}
    return {"identified_terms": terms, "active_terms": model.complexity,
            "spurious_terms": len(found - wanted), "missing_terms": len(wanted - found),
            "exact_terms_learned": {f"{t} in ({s})'": terms.get(s, {}).get(t, 0.0)
                                    for s, t in sorted(wanted)},
            "exact_terms": exact}
