"""The README and the user guide (docs/guide/) as printed: every Python block that states a
result is run here on data whose true answer is known, wherever the block now lives; a block
that only shows the calls must say so; the README's links lead somewhere."""
import re
import runpy
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
GUIDE = ROOT / "docs" / "guide"
NOT_RUN = "not run as printed"
#: (page, index of its Python block) of every block the tests below run
RUN = {("README.md", 0), ("docs/guide/fitting.md", 0), ("docs/guide/selection.md", 0),
       ("docs/guide/energy.md", 0), ("docs/guide/output-error.md", 0),
       ("docs/guide/estimation.md", 1), ("docs/guide/control.md", 0)}


def pages() -> list[Path]:
    return [README, *sorted(GUIDE.glob("*.md"))]


def blocks(page: Path) -> list[re.Match]:
    return list(re.finditer(r"```python\n(.*?)```", page.read_text(), re.S))


def snippet(page: str, index: int = 0) -> str:
    """The ``index``-th Python block of ``page`` (a path from the repository's root)."""
    assert (page, index) in RUN, f"add {(page, index)} to RUN"
    return blocks(ROOT / page)[index].group(1)


def run_snippet(tmp_path, page: str, index: int = 0, **names) -> dict:
    path = tmp_path / f"{Path(page).stem}_{index}.py"
    path.write_text(snippet(page, index))
    return runpy.run_path(str(path), init_globals=names)


def test_readme_starts_with_the_commands():
    assert README.read_text().splitlines()[:3] == ["make demo", "make test", "make docs"]


def test_every_python_block_is_run_or_says_it_is_not():
    for page in pages():
        text = page.read_text()
        for i, block in enumerate(blocks(page)):
            name = str(page.relative_to(ROOT))
            if (name, i) in RUN:
                continue
            around = " ".join(text[max(0, block.start() - 300):block.end() + 300].split())
            assert NOT_RUN in around, f"{name}, Python block {i}: run it in a test or say so"


def test_every_guide_page_is_in_the_site(tmp_path):
    index = (GUIDE / "index.md").read_text()
    for page in GUIDE.glob("*.md"):
        assert page.name == "index.md" or f"\n{page.stem}\n" in index, page.name
    assert "guide/index" in (ROOT / "docs" / "index.rst").read_text()


def test_readme_links_lead_to_files():
    links = re.findall(r"\]\(([^)#]+)\)", README.read_text())
    assert len(links) >= 20
    for link in links:
        assert not link.startswith(("/", "http")), link
        assert (ROOT / link).is_file(), link


def test_readme_results_say_how_each_figure_was_chosen():
    text = README.read_text()
    table = text[text.index("## Results"):text.index("## Learn more")]
    rows = [r for r in table.splitlines() if r.startswith("| ") and "---" not in r][1:]
    assert len(rows) >= 8
    for row in rows:
        how = row.strip("| ").rsplit("|", 1)[1].strip()
        assert how.startswith(("blind", "tuned", "measured")), row


def test_quick_start_runs_and_finds_the_discrepancy(tmp_path, capsys, vdp_data,
                                                    run_quick_start):
    code = snippet("README.md")
    assert len(code.strip().splitlines()) <= 15
    namespace = run_quick_start(README.read_text())
    printed = capsys.readouterr().out
    assert "(x2)' = prior + 0.40" in printed and "(x2)' = prior + (0.40" in printed
    assert (tmp_path / "model.json").is_file()
    low, high = namespace["unc"].interval()
    names = namespace["model"].get_feature_names()
    for term, truth in (("x2", 0.4), ("x1^2 x2", -0.4)):
        assert low[1, names.index(term)] <= truth <= high[1, names.index(term)]
    assert namespace["x_sim"].shape == (2500, 2)
    truth = np.c_[vdp_data.x[:, 1], 0.5 * (1 - vdp_data.x[:, 0] ** 2) * vdp_data.x[:, 1]
                  - vdp_data.x[:, 0]]
    hybrid = namespace["model"].predict(vdp_data.x)
    assert np.linalg.norm(hybrid - truth) / np.linalg.norm(truth) < 0.01


def test_guide_quick_start_runs_on_van_der_pol_data(tmp_path, capsys, run_quick_start):
    code = snippet("docs/guide/fitting.md")
    namespace = run_quick_start(f"## Quick start\n\n```python\n{code}```")
    assert "(x2)' = prior + 0.40" in capsys.readouterr().out
    assert (tmp_path / "model.json").is_file() and namespace["x_sim"].shape == (2500, 2)


def test_energy_snippet_finds_the_friction_of_a_rod_pendulum(tmp_path, capsys):
    """Given a simulated rod pendulum (viscous 2e-3 N m s and Coulomb 4e-3 N m, 5000-count
    encoder, 24 s at 1 kHz), the energy page's code finds both laws within 2 %."""
    import sympy as sp

    import discrepancy as dc

    m, l, g = 0.5, 0.4, 9.81
    q, w = sp.symbols("q dq")
    true = dc.systems.LagrangianSystem(m * l ** 2 / 6 * w ** 2, -m * g * l / 2 * sp.cos(q),
                                       ["q"], dissipation=1e-3 * w ** 2
                                       + 4e-3 * sp.sqrt(w ** 2 + 1e-6))
    t = np.arange(24001) / 1000
    step = 2 * np.pi / 5000
    angles = np.round(true.simulate([2.6, 0.0], t)[:, :1] / step) * step
    namespace = run_snippet(tmp_path, "docs/guide/energy.md", m=m, l=l, g=g, angles=angles,
                            t=t, k=19200)
    assert "P_loss = " in capsys.readouterr().out
    model = namespace["blind"].model
    laws = {term.name: c for term, c in zip(model.terms_, model.coef_, strict=True)}
    assert set(laws) == {"viscous joint 1", "Coulomb joint 1"}
    assert laws["viscous joint 1"] == pytest.approx(2e-3, rel=0.02)
    assert laws["Coulomb joint 1"] == pytest.approx(4e-3, rel=0.02)


def test_how_models_are_chosen_snippet_runs_on_a_damped_oscillator(tmp_path, capsys):
    """Given a Duffing oscillator whose prior lacks a weak damping (noise 10x the paper's),
    the selection page's code finds exactly the damping; the prior alone is fitted too."""
    from scipy.integrate import solve_ivp

    import discrepancy as dc

    f_m = lambda x, u=None: np.c_[x[:, 1], -x[:, 0] - x[:, 0] ** 3]   # noqa: E731
    t = np.arange(2501) * 0.01
    x = solve_ivp(lambda s, z: [z[1], -z[0] - z[0] ** 3 - 0.1 * z[1]], (0, 25), [1.5, 0.0],
                  t_eval=t, rtol=1e-10, atol=1e-10).y.T
    x = x + 0.1 * np.random.default_rng(0).standard_normal(x.shape)
    namespace = run_snippet(tmp_path, "docs/guide/selection.md", dc=dc, f_m=f_m, x=x, dt=0.01)
    model = namespace["model"]
    names = model.get_feature_names()
    assert not model.prior_only_ and np.count_nonzero(model.coef_) == 1
    assert model.coef_[1, names.index("x2")] == pytest.approx(-0.1, rel=0.15)
    assert namespace["prior"].prior_only_
    assert "<- chosen" in capsys.readouterr().out


def forced_oscillator(seed: int, x0, gain: float = 3.0):
    """x'' = -x - 0.2 x' - 0.5 x^3 + u for 80 s every 0.05 s, u smoothed noise; the measured
    position has noise 0.01. ``(t, u, x, y)``."""
    from scipy.integrate import solve_ivp

    t = np.arange(1601) * 0.05
    rng = np.random.default_rng(seed)
    u = gain * np.convolve(rng.standard_normal(len(t)), np.ones(40) / 40, mode="same")
    x = solve_ivp(lambda s, z: [z[1], -z[0] - 0.2 * z[1] - 0.5 * z[0] ** 3
                                + np.interp(s, t, u)],
                  (0, t[-1]), x0, t_eval=t, rtol=1e-11, atol=1e-11, max_step=0.05).y.T
    return t, u, x, x[:, 0] + 0.01 * rng.standard_normal(len(t))


@pytest.mark.slow
def test_output_error_snippet_finds_the_terms_on_the_hidden_velocity(tmp_path, capsys):
    pytest.importorskip("casadi")
    import discrepancy as dc

    t, u, x, y = forced_oscillator(1, [0.5, -0.3])
    t_new, u_new, x_new, y_new = forced_oscillator(7, [-0.4, 0.6], gain=1.5)
    namespace = run_snippet(tmp_path, "docs/guide/output-error.md", dc=dc, y=y, dt=0.05, u=u,
                            y_new=y_new, u_new=u_new, t_new=t_new)
    assert "(vel)' = prior - 0.100 vel - 0.500 pos^3" in capsys.readouterr().out
    model = namespace["model"]
    names, row = model.get_feature_names(), model.coef_[1]
    assert model.complexity == 2
    assert row[names.index("vel")] == pytest.approx(-0.1, rel=0.02)
    assert row[names.index("pos^3")] == pytest.approx(-0.5, rel=0.02)
    np.testing.assert_allclose(model.x0_, x[0], atol=0.02)            # the hidden velocity
    np.testing.assert_allclose(namespace["x0"], x_new[0], atol=0.02)
    assert np.abs(namespace["x"] - x_new).max() < 0.02 * np.abs(x_new).max()


@pytest.mark.slow
def test_prediction_error_snippet_on_the_experiments_record(tmp_path, capsys):
    """The estimation page's prediction-error block on the 300 s record of
    ``discrepancy reproduce prediction-error`` (push and process noise): the two true terms,
    each within 1.5 %, as the page says (0.4 % and 1.2 %)."""
    pytest.importorskip("casadi")
    from discrepancy_paper.experiments import prediction_error as pe

    t, u, y, _, _ = pe.record(0, pe.T_FULL)
    namespace = run_snippet(tmp_path, "docs/guide/estimation.md", 1, model=pe.new_model(),
                            y=y, t=t, u=u)
    model = namespace["model"]
    found = {n: c for n, c in zip(model.get_feature_names(), model.coef_[1], strict=True)
             if c != 0}
    assert set(found) == set(pe.TRUE)
    for term, truth in pe.TRUE.items():
        assert found[term] == pytest.approx(truth, rel=0.015)
    claimed = re.search(r"# (\(vel\)' = .*)", snippet("docs/guide/estimation.md", 1)).group(1)
    assert claimed.strip() in capsys.readouterr().out


@pytest.mark.slow
def test_mpc_snippet_is_the_campaigns_controller_and_swings_up(tmp_path, capsys):
    """The control page's block, given the exact hybrid model (the true system's equations):
    upright at the end within the rail, input and rate limits, with sensor noise; its MPC
    has the campaign's settings; ``law.reset()`` empties the law's records."""
    pytest.importorskip("casadi")
    import discrepancy as dc
    from discrepancy_paper.experiments.cart_mpc import cart_task

    hybrid = dc.control.as_casadi(dc.systems.DoublePendulumOnCart().equations())
    namespace = run_snippet(tmp_path, "docs/guide/control.md", hybrid=hybrid)
    assert capsys.readouterr().out.strip().endswith("True True")
    assert namespace["upright"] and namespace["limits"].check(namespace["run"])["respected"]
    task, mpc, law = cart_task(), namespace["mpc"], namespace["law"]
    campaign = task.mpc(hybrid)
    for name in ("dt", "horizon", "substeps", "solver"):
        assert getattr(mpc, name) == getattr(campaign, name), name
    for ours, theirs in zip(mpc.limits.sized(6, 1), campaign.limits.sized(6, 1), strict=True):
        np.testing.assert_array_equal(ours, theirs)   # the rail 1 cm shorter, u, du/dt
    np.testing.assert_array_equal(mpc.Q, campaign.Q)
    np.testing.assert_array_equal(mpc.R, campaign.R)
    plan = namespace["plan"]
    assert (plan.dt, len(plan.u)) == (task.dt, task.n_intervals)
    assert law.cpu_times == [] and law._last is None                  # reset
