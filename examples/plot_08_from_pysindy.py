"""
Coming from PySINDy
===================

The calls are PySINDy's: same constructor arguments, ``fit(x, t)``, ``print()``,
``coefficients()``, ``predict``, ``simulate``, the same column order, and with matched
settings the same coefficients. What changes is what you add: a prior model whose error is
learned, instead of the whole right-hand side, and defaults that need no tuning.

Both libraries, side by side, on the Lorenz system (PySINDy 2.x is installed by
``make docs``).
"""

import os
import platform
import time
import warnings

import matplotlib.pyplot as plt
import numpy as np
import pysindy as ps
from scipy.integrate import solve_ivp

import discrepancy as dc

warnings.filterwarnings("ignore", category=UserWarning, module="pysindy")


def lorenz(t, x, rho=28.0):
    return [10 * (x[1] - x[0]), x[0] * (rho - x[2]) - x[1], x[0] * x[1] - 8 / 3 * x[2]]


dt = 0.002
t = np.arange(0, 10, dt)
x = solve_ivp(lorenz, (0, 10), [-8, 8, 27], t_eval=t, rtol=1e-10, atol=1e-10).y.T

# %%
# The same model in both
# ----------------------
# PySINDy's defaults written out (finite differences, STLSQ with threshold 0.1): ``prior=None``
# makes the discrepancy model plain SINDy.

names = ["x", "y", "z"]
peer = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=2),
                optimizer=ps.STLSQ(threshold=0.1),
                differentiation_method=ps.FiniteDifference())
ours = dc.DiscrepancyModel(prior=None, feature_library=dc.PolynomialLibrary(2),
                           optimizer=dc.STLSQ(threshold=0.1),
                           differentiation_method=dc.FiniteDifference(), state_names=names)
peer.fit(x, t=dt, feature_names=names)
ours.fit(x, t=dt)
peer.print()
ours.print()

assert peer.get_feature_names() == ours.get_feature_names()
difference = np.max(np.abs(peer.coefficients() - ours.coefficients()))
print(f"largest coefficient difference: {difference:.1e}")
assert difference < 1e-8
assert np.allclose(peer.predict(x), ours.predict(x), rtol=1e-8, atol=1e-8)

# %%
# What a prior adds
# -----------------
# Suppose you know Lorenz's equations but not ``ρ``: your model says 20. Give it as the
# prior, and only the error is learned: one term, ``8 x``, instead of seven.

def f_m(x, u=None):
    return np.array(lorenz(None, x.T, rho=20.0)).T


hybrid = dc.DiscrepancyModel(prior=f_m, feature_library=dc.PolynomialLibrary(2),
                             state_names=names).fit(x, t=dt)
hybrid.print()
learned = {name: c for name, c in zip(hybrid.get_feature_names(), hybrid.coefficients()[1])
           if c != 0}
assert list(learned) == ["x"] and abs(learned["x"] - 8) < 1e-3
assert hybrid.complexity == 1

# %%
# Speed
# -----
# The same fit on more data; CPU time of both, measured while this page was built (the
# ratio, not the seconds, is what carries to another machine; ``benchmarks/`` has more).

x_long = solve_ivp(lorenz, (0, 100), [-8, 8, 27], t_eval=np.arange(0, 100, dt),
                   rtol=1e-9, atol=1e-9).y.T
seconds = {}
for name, model in (("PySINDy", peer), ("discrepancy", ours)):
    runs = []
    for _ in range(3):
        start = time.process_time()
        model.fit(x_long, t=dt, **({"feature_names": names} if model is peer else {}))
        runs.append(time.process_time() - start)
    seconds[name] = min(runs)
ratio = seconds["PySINDy"] / seconds["discrepancy"]
print(f"{len(x_long):,} samples, degree-2 library, best of 3: PySINDy "
      f"{seconds['PySINDy']:.3f} s, discrepancy {seconds['discrepancy']:.3f} s of CPU "
      f"({ratio:.1f}x faster); measured while this page was built, on {os.cpu_count()} cores "
      f"of a {platform.machine()} machine, load average {os.getloadavg()[0]:.1f}")
assert ratio > 1
assert np.max(np.abs(peer.coefficients() - ours.coefficients())) < 1e-8

fig, ax = plt.subplots(figsize=(5, 3))
ax.bar(list(seconds), list(seconds.values()), color=["C1", "C0"])
ax.set(ylabel="CPU seconds", title=f"fit of {len(x_long):,} samples")
fig.tight_layout()
