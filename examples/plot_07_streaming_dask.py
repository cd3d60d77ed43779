"""
Streaming a file larger than memory, and a Dask cluster
=======================================================

A fit only needs sums over samples: ``ΘᵀΘ`` (p×p), ``Θᵀy``, ``Σ y²`` and the count. So the
data can stream from files chunk by chunk, with memory bounded by a chunk and not by the
data, and a cluster can compute the sums of each file where the file is and add them. Both
give the model of the in-memory fit.

The system: Lorenz (``ρ = 28``) modelled with ``ρ = 20``; the discrepancy is ``8 x1`` in the
second equation. Four recordings, each in its own HDF5 file. Needs the ``[scale]`` extra.
"""

import tempfile
import tracemalloc
from pathlib import Path

import h5py
import matplotlib.pyplot as plt
import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import discrepancy as dc

x1, x2, x3 = sp.symbols("x1 x2 x3", real=True)
prior = [10 * (x2 - x1), x1 * (20 - x3) - x2, x1 * x2 - sp.Rational(8, 3) * x3]   # ρ = 20


def lorenz(t, x):
    return [10 * (x[1] - x[0]), x[0] * (28 - x[2]) - x[1], x[0] * x[1] - 8 / 3 * x[2]]


dt, rows = 0.002, 150_000
folder = Path(tempfile.mkdtemp())
rng = np.random.default_rng(0)
for k in range(4):
    x = solve_ivp(lorenz, (0, rows * dt), rng.uniform(-10, 10, 3), t_eval=np.arange(rows) * dt,
                  method="DOP853", rtol=1e-9, atol=1e-9).y.T
    with h5py.File(folder / f"run{k}.h5", "w") as f:
        f["x"] = x + 0.01 * rng.standard_normal(x.shape)
data_bytes = sum(p.stat().st_size for p in folder.glob("*.h5"))
print(f"4 files, {4 * rows:,} samples, {data_bytes / 2**20:.1f} MiB")


def new_model():
    return dc.DiscrepancyModel(prior=prior, feature_library=dc.PolynomialLibrary(2),
                               differentiation_method=dc.SavitzkyGolay(window_length=31),
                               state_names=["x1", "x2", "x3"])


# %%
# Memory bounded by the chunk, not by the data
# --------------------------------------------
# A file larger than the machine's memory cannot be made on the machine that builds this
# page, so the claim is shown the other way round: the memory a streamed fit needs does
# not grow with the data. Python's ``tracemalloc`` (which sees numpy's arrays) measures the
# peak while one file, then all four, stream in chunks of 16384 rows.


def streamed_fit(paths):
    tracemalloc.start()
    model = new_model().fit(dc.HDF5Source(paths, x="x", chunk_size=16384), t=dt)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return model, peak


files = sorted(folder.glob("*.h5"))
streamed_fit(files[0])            # once first: one-off costs (imports, compiled terms) aside
_, peak_one = streamed_fit(files[0])
streamed, peak_all = streamed_fit(files)
streamed.print(precision=3)
print(f"peak memory of the streamed fit: {peak_one / 2**20:.1f} MiB for one file, "
      f"{peak_all / 2**20:.1f} MiB for all four ({data_bytes / 2**20:.1f} MiB of data)")
assert peak_all < 1.25 * peak_one and peak_all < data_bytes   # 4x the data, ~the same peak

fig, ax = plt.subplots(figsize=(6, 2.8))
labels = ["data on disk\n(4 files)", "streamed fit,\n1 file", "streamed fit,\n4 files"]
ax.bar(labels, np.array([data_bytes, peak_one, peak_all]) / 2**20, color=["0.6", "C0", "C0"])
ax.set(ylabel="MiB", title="peak memory of a streamed fit (tracemalloc)")
fig.tight_layout()

coef = dict(zip(streamed.get_feature_names(), streamed.coefficients()[1]))
assert abs(coef["x1"] - 8) < 0.05 and sum(c != 0 for c in coef.values()) == 1

# %%
# The same model as in memory
# ---------------------------
in_memory = new_model().fit([dc.io.load(p).x for p in files], t=dt)
difference = np.max(np.abs(in_memory.coefficients() - streamed.coefficients()))
print(f"largest difference from the in-memory fit: {difference:.1e}")
assert difference < 1e-9

# %%
# On a Dask cluster
# -----------------
# A small local cluster (a scheduler and two workers, here threads of this process, so the
# page builds anywhere) stands in for a real one; each file is one task that streams it on a
# worker, and only the p×p statistics travel back. Connect a ``Client`` to your scheduler's
# address instead and the code is the same (a script that starts worker *processes* itself
# needs its code under ``if __name__ == "__main__":``, as any multiprocessing script).

from distributed import Client, LocalCluster  # noqa: E402

from discrepancy.distributed import fit_sources  # noqa: E402

with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                  dashboard_address=None) as cluster, Client(cluster) as client:
    sources = [dc.HDF5Source(p, x="x", chunk_size=16384) for p in files]
    on_cluster = fit_sources(new_model(), sources, t=dt)
    print(f"fitted by {len(client.scheduler_info()['workers'])} workers")
difference = np.max(np.abs(on_cluster.coefficients() - streamed.coefficients()))
print(f"largest difference between the cluster's fit and the streamed one: {difference:.1e}")
assert difference < 1e-9
