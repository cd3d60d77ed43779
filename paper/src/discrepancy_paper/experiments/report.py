"""Writing an experiment's output: figures (PNG), ``report.md`` and ``results.json``.

Every experiment writes ``DIR/NAME/`` with its figures next to a Markdown report
and a JSON file of figures of merit under self-explanatory keys.
"""
from __future__ import annotations

import json
import math
import os
import platform
import time
from pathlib import Path

import numpy as np


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else str(v)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.bool_,)):
        return bool(value)
    return value


def machine() -> dict:
    """The processor, its logical CPUs and the load average now (for timings)."""
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if "model name" in line)
    except (OSError, StopIteration):
        pass
    return {"processor": cpu, "logical_cpus": os.cpu_count(),
            "load_average_1_5_15_min": [round(v, 2) for v in os.getloadavg()]}


class Report:
    """Collects Markdown sections, figures and results of one experiment.

    Usage::

        rep = Report(out_dir, "vdp-parameter", title="Van der Pol, parameter mismatch")
        rep.text("Some *markdown*.")
        rep.figure(fig, "trajectories.png", "Measured vs prior vs hybrid")
        rep.results["coefficients"] = {...}
        rep.write()            # writes report.md and results.json
    """

    def __init__(self, out_dir, name: str, *, title: str):
        self.name = name
        self.dir = Path(out_dir) / name
        self.dir.mkdir(parents=True, exist_ok=True)
        self.title = title
        self.lines: list[str] = [f"# {title}", ""]
        self.results: dict = {"experiment": name}
        self.figures: list[str] = []
        self._t0 = time.perf_counter()

    def text(self, markdown: str) -> None:
        self.lines += [markdown.rstrip(), ""]

    def table(self, header: list[str], rows: list[list]) -> None:
        fmt = [lambda v: f"{v:.4g}" if isinstance(v, (float, np.floating)) else str(v)]
        self.lines.append("| " + " | ".join(header) + " |")
        self.lines.append("|" + "---|" * len(header))
        for row in rows:
            self.lines.append("| " + " | ".join(fmt[0](v) for v in row) + " |")
        self.lines.append("")

    def figure(self, fig, filename: str, caption: str) -> Path:
        import matplotlib.pyplot as plt

        path = self.dir / filename
        fig.savefig(path, dpi=110, bbox_inches="tight")
        plt.close(fig)
        self.figures.append(filename)
        self.lines += [f"![{caption}]({filename})", "", f"*{caption}*", ""]
        return path

    def write(self) -> Path:
        self.results.setdefault("figures", self.figures)
        self.results["wall_time_s"] = round(time.perf_counter() - self._t0, 3)
        (self.dir / "report.md").write_text("\n".join(self.lines) + "\n")
        (self.dir / "results.json").write_text(json.dumps(_jsonable(self.results), indent=2) + "\n")
        return self.dir
