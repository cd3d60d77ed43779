"""A field larger than the memory it is fitted in: streamed from zarr and HDF5, and on a
Dask LocalCluster, against the in-memory fit of the same data; PySINDy in the same run.

Data: viscous Burgers (nu = 0.05) on 1024 periodic points, exact solutions by the
Cole-Hopf transform (no solver error), ``--runs`` runs of 1000 snapshots with random
initial conditions, 1 % noise; the prior lacks the viscosity, so the right answer is
``g = 0.05 u_xx``. Default 120 runs: 1.2e8 values, 940 MB per file, written once to
benchmarks/_data/ (git-ignored).

"Larger than memory" is shown with a memory cap: the streamed fits run with their address
space limited (``RLIMIT_AS``, what ``ulimit -v`` sets) below the field's size, where loading
the field fails (the capped in-memory row). Every fit runs in a fresh child process, so its
peak RSS (VmHWM) is its own; Dask workers report theirs. Times are wall clock on a shared
machine (noisy); the peer row compares throughput on the same subset in one process.

Run: .venv/bin/python benchmarks/bench_pde.py [--runs N] [--cap-mb MB]
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import warnings

import numpy as np
from _common import DATA_DIR, machine, peak_rss_mb, same, table

warnings.filterwarnings("ignore")
NU, POINTS, SNAPSHOTS, DT, NOISE = 0.05, 1024, 1000, 0.005, 0.01
PEER_RUNS = 2


def burgers_run(rng) -> np.ndarray:
    """One exact run ``(SNAPSHOTS, POINTS)``: u = -2 nu theta_x / theta, theta solving the
    heat equation with random decaying modes (kept positive), plus 1 % noise."""
    x = np.linspace(0, 2 * np.pi, POINTS, endpoint=False)
    t = np.arange(SNAPSHOTS) * DT
    k = np.arange(1, 9)
    b = rng.uniform(-1, 1, k.size)
    b *= 0.8 / np.abs(b).sum()
    phase = rng.uniform(0, 2 * np.pi, k.size)
    decay = np.exp(-NU * k ** 2 * t[:, None]) * b
    angle = k * x[:, None] + phase
    u = -2 * NU * (-(decay * k) @ np.sin(angle).T) / (1 + decay @ np.cos(angle).T)
    return u + NOISE * u.std() * rng.standard_normal(u.shape)


def write_data(runs: int):
    """Paths of the zarr store and HDF5 file holding ``run000``... (written once)."""
    import h5py
    import zarr

    DATA_DIR.mkdir(exist_ok=True)
    stem = DATA_DIR / f"burgers_{runs}"
    zpath, hpath = stem.with_suffix(".zarr"), stem.with_suffix(".h5")
    if (zpath / "done").exists() and hpath.exists():
        return zpath, hpath
    group = zarr.open_group(str(zpath), mode="w")
    rng = np.random.default_rng(0)
    with h5py.File(hpath, "w") as h5:
        for r in range(runs):
            u = burgers_run(rng)
            group.create_array(f"run{r:03d}", shape=u.shape, chunks=(250, POINTS),
                               dtype="f8", compressors=None)[:] = u
            h5.create_dataset(f"run{r:03d}", data=u, chunks=(250, POINTS))
    (zpath / "done").write_text("complete\n")
    return zpath, hpath


def new_model():
    import discrepancy as dc
    from discrepancy.symbolic import symbol

    return dc.PDEDiscrepancyModel(prior=[-symbol("u") * symbol("u_x")])


def grid():
    import discrepancy as dc

    return dc.Grid(np.linspace(0, 2 * np.pi, POINTS, endpoint=False), periodic=True)


def child(kind: str, zpath: str, hpath: str, runs: int, cap_mb: float) -> dict:
    """One measurement in this (fresh) process; ``cap_mb`` > 0 limits its address space."""
    if cap_mb > 0:
        import resource
        cap = int(cap_mb * 2 ** 20)
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    import discrepancy as dc

    names = [f"run{r:03d}" for r in range(runs)]
    start = time.perf_counter()
    extra = {}
    try:
        if kind in ("stream-zarr", "stream-hdf5"):
            path = zpath if kind == "stream-zarr" else hpath
            source = dc.FieldSource([(path, n) for n in names], grid=grid(), dt=DT)
            model = new_model().fit(source, grid=grid(), progress=False)
        elif kind.startswith("memory"):
            import zarr

            group = zarr.open_group(zpath, mode="r")
            model = new_model().fit([group[n][:] for n in names], t=DT, grid=grid())
        elif kind == "dask":
            model, extra = dask_fit(zpath, names)
        else:
            return peer(zpath)
    except MemoryError as e:
        return {"failed": f"{type(e).__name__}: {str(e)[:120]}", "peak_mb": peak_rss_mb(),
                "seconds": time.perf_counter() - start}
    return {"seconds": time.perf_counter() - start, "peak_mb": peak_rss_mb(),
            "values": int(runs * SNAPSHOTS * POINTS), "coef": model.coefficients().tolist(),
            "terms": model.equations(5)[0], **extra}


def dask_fit(zpath: str, names: list[str]):
    import dask.array as da
    import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        arrays = [da.from_zarr(zpath, component=n) for n in names]
        model = new_model().fit(arrays, t=DT, grid=grid(), progress=False)
        workers = client.run(peak_rss_mb)
    return model, {"worker_peak_mb": sorted(workers.values())}


def peer(zpath: str) -> dict:
    """PySINDy's weak form and PDE-FIND, and ours, on the first PEER_RUNS runs in memory."""
    import zarr

    sys.path.insert(0, str(os.path.join(os.path.dirname(__file__), "..", "paper", "src")))
    from discrepancy_paper.experiments import pde_pysindy

    group = zarr.open_group(zpath, mode="r")
    runs = [group[f"run{r:03d}"][:] for r in range(PEER_RUNS)]
    t = np.arange(SNAPSHOTS) * DT
    out = {}
    for kind in ("weak", "pde-find"):
        start = time.perf_counter()
        for u in runs:          # PySINDy's weak library takes one grid: one fit per run
            fit = pde_pysindy.fit(kind, u[..., None], t, grid(), field_names=["u"], degree=3,
                                  order=4, threshold=0.025, include_bias=True)
        out[kind] = {"seconds": time.perf_counter() - start, "terms": fit["coefficients"]}
    start = time.perf_counter()
    model = new_model().fit(runs, t=DT, grid=grid())
    out["ours"] = {"seconds": time.perf_counter() - start, "terms": model.equations(5)[0]}
    out["values"] = PEER_RUNS * SNAPSHOTS * POINTS
    return out


def run_child(kind: str, zpath, hpath, runs: int, cap_mb: float) -> dict:
    # one malloc arena: glibc otherwise reserves 64 MB of address space per thread (zarr's
    # I/O threads), which a cap on address space would count as if it were used
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1",
           "MALLOC_ARENA_MAX": "1"}
    out = subprocess.run([sys.executable, __file__, "--child", kind, str(zpath), str(hpath),
                          str(runs), str(cap_mb)], capture_output=True, text=True, env=env)
    if out.returncode != 0:
        return {"failed": out.stderr.strip().splitlines()[-1][:160] if out.stderr else "?",
                "peak_mb": float("nan"), "seconds": float("nan")}
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(runs: int, cap_mb: float):
    field_mb = runs * SNAPSHOTS * POINTS * 8 / 2 ** 20
    cap_mb = cap_mb or min(700.0, 0.75 * field_mb)
    print(f"## Burgers field of {runs * SNAPSHOTS * POINTS:.2e} values ({field_mb:.0f} MB), "
          f"{runs} runs, streamed, on Dask and in memory\n")
    print(machine() + "\n")
    zpath, hpath = write_data(runs)
    results = {}
    for kind, cap in (("memory", 0), ("memory-capped", cap_mb), ("stream-zarr", cap_mb),
                      ("stream-hdf5", cap_mb), ("dask", 0), ("peer", 0)):
        results[kind] = run_child(kind, zpath, hpath, runs, cap)
        print(f"  {kind}: {results[kind].get('seconds', float('nan')):.1f} s", file=sys.stderr)
    ref = np.asarray(results["memory"]["coef"])
    labels = {"memory": "ours, in memory (whole field loaded), no cap",
              "memory-capped": f"ours, in memory, address space capped at {cap_mb:.0f} MB",
              "stream-zarr": f"ours, streamed from zarr, capped at {cap_mb:.0f} MB",
              "stream-hdf5": f"ours, streamed from HDF5, capped at {cap_mb:.0f} MB",
              "dask": "ours, Dask LocalCluster (2 workers x 1 thread), from zarr"}
    rows = []
    for kind, label in labels.items():
        r = results[kind]
        if "failed" in r:
            rows.append([label, "fails: " + r["failed"], "", "", "", ""])
            continue
        peak = f"{r['peak_mb']:.0f}"
        if "worker_peak_mb" in r:
            peak += " (client); workers " + ", ".join(f"{w:.0f}" for w in r["worker_peak_mb"])
        rows.append([label, f"{r['seconds']:.0f}", f"{r['values'] / r['seconds']:.2e}", peak,
                     r["terms"], same(r["coef"], ref, rtol=1e-10, atol=1e-14)])
    print(table(["fit", "seconds", "values/s", "peak RSS (MB)", "learned g (true +0.05 u_xx)",
                 "coefficients equal the in-memory fit (rtol 1e-10)"], rows))
    p = results["peer"]
    print(f"\nSame {p['values']:.1e} values ({PEER_RUNS} runs) in memory, one process: ours "
          f"{p['ours']['seconds']:.1f} s ({p['ours']['terms']}); PySINDy weak form "
          f"{p['weak']['seconds']:.1f} s ({p['weak']['seconds'] / p['ours']['seconds']:.1f}x "
          f"ours; {p['weak']['terms']}); PySINDy PDE-FIND {p['pde-find']['seconds']:.1f} s "
          f"({p['pde-find']['seconds'] / p['ours']['seconds']:.1f}x; "
          f"{p['pde-find']['terms']}). PySINDy identifies the whole equation (true: -1 u u_x "
          "+ 0.05 u_xx) with a threshold set from the truth; it has no streamed or Dask fit.")
    print(f"\nThe field is {field_mb:.0f} MB; the capped fits may use {cap_mb:.0f} MB of address "
          "space in all (Python, numpy, scipy, sympy and zarr/h5py included).")


if __name__ == "__main__":
    if "--child" in sys.argv:
        i = sys.argv.index("--child")
        kind, zpath, hpath, runs, cap = sys.argv[i + 1:i + 6]
        print(json.dumps(child(kind, zpath, hpath, int(runs), float(cap))))
    else:
        runs = int(sys.argv[sys.argv.index("--runs") + 1]) if "--runs" in sys.argv else 120
        cap = float(sys.argv[sys.argv.index("--cap-mb") + 1]) if "--cap-mb" in sys.argv else 0
        main(runs, cap)
