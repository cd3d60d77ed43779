"""The examples of Kaheman et al. (2019), "Learning discrepancy models from experimental
data", and the benchmarks, reproduced with the ``discrepancy`` library: each writes figures,
``report.md`` and ``results.json``. Run ``discrepancy reproduce NAME --out DIR`` (or
``python -m discrepancy_paper reproduce NAME --out DIR``)."""
__version__ = "0.1.0"
