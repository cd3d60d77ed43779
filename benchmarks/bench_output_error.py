"""Output error at scale: ``fit_outputs`` on 25,000 samples of a forced Duffing oscillator
whose velocity is not measured, with a degree-3 polynomial library in the position and the
velocity (10 candidate terms in the velocity's equation; the one to find is -0.5 pos^3), and
the same with a Coulomb term 0.3 sign(vel) in the truth and in the prior. Compared with

* the previous implementation (commit :data:`PREVIOUS`, exported with ``git archive`` and
  run on the same data in its own interpreter): same algorithm, sensitivities of every
  coefficient in CasADi's virtual machine, BLAS threads left on;
* scipy's ``least_squares`` with its own finite-difference Jacobian ("2-point") on the
  chosen support, from the same start as ours with exact sensitivities: the same answer
  (the simulation is shared; what differs is where the Jacobian comes from).

Each fit runs in a fresh interpreter; CPU time counts its children (the C compiler).
"fresh cache" compiles the model's blocks (``DISCREPANCY_CACHE`` in a new folder), "cached"
loads them. The truth is integrated by classical RK4 at 16 steps per sample with the input
linear between samples; the fits take 4 RK4 substeps per sample.

Run: .venv/bin/python benchmarks/bench_output_error.py [--samples N] [--skip-previous]
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np
from _common import machine, table

HERE = Path(__file__).resolve().parent
PREVIOUS = "efe0ae0"
DT, NOISE, COULOMB, CUBIC = 0.05, 0.01, 0.3, -0.5
TIMEOUT = 3600

#: run in a fresh interpreter: fit one case, print JSON
WORKER = r"""
import json, resource, sys, time
import numpy as np, sympy as sp
import discrepancy as dc
data = np.load(sys.argv[1])
pos, vel, u = sp.symbols("pos vel u", real=True)
coulomb = float(data["coulomb"])
model = dc.DiscrepancyModel(
    prior=[vel, -pos - 0.2 * vel + u - coulomb * sp.sign(vel)], state_names=["pos", "vel"],
    input_names=["u"], feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]),
    constraints=dc.Constraints(exact_equations=["pos"]))
wall, cpu = time.perf_counter(), time.process_time()
model.fit_outputs(data["y"], t=data["t"], u=data["u"], outputs=["pos"], progress=False)
children = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"wall": time.perf_counter() - wall,
                  "cpu": time.process_time() - cpu + children.ru_utime + children.ru_stime,
                  "coef": model.coef_.tolist(), "x0": np.ravel(model.x0_).tolist(),
                  "names": model.get_feature_names()}))
"""


def truth(m: int, coulomb: float, seed: int = 1, substeps: int = 16):
    """Times, input, states and noisy positions of the forced Duffing oscillator, by
    classical RK4 at ``substeps`` steps per sample (the fits take 4) with the input linear
    between samples (a fixed step: with the sign term an adaptive integrator chatters)."""
    t = np.arange(m) * DT
    rng = np.random.default_rng(seed)
    u = 3 * np.convolve(rng.standard_normal(m), np.ones(20) / 20, mode="same")

    def f(z, v):
        return np.array([z[1], -z[0] - 0.2 * z[1] + CUBIC * z[0] ** 3
                         - coulomb * np.sign(z[1]) + v])

    x, h = np.empty((m, 2)), DT / substeps
    x[0] = z = np.array([0.5, -0.3])
    for k in range(m - 1):
        for j in range(substeps):
            a, b, c = (u[k] + (u[k + 1] - u[k]) * (j + s) / substeps for s in (0, 0.5, 1))
            k1 = f(z, a)
            k2 = f(z + h / 2 * k1, b)
            k3 = f(z + h / 2 * k2, b)
            z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + f(z + h * k3, c))
        x[k + 1] = z
    y = x[:, 0] + NOISE * np.random.default_rng(seed + 1).standard_normal(m)
    return t, u, x, y


def run_worker(data_file, *, source=None, cache=None) -> dict:
    """One fit in a fresh interpreter; ``source``: a ``src`` folder to import from."""
    env = dict(os.environ)
    if source is not None:
        env["PYTHONPATH"] = str(source)
    if cache is not None:
        env["DISCREPANCY_CACHE"] = str(cache)
    try:
        done = subprocess.run([sys.executable, "-c", WORKER, str(data_file)],
                              capture_output=True, text=True, env=env, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"error": f"stopped after {TIMEOUT} s"}
    if done.returncode != 0:
        return {"error": (done.stderr.strip().splitlines() or ["?"])[-1][:200]}
    return json.loads(done.stdout.strip().splitlines()[-1])


def previous_source(folder) -> Path | None:
    """``src`` of commit :data:`PREVIOUS`, exported into ``folder`` (None without git)."""
    try:
        archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", PREVIOUS, "src"],
                                 capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(folder, filter="data")
    return Path(folder) / "src"


def terms(result) -> str:
    """The velocity equation's terms of a worker's result."""
    if "coef" not in result:
        return result.get("error", "?")
    row = result["coef"][1]
    return ", ".join(f"{c:+.4f} {n}" for c, n in zip(row, result["names"], strict=True)
                     if c != 0) or "none"


def against_scipy(t, u, y, coulomb, support):
    """The chosen support refitted on all the data from the same start by ours (exact
    sensitivities) and by scipy's ``least_squares`` with a finite-difference Jacobian."""
    import scipy.optimize
    import sympy as sp

    import discrepancy as dc
    from discrepancy.models.outputs.output_error import records_of
    from discrepancy.models.outputs.output_fit import prepare

    pos, vel, u_ = sp.symbols("pos vel u", real=True)
    model = dc.DiscrepancyModel(
        prior=[vel, -pos - 0.2 * vel + u_ - coulomb * sp.sign(vel)],
        state_names=["pos", "vel"], input_names=["u"],
        feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]),
        constraints=dc.Constraints(exact_equations=["pos"]))
    records, _ = records_of(model, y, t, u, 4, "linear")
    fit, _, rows = prepare(model.make_setup(2, 1), records, outputs=["pos"], x0=None,
                           x0_bounds=None, substeps=4)
    x0s = np.array([[y[0], 0.0]])
    fit.set_coef_scale(x0s)
    start = np.zeros(support.shape)
    index = np.flatnonzero(support.ravel())
    theta0 = np.concatenate([start.ravel()[index] / fit.coef_scale[index], x0s.ravel()])
    out = {}
    wall, cpu = time.perf_counter(), time.process_time()
    coef, x0, cost = fit.solve(support, start, x0s, rows, 0.0)
    out["ours: exact sensitivities (trf)"] = (time.perf_counter() - wall,
                                              time.process_time() - cpu, coef[support], cost)
    wall, cpu = time.perf_counter(), time.process_time()
    peer = scipy.optimize.least_squares(
        lambda th: fit.residuals(th, support, rows, 0.0, jacobian=False), theta0,
        jac="2-point", method="trf", x_scale="jac", xtol=1e-9, ftol=1e-9, gtol=1e-9)
    out["scipy least_squares, 2-point Jacobian (trf)"] = (
        time.perf_counter() - wall, time.process_time() - cpu,
        peer.x[:len(index)] * fit.coef_scale[index], 2 * peer.cost)
    return out


def main(argv):
    samples = int(argv[argv.index("--samples") + 1]) if "--samples" in argv else 25_000
    print(f"## Output error: {samples} samples, velocity unmeasured, degree-3 library\n")
    print(machine() + "\n")
    rows, peer_rows = [], []
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        source = None if "--skip-previous" in argv else previous_source(work / "previous")
        for label, coulomb in (("Duffing", 0.0), ("Duffing, Coulomb term in the prior",
                                                  COULOMB)):
            print(f"  {label}: data ...", file=sys.stderr, flush=True)
            t, u, x, y = truth(samples, coulomb)
            data = work / f"data_{coulomb}.npz"
            np.savez(data, t=t, u=u, y=y, coulomb=coulomb)
            runs = {"this, fresh cache (compiles)": work / f"cache_{coulomb}",
                    "this, cached": work / f"cache_{coulomb}"}
            results = {}
            for name, cache in runs.items():
                print(f"  {label}: {name} ...", file=sys.stderr, flush=True)
                results[name] = run_worker(data, cache=cache)
            if source is not None:
                print(f"  {label}: previous ...", file=sys.stderr, flush=True)
                results[f"previous ({PREVIOUS})"] = run_worker(data, source=source)
            rows += _rows(label, results)
            ours = results["this, cached"]
            if "coef" in ours:
                support = np.array(ours["coef"]) != 0
                for name, (wall, cpu, coef, cost) in against_scipy(t, u, y, coulomb,
                                                                   support).items():
                    peer_rows.append([label, name, f"{wall:.2f}", f"{cpu:.2f}",
                                      " ".join(f"{c:+.6f}" for c in coef), f"{cost:.8g}"])
    print(table(["case", "implementation", "wall (s)", "CPU (s)", "CPU: previous / this",
                 "terms found (velocity equation)", "largest coefficient difference"], rows))
    print("\nThe chosen support refitted on all the data from the same start (zero "
          "coefficients, x0 = (first position, 0)):\n")
    print(table(["case", "solver", "wall (s)", "CPU (s)", "coefficients", "cost"],
                peer_rows))


def _rows(label, results):
    previous = results.get(f"previous ({PREVIOUS})", {})
    out = []
    for name, r in results.items():
        if "wall" not in r:
            out.append([label, name, "-", "-", "-", terms(r), "-"])
            continue
        ratio = f"{previous['cpu'] / r['cpu']:.1f}" if "cpu" in previous else "-"
        diff = (f"{np.max(np.abs(np.array(r['coef']) - np.array(previous['coef']))):.1e}"
                if "coef" in previous else "-")
        out.append([label, name, f"{r['wall']:.1f}", f"{r['cpu']:.1f}", ratio, terms(r),
                    diff])
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
