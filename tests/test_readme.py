"""The README's quick start runs as printed and finds the discrepancy it promises."""
import re
import runpy
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_starts_with_the_two_commands():
    assert README.read_text().splitlines()[:2] == ["make demo", "make test"]


def test_quick_start_runs_on_van_der_pol_data(tmp_path, capsys, vdp_data, run_quick_start):
    namespace = run_quick_start(README.read_text())
    assert "(x2)' = prior + 0.40" in capsys.readouterr().out
    assert (tmp_path / "model.json").is_file()
    truth = np.c_[vdp_data.x[:, 1], 0.5 * (1 - vdp_data.x[:, 0] ** 2) * vdp_data.x[:, 1]
                  - vdp_data.x[:, 0]]
    assert namespace["x_sim"].shape == (2500, 2)
    hybrid = namespace["model"].predict(vdp_data.x)
    assert np.linalg.norm(hybrid - truth) / np.linalg.norm(truth) < 0.01


def test_energy_snippet_finds_the_friction_of_a_rod_pendulum(tmp_path, capsys):
    """The energy section's code, given a simulated rod pendulum (viscous 2e-3 N m s and
    Coulomb 4e-3 N m, 5000-count encoder, 24 s at 1 kHz), finds both laws within 2 %."""
    import sympy as sp

    import discrepancy as dc

    code = re.search(r"## Energy lost to friction.*?```python\n(.*?)```", README.read_text(),
                     re.S).group(1)
    m, l, g = 0.5, 0.4, 9.81
    q, w = sp.symbols("q dq")
    true = dc.systems.LagrangianSystem(m * l ** 2 / 6 * w ** 2, -m * g * l / 2 * sp.cos(q),
                                       ["q"], dissipation=1e-3 * w ** 2
                                       + 4e-3 * sp.sqrt(w ** 2 + 1e-6))
    t = np.arange(24001) / 1000
    step = 2 * np.pi / 5000
    angles = np.round(true.simulate([2.6, 0.0], t)[:, :1] / step) * step
    (tmp_path / "energy.py").write_text(code)
    namespace = runpy.run_path(str(tmp_path / "energy.py"), init_globals={
        "m": m, "l": l, "g": g, "angles": angles, "t": t, "k": 19200})
    assert "P_loss = " in capsys.readouterr().out
    model = namespace["blind"].model
    laws = {term.name: c for term, c in zip(model.terms_, model.coef_, strict=True)}
    assert set(laws) == {"viscous joint 1", "Coulomb joint 1"}
    assert laws["viscous joint 1"] == pytest.approx(2e-3, rel=0.02)
    assert laws["Coulomb joint 1"] == pytest.approx(4e-3, rel=0.02)


def test_how_models_are_chosen_snippet_runs_on_a_damped_oscillator(tmp_path, capsys):
    """The section's code, given a Duffing oscillator whose prior lacks a weak damping
    (noise 10x the paper's), finds exactly the damping; the prior alone is fitted too."""
    from scipy.integrate import solve_ivp

    code = re.search(r"## How models are chosen.*?```python\n(.*?)```", README.read_text(),
                     re.S).group(1)
    f_m = lambda x, u=None: np.c_[x[:, 1], -x[:, 0] - x[:, 0] ** 3]   # noqa: E731
    t = np.arange(2501) * 0.01
    x = solve_ivp(lambda s, z: [z[1], -z[0] - z[0] ** 3 - 0.1 * z[1]], (0, 25), [1.5, 0.0],
                  t_eval=t, rtol=1e-10, atol=1e-10).y.T
    x = x + 0.1 * np.random.default_rng(0).standard_normal(x.shape)
    import discrepancy as dc

    (tmp_path / "choose.py").write_text(code)
    namespace = runpy.run_path(str(tmp_path / "choose.py"), init_globals={
        "dc": dc, "f_m": f_m, "x": x, "dt": 0.01})
    model = namespace["model"]
    names = model.get_feature_names()
    assert not model.prior_only_ and np.count_nonzero(model.coef_) == 1
    assert model.coef_[1, names.index("x2")] == pytest.approx(-0.1, rel=0.15)
    assert namespace["prior"].prior_only_
    assert "<- chosen" in capsys.readouterr().out
