"""Streaming fit of 1e8 Lorenz samples (3 states, x_dot given, degree-5 library) from an
on-disk zarr file: throughput and peak memory, coefficients against the in-memory fit of
the same data, and PySINDy's in-memory throughput measured in the same run.

The file (4.8 GB: x and x_dot) is written once to benchmarks/_data/ (git-ignored).
Each measurement runs in a fresh child process so its peak memory (getrusage) is its own.

Run: .venv/bin/python benchmarks/bench_streaming.py [--rows N]
"""
from __future__ import annotations

import json
import subprocess
import sys
import time
import warnings

import numpy as np
from _common import BIG_CHUNK, BIG_ROWS, DATA_DIR, DT, big_zarr, machine, peak_rss_mb, same, table

warnings.filterwarnings("ignore")
PEER_ROWS = 100_000


def new_model():
    import discrepancy as dc

    return dc.DiscrepancyModel(feature_library=dc.PolynomialLibrary(degree=5),
                               optimizer=dc.STLSQ(threshold=0.1))


def child(kind: str, path: str) -> dict:
    import zarr
    from _common import median_time

    from discrepancy.data.sources import ZarrSource

    t0 = time.perf_counter()
    if kind == "stream":
        model = new_model().fit(ZarrSource(path, x_dot="x_dot", chunk_size=BIG_CHUNK), t=DT)
        rows = model.statistics_.count
    elif kind == "memory":
        g = zarr.open_group(path, mode="r")
        x, xd = g["x"][:], g["x_dot"][:]
        model = new_model().fit(x, t=DT, x_dot=xd)
        rows = x.shape[0]
    else:  # peers on the first PEER_ROWS rows, in memory
        import pysindy as ps
        from threadpoolctl import threadpool_limits

        g = zarr.open_group(path, mode="r")
        x, xd = g["x"][:PEER_ROWS], g["x_dot"][:PEER_ROWS]

        def peer():
            m = ps.SINDy(feature_library=ps.PolynomialLibrary(degree=5),
                         optimizer=ps.STLSQ(threshold=0.1))
            return np.asarray(m.fit(x, t=DT, x_dot=xd).coefficients())

        t_ours, _ = median_time(lambda: new_model().fit(x, t=DT, x_dot=xd), 3)
        with threadpool_limits(1, user_api="blas"):
            t_peer, coef = median_time(peer, 3)
        return {"rows": PEER_ROWS, "seconds": t_peer, "ours_seconds": t_ours,
                "coef": coef.tolist(), "peak_mb": peak_rss_mb()}
    return {"rows": int(rows), "seconds": time.perf_counter() - t0,
            "coef": model.coefficients().tolist(), "peak_mb": peak_rss_mb()}


def run_child(kind: str, path) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", kind, str(path)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(rows: int):
    print(f"## Streaming fit of {rows:.0e} samples from zarr (degree 5, x_dot given)\n")
    print(machine() + "\n")
    t0 = time.perf_counter()
    path = big_zarr(rows)
    print(f"(data file ready after {time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    stream = run_child("stream", path)
    print(f"  stream: {stream['seconds']:.1f} s", file=sys.stderr)
    memory = run_child("memory", path)
    print(f"  in memory: {memory['seconds']:.1f} s", file=sys.stderr)
    saved = DATA_DIR / f"reference_{rows:.0e}.json".replace("+", "")
    saved.write_text(json.dumps({**memory, "kind": "in memory"}))  # for bench_dask.py
    peer = run_child("peer", path)
    ref = np.asarray(memory["coef"])
    results = [
        ["ours, streamed from zarr (chunks of 1e6 rows)", stream],
        ["ours, in memory (whole file loaded)", memory],
    ]
    body = [[name, f"{r['rows']:.0e}", f"{r['seconds']:.1f}", f"{r['rows'] / r['seconds']:.2e}",
             f"{r['peak_mb']:.0f}", same(r["coef"], ref, rtol=1e-10, atol=0)]
            for name, r in results]
    body.append([f"ours, in memory, first {PEER_ROWS:.0e} rows (median of 3)", f"{PEER_ROWS:.0e}",
                 f"{peer['ours_seconds']:.3f}", f"{PEER_ROWS / peer['ours_seconds']:.2e}",
                 "", ""])
    body.append([f"PySINDy 2.x, in memory, first {PEER_ROWS:.0e} rows (median of 3, 1 BLAS "
                 "thread)", f"{PEER_ROWS:.0e}", f"{peer['seconds']:.3f}",
                 f"{PEER_ROWS / peer['seconds']:.2e}", f"{peer['peak_mb']:.0f}",
                 "(other data)"])
    print(table(["fit", "samples", "seconds", "samples/s", "peak RSS (MB)",
                 "coefficients equal the in-memory fit (rtol 1e-10)"], body))
    speedup = stream["rows"] / stream["seconds"] / (PEER_ROWS / peer["seconds"])
    print(f"\nStreamed throughput is {speedup:.0f}x "
          "PySINDy's in-memory throughput; PySINDy cannot fit 1e8 samples here at all (its "
          "feature matrix alone would take 1e8 x 56 x 8 B = 45 GB). One run each (1e8 rows "
          "is expensive); the peak RSS includes Python, numpy, zarr and the library (~150 MB).")


if __name__ == "__main__":
    if "--child" in sys.argv:
        i = sys.argv.index("--child")
        print(json.dumps(child(sys.argv[i + 1], sys.argv[i + 2])))
    else:
        main(int(float(sys.argv[sys.argv.index("--rows") + 1])) if "--rows" in sys.argv
             else BIG_ROWS)
