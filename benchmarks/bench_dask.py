"""Dask LocalCluster fit of the same 1e8-sample zarr file as bench_streaming.py: 2 worker
processes with one thread each, on loopback; throughput, workers' peak memory, and the
coefficients against the in-memory fit (from bench_streaming's saved result, else streamed).

Run: .venv/bin/python benchmarks/bench_dask.py [--rows N]
"""
from __future__ import annotations

import json
import sys
import time
import warnings

from _common import BIG_CHUNK, BIG_ROWS, DATA_DIR, DT, big_zarr, machine, same, table
from bench_streaming import PEER_ROWS, new_model, run_child

warnings.filterwarnings("ignore")


def _peak_mb():
    """VmHWM of the calling (worker) process, MB."""
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmHWM")) / 1024


def main(rows: int):
    import dask.array as da
    from distributed import Client, LocalCluster

    print(f"## Dask LocalCluster fit of {rows:.0e} samples from zarr (degree 5, x_dot given)\n")
    print(machine() + "\n")
    path = big_zarr(rows)
    saved = DATA_DIR / f"reference_{rows:.0e}.json".replace("+", "")
    if saved.exists():
        ref = json.loads(saved.read_text())
    else:
        ref = run_child("memory" if rows <= 10_000_000 else "stream", path)
        saved.write_text(json.dumps(ref))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        x = da.from_zarr(str(path), component="x")
        xd = da.from_zarr(str(path), component="x_dot")
        new_model().fit(x[:100_000], t=DT, x_dot=xd[:100_000])  # warm-up: workers' imports
        t0 = time.perf_counter()
        model = new_model().fit(x, t=DT, x_dot=xd)
        seconds = time.perf_counter() - t0
        worker_peak = max(client.run(_peak_mb).values())
    peer = run_child("peer", path)
    n = model.statistics_.count
    body = [
        [f"ours, Dask LocalCluster (2 processes x 1 thread), blocks of {BIG_CHUNK:.0e} rows",
         f"{n:.0e}", f"{seconds:.1f}", f"{n / seconds:.2e}", f"{worker_peak:.0f} per worker",
         same(model.coefficients(), ref["coef"], rtol=1e-10, atol=1e-12)],
        [f"PySINDy 2.x, in memory, first {PEER_ROWS:.0e} rows (median of 3, 1 BLAS thread)",
         f"{PEER_ROWS:.0e}", f"{peer['seconds']:.3f}", f"{PEER_ROWS / peer['seconds']:.2e}",
         f"{peer['peak_mb']:.0f}", "(other data)"],
    ]
    print(table(["fit", "samples", "seconds", "samples/s", "peak RSS (MB)",
                 f"coefficients equal the reference fit ({ref.get('kind', 'in memory')})"],
                body))
    print(f"\nRows counted by the reduction: {n} (expected {rows}). One run (1e8 rows is "
          "expensive), after a 1e5-row warm-up fit that lets the workers import the library. "
          "The Dask graph sums per-block Gram statistics as a tree; both worker processes share "
          "this machine's 2 cores, and on a cluster the same graph spreads over its workers.")


if __name__ == "__main__":
    main(int(float(sys.argv[sys.argv.index("--rows") + 1])) if "--rows" in sys.argv
         else BIG_ROWS)
