"""The core install (numpy, scipy, sympy, derivative) is enough to fit, simulate, save and
export to sympy/LaTeX; optional dependencies are imported only when used, and a missing one
is named with the pip install that brings it. Each check runs in a fresh interpreter."""
import subprocess
import sys
import textwrap

import pytest

OPTIONAL = ("matplotlib", "casadi", "dask", "distributed", "zarr", "h5py", "PIL")

BLOCK = f"""
import importlib.abc, sys
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {OPTIONAL!r}:
            raise ImportError(f"{{name}} is blocked for this test")
sys.meta_path.insert(0, Block())
"""


def run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_import_discrepancy_imports_no_optional_dependency():
    out = run(f"""
        import sys, discrepancy
        print(sorted(m for m in {OPTIONAL!r} if m in sys.modules))
        """)
    assert out.strip() == "[]"


def test_quick_start_without_any_extra(tmp_path):
    out = run(BLOCK + f"""
import numpy as np, sympy as sp
import discrepancy as dc
from discrepancy.symbolic import symbol
t = np.arange(2000) * 0.01
x = np.c_[np.exp(-0.1 * t) * np.sin(t), np.exp(-0.1 * t) * np.cos(t)]
x1, x2 = symbol("x1"), symbol("x2")
model = dc.DiscrepancyModel(prior=[x2, -x1], feature_library=dc.PolynomialLibrary(2)).fit(x, t=0.01)
sim = model.simulate(x[0], t[:500])
assert np.max(np.abs(sim - x[:500])) < 1e-3, np.max(np.abs(sim - x[:500]))
model.save({str(tmp_path / 'm.json')!r})
again = dc.load_model({str(tmp_path / 'm.json')!r})
assert np.array_equal(again.coef_, model.coef_)
print(again.to_sympy()[0], "|", again.to_latex().splitlines()[1])
for name in ("nothing.h5", "x.h5"):
    open({str(tmp_path)!r} + "/" + name, "wb").close()
for call, extra in [(lambda: model.to_casadi(), "control"),
                    (lambda: __import__("discrepancy.control"), "control"),
                    (lambda: __import__("discrepancy.plots"), "plots"),
                    (lambda: dc.HDF5Source({str(tmp_path / 'nothing.h5')!r}), "scale"),
                    (lambda: dc.io.load({str(tmp_path / 'x.h5')!r}), "scale")]:
    try:
        call()
    except dc.errors.MissingDependencyError as e:
        assert f"pip install 'discrepancy[{{extra}}]'" in str(e), str(e)
        print("refused:", extra)
    else:
        raise AssertionError("no error")
""")
    assert "x2" in out.split("|")[0] and "dot{x_{1}}" in out  # sympy and LaTeX forms
    assert out.count("refused:") == 5


def test_dask_fit_without_dask_names_the_extra():
    pytest.importorskip("dask")
    out = run(BLOCK + """
import discrepancy as dc
class FakeDask:  # looks like a dask array to the dispatcher
    __module__ = "dask.array.core"
try:
    dc.DiscrepancyModel().fit(FakeDask(), t=0.1)
except dc.errors.MissingDependencyError as e:
    print(e)
""")
    assert "pip install 'discrepancy[scale]'" in out


def test_filters_run_in_numpy_without_casadi():
    out = run(BLOCK + """
import numpy as np, sympy as sp, sys
from discrepancy.estimation import ExtendedKalmanFilter
x1, x2 = sp.symbols("x1 x2")
kf = ExtendedKalmanFilter([x2, -x1], outputs=["x1"], state_names=["x1", "x2"],
                          process_noise=[0, 0.01], measurement_noise=0.01)
t = np.arange(200) * 0.05
run = kf.filter(np.sin(t)[:, None], 0.05, x0=[0, 1], P0=[0.1, 0.1])
assert abs(run.x[-1, 1] - np.cos(t[-1])) < 0.01, run.x[-1]
try:
    ExtendedKalmanFilter([x2, -x1], outputs=["x1"], state_names=["x1", "x2"],
                         process_noise=[0, 0.01], measurement_noise=0.01, backend="casadi")
except ImportError as e:
    print("refused:", e)
print(kf.backend, "casadi" in sys.modules)
""")
    assert "pip install 'discrepancy[control]'" in out and out.strip().endswith("numpy False")
