"""
A first discrepancy model
=========================

You have a model that is almost right and measurements of the real system. Here the real
system is the Van der Pol oscillator with damping ``α = 0.5``,

.. math:: \\dot x_1 = x_2, \\qquad \\dot x_2 = α (1 - x_1^2) x_2 - x_1,

and our model of it believes ``α = 0.1`` (the paper's first example). The library learns the
sparse correction ``g`` so that ``f_m + g`` is the real system, and writes it as an equation.
"""

import matplotlib.pyplot as plt
import numpy as np
from scipy.integrate import solve_ivp

import discrepancy as dc


def van_der_pol(alpha):
    return lambda t, x: [x[1], alpha * (1 - x[0] ** 2) * x[1] - x[0]]


# Measurements of the real system (α = 0.5) from x0 = (0.5, 0), 25 time units sampled
# every 0.01, as in the paper
t = np.arange(0, 25, 0.01)
x = solve_ivp(van_der_pol(0.5), (0, 25), [0.5, 0.0], t_eval=t, rtol=1e-10, atol=1e-10).y.T


def f_m(x, u=None):
    """Our model, α = 0.1: x (m, 2) -> dx/dt (m, 2)."""
    return np.c_[x[:, 1], 0.1 * (1 - x[:, 0] ** 2) * x[:, 1] - x[:, 0]]


# %%
# Fit the discrepancy
# -------------------
# Candidate terms: polynomials of the states up to degree 3. Nothing else is set: the
# derivative's smoothing and the sparsity threshold are chosen from the data.

model = dc.DiscrepancyModel(prior=f_m, feature_library=dc.PolynomialLibrary(degree=3))
model.fit(x, t=0.01)
model.print()

# %%
# The learned correction is the error of the model, ``(0.5 - 0.1) (1 - x1²) x2``, and
# nothing else:

learned = {name: c for name, c in zip(model.get_feature_names(), model.coefficients()[1])
           if c != 0}
assert not model.coefficients()[0].any()                     # no correction of x1' = x2
assert set(learned) == {"x2", "x1^2 x2"}
assert abs(learned["x2"] - 0.4) < 1e-3 and abs(learned["x1^2 x2"] + 0.4) < 1e-3

# %%
# Simulate from a new initial state
# ---------------------------------
# The hybrid model ``f_m + g`` follows the real system from a state it was not fitted on;
# the model alone does not.

t_new = np.arange(0, 25, 0.01)
x0 = [-0.2, -0.3]
truth = solve_ivp(van_der_pol(0.5), (0, 25), x0, t_eval=t_new, rtol=1e-10, atol=1e-10).y.T
hybrid = model.simulate(x0, t_new)
prior_alone = solve_ivp(van_der_pol(0.1), (0, 25), x0, t_eval=t_new, rtol=1e-10).y.T

error = np.linalg.norm(hybrid - truth) / np.linalg.norm(truth)
print(f"hybrid model: relative error {error:.2%} over 25 time units")
assert error < 0.01

fig, ax = plt.subplots(figsize=(8, 3.2))
ax.plot(t_new, truth[:, 0], "k", lw=2.5, label="real system")
ax.plot(t_new, prior_alone[:, 0], "C1", label="model f_m alone")
ax.plot(t_new, hybrid[:, 0], "C0--", label="hybrid f_m + g")
ax.set(xlabel="time", ylabel="x1")
ax.legend(loc="lower left")
fig.tight_layout()

# %%
# The model is a file of equations, not code: save it and load it with the prior.

model.save("first_model.json")
again = dc.load_model("first_model.json", prior=f_m)
assert np.allclose(again.coefficients(), model.coefficients())
print(again.to_latex())
