"""
Energy lost to friction, for your own mechanical system
=======================================================

Write the kinetic and potential energy of your rig, record its angles while it swings
freely, and the library finds which friction laws take the energy away, with their
coefficients. Here the "rig" is a rod pendulum (0.5 kg, 0.4 m) on a bearing with viscous
friction (2e-3 N m s) and dry (Coulomb) friction (4e-3 N m), read by a 5000-count encoder
at 1 kHz for 24 s. Nothing but the angles is measured.
"""

import matplotlib.pyplot as plt
import numpy as np
import sympy as sp

import discrepancy as dc

m, l, g = 0.5, 0.4, 9.81
q, dq = sp.symbols("q dq")
T = m * l**2 / 6 * dq**2                  # kinetic energy (J) of a rod about its end
V = -m * g * l / 2 * sp.cos(q)            # potential energy (J)

# %%
# The recording. The "real" pendulum is the same system with a Rayleigh dissipation
# function ``D = ½ c dq² + F |dq|`` (the ``sqrt`` smooths the kink at rest); its angles go
# through an encoder's quantisation.

real = dc.systems.LagrangianSystem(T, V, ["q"],
                                   dissipation=1e-3 * dq**2 + 4e-3 * sp.sqrt(dq**2 + 1e-6))
t = np.arange(24001) / 1000
count = 2 * np.pi / 5000
angles = np.round(real.simulate([2.6, 0.0], t)[:, :1] / count) * count

# %%
# Learn the friction
# ------------------
# The model of the rig knows only ``T`` and ``V``. :func:`~discrepancy.energy.blind_fit`
# compares fitting procedures (friction libraries, fit windows, term selection) by
# forecasting the energy loss from five origins inside the first 80 % of the recording and
# never reads the last 20 %: those are kept to check the forecast.

rig = dc.systems.LagrangianSystem(T, V, ["q"])
split = 19200
blind = dc.energy.blind_fit(dc.DissipationDiscrepancy.from_system(rig), angles, t,
                            split=split, progress=False)
print("chosen procedure:", blind.chosen)
print(blind.model.equation())

laws = dict(zip((term.name for term in blind.model.terms_), blind.model.coef_))
assert set(laws) == {"viscous joint 1", "Coulomb joint 1"}
assert abs(laws["viscous joint 1"] / 2e-3 - 1) < 0.02       # within 2 % of the truth
assert abs(laws["Coulomb joint 1"] / 4e-3 - 1) < 0.02

# %%
# Forecast the energy loss of the unseen part
# -------------------------------------------
# From the start of the held-out 20 %, the learned laws forecast the energy the swing loses;
# the band is the largest error the chosen procedure made at each lead time when it
# forecast from inside the training part (its form error, not only noise).

held_out = slice(split, None)
forecast = blind.model.predict(angles[held_out], t[held_out])
# the samples within the smoother's half window of either end are dropped: these are the times
_, t_forecast = blind.model.states(angles[held_out], t[held_out])
low, high = blind.forecast_band(forecast, t_forecast)
true_energy = rig.energy(real.simulate([2.6, 0.0], t))
energy = np.interp(t_forecast, t, true_energy)
lost = energy[0] - energy                                     # true loss (J) since the origin

end_error = abs(forecast[-1] - lost[-1]) / lost[-1]
print(f"energy lost in the last {t_forecast[-1] - t_forecast[0]:.1f} s: "
      f"true {lost[-1] * 1e3:.2f} mJ, forecast {forecast[-1] * 1e3:.2f} mJ ({end_error:.1%} off)")
assert end_error < 0.05

fig, ax = plt.subplots(figsize=(8, 3.2))
ax.fill_between(t_forecast, 1e3 * low, 1e3 * high, color="C0", alpha=0.25,
                label="forecast band")
ax.plot(t_forecast, 1e3 * lost, "k", lw=2, label="true loss")
ax.plot(t_forecast, 1e3 * forecast, "C0--", label="forecast (learned laws)")
ax.set(xlabel="time (s)", ylabel="energy lost since the origin (mJ)")
ax.legend(loc="upper left")
fig.tight_layout()
