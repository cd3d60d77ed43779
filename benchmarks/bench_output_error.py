"""Output error at scale: ``fit_outputs`` on 25,000 samples of a forced Duffing oscillator
whose velocity is not measured, with a degree-3 polynomial library in the position and the
velocity (10 candidate terms in the velocity's equation; the one to find is -0.5 pos^3),
against

* the implementation before multiple shooting (commit d0cbb05: single shooting with
  scipy's ``least_squares``), exported with ``git archive`` into a temporary folder at run
  time and run in a subprocess on the same data;
* scipy's ``least_squares`` on the same problem: the chosen support refitted on all the
  data from the same start by our multiple-shooting Levenberg–Marquardt and by scipy's
  trust-region reflective method (single shooting, the same exact Jacobian);

and the same with a Coulomb term (0.3 sign(v)) in the truth and in the prior. Times are
wall and CPU seconds of the fitting process and its children (compiling counts); ours with
the compiled code not yet cached (a fresh cache folder) and cached, on one and two threads.

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
PREVIOUS = "d0cbb05"
DT, NOISE, COULOMB = 0.05, 0.01, 0.3
TIMEOUT = 3600

#: run in a subprocess: fit one case with the ``discrepancy`` on its path, print JSON
WORKER = r"""
import json, resource, sys, time
import numpy as np, sympy as sp
import discrepancy as dc
data = np.load(sys.argv[1]); options = json.loads(sys.argv[2])
pos, vel, u = sp.symbols("pos vel u", real=True)
coulomb = float(data["coulomb"])
prior = [vel, -pos - 0.2 * vel + u - coulomb * sp.sign(vel)]
model = dc.DiscrepancyModel(prior=prior, state_names=["pos", "vel"], input_names=["u"],
    feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]),
    constraints=dc.Constraints(exact_equations=["pos"]))
wall, cpu = time.perf_counter(), time.process_time()
model.fit_outputs(data["y"], t=data["t"], u=data["u"], outputs=["pos"], progress=False,
                  **options)
children = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"wall": time.perf_counter() - wall,
                  "cpu": time.process_time() - cpu + children.ru_utime + children.ru_stime,
                  "coef": model.coef_.tolist(), "x0": np.ravel(model.x0_).tolist(),
                  "terms": [f"({s}) {n}" for s, row in zip(model.state_names_, model.coef_)
                            for n, c in zip(model.get_feature_names(), row) if c != 0]}))
"""


def forcing(m, seed):
    rng = np.random.default_rng(seed)
    return 3 * np.convolve(rng.standard_normal(m), np.ones(20) / 20, mode="same")


def truth(m, coulomb, seed=1, substeps=16):
    """The forced Duffing oscillator by classical RK4 at ``substeps`` steps per sample (the
    fits take 4), the input interpolated linearly; positions with noise."""
    t = np.arange(m) * DT
    u = forcing(m, seed)

    def f(z, v):
        return np.array([z[1], -z[0] - 0.2 * z[1] - 0.5 * z[0] ** 3 - coulomb * np.sign(z[1])
                         + v])

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


def run_worker(data_file, options, *, source=None, cache=None):
    """Fit in a fresh interpreter; ``source``: a ``src`` folder to import from."""
    env = dict(os.environ)
    if source is not None:
        env["PYTHONPATH"] = str(source)
    if cache is not None:
        env["DISCREPANCY_CACHE_DIR"] = str(cache)
    try:
        done = subprocess.run([sys.executable, "-c", WORKER, str(data_file),
                               json.dumps(options)], capture_output=True, text=True, env=env,
                              timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return {"error": f"stopped after {TIMEOUT} s"}
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1][:200]}
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


def against_scipy(t, u, y, coulomb, support):
    """The chosen support refitted on everything from the same start by ours and scipy."""
    import sympy as sp

    import discrepancy as dc
    from discrepancy.models import single_shooting
    from discrepancy.models.output_fit import _allowed, prepare
    from discrepancy.models.output_records import records_of

    pos, vel, u_ = sp.symbols("pos vel u", real=True)
    model = dc.DiscrepancyModel(
        prior=[vel, -pos - 0.2 * vel + u_ - coulomb * sp.sign(vel)], state_names=["pos", "vel"],
        input_names=["u"], feature_library=dc.PolynomialLibrary(3, variables=["pos", "vel"]),
        constraints=dc.Constraints(exact_equations=["pos"]))
    records, _ = records_of(y, t, u, 4, "linear")
    setup = model.make_setup(2, 1)
    fit, _, rows = prepare(setup, records, outputs=["pos"], x0=None, x0_bounds=None,
                           substeps=4, allowed=_allowed(setup), structure=_allowed(setup),
                           options={"n_jobs": 1}, passes=40)
    x0s = np.array([[y[0], 0.0]])
    fit.set_coef_scale(x0s)
    start = np.zeros_like(support, float)
    out = {}
    for name, solve in (("ours (multiple shooting, Levenberg-Marquardt)",
                         lambda: fit.solve(support, start, x0s, rows, 0.0)),
                        ("scipy least_squares (single shooting, trf)",
                         lambda: single_shooting.solve(fit, support, start, x0s, rows, 0.0))):
        if name.startswith("ours"):
            solve()                                   # compiles its blocks before timing
        else:                                         # the blocks single shooting runs
            from discrepancy.models.shooting import BLOCK
            fit.shooting.block(list(np.flatnonzero(support.ravel())), BLOCK)
            fit.shooting.block(None, BLOCK)
        wall, cpu = time.perf_counter(), time.process_time()
        result = solve()
        timing = (time.perf_counter() - wall, time.process_time() - cpu)
        coef, x0, cost = (result.coef, result.x0s, result.cost) if hasattr(result, "coef") \
            else result
        out[name] = {"wall": timing[0], "cpu": timing[1], "coef": coef[support],
                     "x0": x0[0], "cost": cost}
    return out


def main(argv):
    samples = int(argv[argv.index("--samples") + 1]) if "--samples" in argv else 25_000
    print(f"## Output error: {samples} samples, velocity unmeasured, degree-3 library\n")
    print(machine() + "\n")
    load = os.getloadavg()
    rows, peer_rows = [], []
    with tempfile.TemporaryDirectory() as work:
        work = Path(work)
        source = None if "--skip-previous" in argv else previous_source(work / "previous")
        for label, coulomb in (("Duffing", 0.0), ("Duffing + Coulomb prior", COULOMB)):
            print(f"  {label}: data ...", file=sys.stderr, flush=True)
            t, u, x, y = truth(samples, coulomb)
            data = work / f"data_{coulomb}.npz"
            np.savez(data, t=t, u=u, y=y, coulomb=coulomb)
            cache = work / f"cache_{coulomb}"
            runs = {"ours, compiling (fresh cache), 2 threads": ({"n_jobs": 2}, cache),
                    "ours, cached, 2 threads": ({"n_jobs": 2}, cache),
                    "ours, cached, 1 thread": ({"n_jobs": 1}, cache)}
            results = {}
            if source is not None:
                print(f"  {label}: previous implementation ...", file=sys.stderr, flush=True)
                results["previous (d0cbb05, scipy least_squares)"] = run_worker(
                    data, {}, source=source)
            for name, (options, folder) in runs.items():
                print(f"  {label}: {name} ...", file=sys.stderr, flush=True)
                results[name] = run_worker(data, options, cache=folder)
            rows += _rows(label, results, x[0])
            ours = results["ours, cached, 1 thread"]
            if "coef" in ours:
                support = np.array(ours["coef"]) != 0
                peers = against_scipy(t, u, y, coulomb, support)
                peer_rows += _peer_rows(label, peers)
    print(table(["case", "implementation", "wall (s)", "CPU (s)", "CPU: previous / this",
                 "terms", "x0 (pos, vel)", "largest coefficient difference from previous"],
                rows))
    print("\nThe chosen support refitted on all the data from the same start (zero "
          "coefficients, x0 = [y0, 0]): ours against scipy's `least_squares` on identical "
          "residuals and Jacobians.\n")
    print(table(["case", "solver", "wall (s)", "CPU (s)", "CPU: scipy / ours", "cost",
                 "coefficients", "largest relative difference"], peer_rows))
    end = os.getloadavg()
    print(f"\nLoad average (1, 5, 15 min) at the start {load[0]:.1f}, {load[1]:.1f}, "
          f"{load[2]:.1f} and at the end {end[0]:.1f}, {end[1]:.1f}, {end[2]:.1f}: the two "
          "cores are shared, so wall times move with other jobs; CPU times are the measure. "
          "Truth: RK4 at 16 steps per sample (the fits take 4); noise 0.01 on the position.")
    return 0


def _rows(label, results, x0_true):
    previous = results.get("previous (d0cbb05, scipy least_squares)", {})
    out = []
    for name, r in results.items():
        if "error" in r:
            out.append([label, name, r["error"], "", "", "", "", ""])
            continue
        ratio = f"**{previous['cpu'] / r['cpu']:.1f}x**" if "cpu" in previous and \
            r is not previous else ""
        diff = f"{np.abs(np.array(r['coef']) - np.array(previous['coef'])).max():.1e}" \
            if "coef" in previous and r is not previous else ""
        out.append([label, name, f"{r['wall']:.1f}", f"{r['cpu']:.1f}", ratio,
                    "; ".join(f"{term}" for term in r["terms"]) + " = " + ", ".join(
                        f"{c:.5f}" for c in np.ravel(r["coef"]) if c != 0),
                    f"{r['x0'][0]:.4f}, {r['x0'][1]:.4f} (true {x0_true[0]}, "
                    f"{x0_true[1]})", diff])
    return out


def _peer_rows(label, peers):
    (ours_name, ours), (peer_name, peer) = peers.items()
    difference = np.abs(ours["coef"] - peer["coef"]) / np.maximum(np.abs(peer["coef"]), 1e-12)
    return [[label, ours_name, f"{ours['wall']:.2f}", f"{ours['cpu']:.2f}",
             f"**{peer['cpu'] / ours['cpu']:.1f}x**", f"{ours['cost']:.10g}",
             ", ".join(f"{c:.6f}" for c in ours["coef"]), f"{difference.max():.1e}"],
            [label, peer_name, f"{peer['wall']:.2f}", f"{peer['cpu']:.2f}", "",
             f"{peer['cost']:.10g}", ", ".join(f"{c:.6f}" for c in peer["coef"]), ""]]


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
