"""Learning between attempts: an update is a sum of Gram statistics, the loop stops at the
first success, and the learned terms are the exact discrepancy (derived by sympy)."""
import numpy as np
import pytest
import sympy as sp

import discrepancy as dc
from discrepancy.control import DiscrepancyUpdater, closed_loop, learn_by_attempts
from discrepancy.control.learning import coefficient_table
from discrepancy.errors import ParameterError
from discrepancy.symbolic import symbol
from discrepancy.systems import PendulumOnCart, PendulumOnCartParameters

SYSTEM = PendulumOnCart(PendulumOnCartParameters(k=0.01))


def template():
    trig = dc.FourierLibrary(n_frequencies=1, variables=["phi"])
    u = dc.PolynomialLibrary(degree=1, include_bias=False, variables=["u"])
    library = dc.PolynomialLibrary(degree=1, variables=list(SYSTEM.state_names)) + trig + u \
        + trig * u
    return dc.DiscrepancyModel(prior=SYSTEM.flawed_equations()[2], feature_library=library,
                               optimizer=dc.STLSQ(threshold=1e-3),
                               differentiation_method=dc.SavitzkyGolay(41, 7, smooth=False),
                               state_names=list(SYSTEM.state_names), input_names=["u"])


def log(seed, steps=150):
    """A noise-free 0.5 ms log of the true system (scipy) driven by a random held input."""
    rng = np.random.default_rng(seed)
    inputs = rng.uniform(-8, 8, steps)
    run = closed_loop(SYSTEM.rhs, lambda k, x: inputs[k:k + 1], [np.pi - 0.3, 0, 0, 0],
                      dt=0.02, steps=steps, samples=40)
    return run.measured_trajectories()


def exact():
    """``{state: {term name: coefficient}}`` of the exact discrepancy, from sympy."""
    phi, dphi, u = symbol("phi"), symbol("dphi"), symbol("u")
    g = SYSTEM.discrepancy_equations()
    return {"dphi": {"dphi": float(g[2].coeff(dphi)), "cos(phi) u": float(
        g[2].coeff(u).coeff(sp.cos(phi)))}, "ds": {"u": float(g[3].coeff(u))}}


def test_an_update_adds_statistics_so_two_updates_equal_one_fit_on_both_logs():
    (x1, t1, u1), (x2, t2, u2) = log(1), log(2)   # 6150 rows each: same fold set-up
    updater = DiscrepancyUpdater(template())
    first = updater.update(x1, t1, u=u1)
    second = updater.update(x2, t2, u=u2)
    both = template().fit(x1 + x2, t=t1 + t2, u=u1 + u2)
    np.testing.assert_allclose(second.coefficients(), both.coefficients(), rtol=1e-10,
                               atol=1e-12)
    assert updater.statistics_.count == 2 * 150 * 41
    assert updater.models_ == [first, second] and first is not second
    names = second.get_feature_names()
    for state, terms in exact().items():
        row = second.coefficients()[SYSTEM.state_names.index(state)]
        assert {n for n, c in zip(names, row, strict=True) if c} == set(terms)
        for term, value in terms.items():
            assert row[names.index(term)] == pytest.approx(value, rel=1e-4)


def test_attempts_stop_at_the_first_success_and_each_uses_the_last_learned_model():
    logs = [log(3), log(4), log(5)]
    seen = []

    def attempt(model):
        seen.append(model)
        k = len(seen)
        return k == 3, logs[k - 1], {"k": k}

    updater = DiscrepancyUpdater(template())
    attempts = learn_by_attempts(attempt, updater, first="prior", max_attempts=5)
    assert [a.success for a in attempts] == [False, False, True]
    assert seen[0] == "prior" and seen[1] is attempts[0].learned and \
        seen[2] is attempts[1].learned and attempts[2].learned is None
    table = coefficient_table(attempts)
    assert [r["attempt"] for r in table] == [1, 2, 3] and table[2]["coefficients_after"] == {}
    assert table[1]["coefficients_after"]["ds"]["u"] == pytest.approx(-0.5, rel=1e-4)
    with pytest.raises(ParameterError, match="max_attempts"):
        learn_by_attempts(attempt, updater, first=None, max_attempts=0)
    with pytest.raises(ParameterError, match="unfitted DiscrepancyModel"):
        DiscrepancyUpdater("model").update(*logs[0][:2], u=logs[0][2])
