"""Shared pieces of the benchmarks: Lorenz data, timing, tables, machine description."""
from __future__ import annotations

import os
import platform
import time

import numpy as np

DT = 0.002
SIGMA, RHO, BETA = 10.0, 28.0, 8.0 / 3.0


def lorenz(x: np.ndarray) -> np.ndarray:
    """Lorenz right-hand side, ``x`` ``(m, 3)``."""
    return np.c_[SIGMA * (x[:, 1] - x[:, 0]), x[:, 0] * (RHO - x[:, 2]) - x[:, 1],
                 x[:, 0] * x[:, 1] - BETA * x[:, 2]]


def rk4_step(x: np.ndarray, dt: float = DT) -> np.ndarray:
    k1 = lorenz(x)
    k2 = lorenz(x + dt / 2 * k1)
    k3 = lorenz(x + dt / 2 * k2)
    k4 = lorenz(x + dt * k3)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def lorenz_trajectories(n_traj: int, steps: int, seed: int = 0, settle: int = 500):
    """``n_traj`` Lorenz trajectories of ``steps`` samples at ``DT`` (RK4), ``(n_traj, steps, 3)``,
    started from random points and run ``settle`` steps onto the attractor first."""
    rng = np.random.default_rng(seed)
    x = rng.uniform([-15, -15, 5], [15, 15, 40], size=(n_traj, 3))
    for _ in range(settle):
        x = rk4_step(x)
    out = np.empty((steps, n_traj, 3))
    for i in range(steps):
        out[i] = x
        x = rk4_step(x)
    return np.ascontiguousarray(out.transpose(1, 0, 2))


def median_time(f, reps: int):
    """Median wall time of ``reps`` calls of ``f`` and the last result."""
    times, out = [], None
    for _ in range(reps):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def table(headers, rows) -> str:
    """Markdown table."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def machine() -> str:
    """One paragraph describing the machine and the numerical libraries."""
    import numpy
    import pysindy
    from threadpoolctl import threadpool_info

    from discrepancy_paper.experiments.report import machine as processor

    cpu = processor()["processor"]
    try:
        mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    except (ValueError, OSError):
        mem = float("nan")
    blas = [f"{i['internal_api']} {i.get('version')} ({i.get('architecture')}, "
            f"{i['num_threads']} threads)" for i in threadpool_info() if i["user_api"] == "blas"]
    core = os.environ.get("OPENBLAS_CORETYPE", "not set")
    return (f"{cpu}, {os.cpu_count()} logical CPUs, {mem:.0f} GiB RAM, {platform.system()} "
            f"{platform.release()}; Python {platform.python_version()}, numpy {numpy.__version__}, "
            f"PySINDy {pysindy.__version__}; BLAS: {'; '.join(blas)}; OPENBLAS_CORETYPE={core}. "
            f"Load average at start: {', '.join(f'{v:.2f}' for v in os.getloadavg())} "
            "(the machine is shared, so timings are noisy: medians of repeated runs).")


def same(a, b, rtol=1e-6, atol=1e-9) -> str:
    a, b = np.asarray(a), np.asarray(b)
    ok = a.shape == b.shape and np.allclose(a, b, rtol=rtol, atol=atol)
    return f"{'yes' if ok else 'NO'} ({np.abs(a - b).max():.1e})" if a.shape == b.shape else "NO"


DATA_DIR = __import__("pathlib").Path(__file__).parent / "_data"
BIG_ROWS = 100_000_000
BIG_CHUNK = 1_000_000


def big_zarr(rows: int = BIG_ROWS):
    """Path of a zarr group with Lorenz ``x`` and ``x_dot`` ``(rows, 3)`` under ``_data/``,
    written once in pieces (1000 trajectories of rows/1000 samples each, one after another)."""
    import shutil

    import zarr

    path = DATA_DIR / f"lorenz_{rows:.0e}.zarr".replace("+", "")
    if (path / "done").exists():
        return path
    free = shutil.disk_usage(DATA_DIR.parent).free
    if free < 3 * rows * 48:
        raise SystemExit(f"need about {rows * 48 / 1e9:.1f} GB free for {path}; "
                         f"{free / 1e9:.1f} GB free")
    DATA_DIR.mkdir(exist_ok=True)
    g = zarr.open_group(str(path), mode="w")
    # uncompressed: chaotic float64 data barely compresses, and zstd made reads 4x slower
    x = g.create_array("x", shape=(rows, 3), chunks=(BIG_CHUNK, 3), dtype="f8", compressors=None)
    xd = g.create_array("x_dot", shape=(rows, 3), chunks=(BIG_CHUNK, 3), dtype="f8",
                        compressors=None)
    n_traj, groups = 1000, 10
    steps = rows // n_traj
    per = n_traj // groups
    for k in range(groups):
        block = lorenz_trajectories(per, steps, seed=100 + k).reshape(-1, 3)
        a = k * per * steps
        x[a:a + block.shape[0]] = block
        xd[a:a + block.shape[0]] = lorenz(block)
        print(f"  wrote rows {a}..{a + block.shape[0] - 1}", file=__import__("sys").stderr)
    (path / "done").write_text("complete\n")
    return path


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far (MB): VmHWM from /proc (getrusage's
    ru_maxrss would include the parent's peak, which Linux carries across exec)."""
    try:
        with open("/proc/self/status") as f:
            return next(int(line.split()[1]) for line in f if line.startswith("VmHWM")) / 1024
    except (OSError, StopIteration):
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
