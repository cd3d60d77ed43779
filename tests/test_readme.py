"""The README's quick start runs as printed and finds the discrepancy it promises."""
import re
import runpy
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_starts_with_the_two_commands():
    assert README.read_text().splitlines()[:2] == ["make demo", "make test"]


def test_quick_start_runs_on_van_der_pol_data(tmp_path, monkeypatch, capsys, vdp_data):
    code = re.search(r"## Quick start\n\n```python\n(.*?)```", README.read_text(), re.S).group(1)
    x = vdp_data.x + 0.01 * np.random.default_rng(0).standard_normal(vdp_data.x.shape)
    np.savetxt(tmp_path / "run.csv", np.c_[vdp_data.t, x], delimiter=",", header="t,x1,x2",
               comments="")
    (tmp_path / "quick_start.py").write_text(code)
    monkeypatch.chdir(tmp_path)
    namespace = runpy.run_path(str(tmp_path / "quick_start.py"))
    assert "(x2)' = prior + 0.40" in capsys.readouterr().out
    assert (tmp_path / "model.json").is_file()
    truth = np.c_[vdp_data.x[:, 1], 0.5 * (1 - vdp_data.x[:, 0] ** 2) * vdp_data.x[:, 1]
                  - vdp_data.x[:, 0]]
    assert namespace["x_sim"].shape == (2500, 2)
    hybrid = namespace["model"].predict(vdp_data.x)
    assert np.linalg.norm(hybrid - truth) / np.linalg.norm(truth) < 0.01
