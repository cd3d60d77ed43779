"""The paper package's figures draw what they say (checked on the plotted data)."""
import numpy as np

from discrepancy.energy import default_friction_library
from discrepancy.systems import DoublePendulum


def test_friction_law_figure_shows_each_joints_own_torque():
    from discrepancy_paper.plots.energy import friction_law_figure

    # 2, 3: Coulomb joint 1, joint 2; 5: air drag of arm 2 (dphi2)
    terms = default_friction_library(["dphi1", "dphi2"], joints=DoublePendulum().joints())
    fig = friction_law_figure({"law": [(terms[2], 5e-4), (terms[3], 2e-4), (terms[5], 1e-5)]})
    (joint1,), (joint2,) = (ax.get_lines()[:1] for ax in fig.axes[:2])
    w1, tau1 = joint1.get_data()
    np.testing.assert_allclose(tau1[w1 > 0], 5e-4)                     # joint 1 alone
    w2, tau2 = joint2.get_data()
    np.testing.assert_allclose(tau2[w2 > 0], 2e-4 + 1e-5 * w2[w2 > 0] ** 2)   # joint 2 + arm 2
