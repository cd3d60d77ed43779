"""Compiled CasADi functions: same numbers as the virtual machine, cached by source, and a
warned fallback when there is no compiler."""
import os
import shutil

import casadi as ca
import numpy as np
import pytest

from discrepancy.control import MPC
from discrepancy.errors import CompilationWarning
from discrepancy.hybrid import codegen
from discrepancy.hybrid.codegen import compiled

needs_cc = pytest.mark.skipif(codegen.compiler() is None, reason="no C compiler")


def small_function():
    x = ca.SX.sym("x", 3)
    return ca.Function("small_test_fn", [x], [ca.vertcat(ca.sin(x[0]) * x[1], ca.exp(x[2]))])


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DISCREPANCY_CACHE", str(tmp_path))
    return tmp_path / "casadi"


@needs_cc
def test_compiled_function_gives_the_same_numbers_and_is_cached(cache, monkeypatch):
    f = small_function()
    g = compiled(f)
    assert g.class_name() != f.class_name()          # a loaded library, not the SX function
    x = np.array([0.3, -2.0, 0.7])
    np.testing.assert_allclose(np.array(g(x)).ravel(), [np.sin(0.3) * -2.0, np.exp(0.7)],
                               rtol=1e-15)
    libraries = list(cache.glob("small_test_fn_*.so"))
    assert len(libraries) == 1
    # the second time nothing is compiled: the cached library is loaded
    monkeypatch.setattr(codegen, "_compile", lambda *a: pytest.fail("compiled again"))
    compiled(small_function())


def test_without_a_compiler_the_function_runs_uncompiled_with_a_warning(cache, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-xyz")
    monkeypatch.setattr(shutil, "which", lambda name: None)
    f = small_function()
    with pytest.warns(CompilationWarning, match="no C compiler"):
        g = compiled(f)
    assert g is f
    assert not cache.exists() or not any(cache.iterdir())


def test_a_failing_compiler_falls_back_with_a_warning(cache, monkeypatch):
    monkeypatch.setenv("CC", "false")               # exits with status 1
    if shutil.which("false") is None:
        pytest.skip("no 'false' command")
    with pytest.warns(CompilationWarning, match="could not compile"):
        g = compiled(small_function())
    assert g.class_name() == "SXFunction"


@needs_cc
def test_compiled_real_time_mpc_equals_the_uncompiled_one(cache):
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 1)
    f = ca.Function("f", [x, u], [ca.vertcat(x[1], -9.81 * ca.sin(x[0]) + u)])
    kw = dict(dt=0.05, horizon=6, Q=[10.0, 1.0], R=0.1, solver="rti")
    x_ref, u_ref = np.tile([np.pi, 0.0], (7, 1)), np.zeros((6, 1))
    plain = MPC(f, **kw).solve(np.array([0.1, 0.0]), x_ref, u_ref)
    fast = MPC(f, compile=True, **kw).solve(np.array([0.1, 0.0]), x_ref, u_ref)
    assert len(os.listdir(cache)) == 2              # linearise and condense
    np.testing.assert_allclose(fast.u, plain.u, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(fast.x, plain.x, rtol=1e-12, atol=1e-12)
