"""
Uncertainty and forecast bands
==============================

A learned coefficient is an estimate from noisy data: how sure is it, and how far off can a
forecast of the hybrid model be? ``model.bootstrap`` refits the model on resampled data (a
block bootstrap of the fit's own statistics, so 200 resamples cost 200 small solves), each
resample choosing its terms again, and gives every coefficient a distribution. The resampled
models give bands around predictions and simulations.

Van der Pol again (real ``α = 0.5``, model ``α = 0.1``), noise 0.05 on both states.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import discrepancy as dc
from discrepancy.plots.uncertainty import uncertainty_figure


def van_der_pol(t, x):
    return [x[1], 0.5 * (1 - x[0] ** 2) * x[1] - x[0]]


def f_m(x, u=None):
    return np.c_[x[:, 1], 0.1 * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]]


t = np.arange(0, 25, 0.01)
clean = solve_ivp(van_der_pol, (0, 25), [0.5, 0.0], t_eval=t, rtol=1e-10, atol=1e-10).y.T
x = clean + 0.05 * np.random.default_rng(3).standard_normal(clean.shape)
model = dc.DiscrepancyModel(prior=f_m, feature_library=dc.PolynomialLibrary(3)).fit(x, t=0.01)

# %%
# The uncertainty of every term
# -----------------------------
unc = model.bootstrap(x, t=0.01, n_resamples=200, seed=0)
print(unc)
model.print(uncertainty=unc)

truth = {("x2", "x2"): 0.4, ("x2", "x1^2 x2"): -0.4}
low, high = unc.interval(0.95)
names = model.get_feature_names()
for (state, term), value in truth.items():
    i, j = model.state_names_.index(state), names.index(term)
    print(f"{term}: 95 % interval [{low[i, j]:.4f}, {high[i, j]:.4f}], truth {value}, "
          f"selected in {unc.inclusion_probability[i, j]:.0%} of resamples")
    assert low[i, j] <= value <= high[i, j]
    assert unc.inclusion_probability[i, j] == 1.0

fig = uncertainty_figure(unc, truth=truth)

# %%
# A forecast band
# ---------------
# Simulate the hybrid model from a state it was not fitted on, with 50 of the resampled
# models. The band holds the coefficients' uncertainty (not the measurement noise): how much
# the forecast could differ had the experiment been repeated.

x0, t_new = [-0.2, -0.3], np.arange(0, 25, 0.01)
forecast = model.simulate(x0, t_new)
band_low, band_high = model.simulate_interval(x0, t_new, uncertainty=unc, n_draws=50)
real = solve_ivp(van_der_pol, (0, 25), x0, t_eval=t_new, rtol=1e-10, atol=1e-10).y.T

inside = np.mean((real[:, 0] >= band_low[:, 0]) & (real[:, 0] <= band_high[:, 0]))
width = np.max(band_high[:, 0] - band_low[:, 0])
print(f"real x1 inside the 95 % band at {inside:.0%} of the samples; widest band {width:.3f}")
assert inside > 0.9

fig, ax = plt.subplots(figsize=(8, 3.2))
ax.fill_between(t_new, band_low[:, 0], band_high[:, 0], color="C0", alpha=0.3,
                label="95 % band (resampled models)")
ax.plot(t_new, real[:, 0], "k", lw=1.2, label="real system")
ax.plot(t_new, forecast[:, 0], "C0--", lw=1, label="hybrid model")
ax.set(xlabel="time", ylabel="x1", xlim=(10, 25))
ax.legend(loc="lower left")
fig.tight_layout()
