"""The smoothing of an energy fit chosen from the recording, judged by the error of H_m
against the energy of the exact states (known in simulation, unknown to the choice)."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.differentiation import SavitzkyGolay
from discrepancy.energy import choose_smoothing
from discrepancy.energy.smoothing import DEGREES, WINDOWS
from discrepancy.errors import DataError


@pytest.fixture(scope="module")
def encoder_swing():
    q, w = sp.symbols("q dq")
    rod = dc.systems.LagrangianSystem(0.4 * 0.35 ** 2 / 6 * w ** 2,
                                      -0.4 * 9.81 * 0.175 * sp.cos(q), ["q"],
                                      dissipation=1e-3 * w ** 2 / 2)
    t = np.arange(20001) / 1000
    x = rod.simulate([2.4, 0.0], t, rtol=1e-11, atol=1e-11)
    step = 2 * np.pi / 2048
    return rod, np.round(x[:, :1] / step) * step, t, x


def energy_error(rod, smoother, q, t, x) -> float:
    smooth, rate = smoother.smooth_and_differentiate(q, t)
    keep = slice(smoother.edge, len(t) - smoother.edge)
    return float(np.sqrt(np.mean((rod.energy(np.hstack([smooth, rate])[keep])
                                  - rod.energy(x[keep])) ** 2)))


def test_chosen_filter_errs_less_than_the_fixed_default_and_near_the_best(encoder_swing):
    rod, q, t, x = encoder_swing
    chosen = choose_smoothing(rod.energy, q, t)
    errors = {(w, d): energy_error(rod, SavitzkyGolay(window_length=w, polyorder=d), q, t, x)
              for w in WINDOWS for d in DEGREES}
    ours = errors[chosen.window_length, chosen.polyorder]
    assert ours < 0.6 * errors[31, 3]                # the former fixed default
    assert ours <= 2.0 * min(errors.values())


def test_too_short_a_record_is_refused(encoder_swing):
    rod, q, t, _ = encoder_swing
    with pytest.raises(DataError, match="too short"):
        choose_smoothing(rod.energy, q[:300], t[:300])
