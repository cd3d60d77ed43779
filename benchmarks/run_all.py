"""Run every benchmark and write its printed tables into benchmarks/RESULTS.md.

Each benchmark's output replaces the text between its markers
``<!-- NAME:start -->`` and ``<!-- NAME:end -->``; the rest of RESULTS.md (the
discussion) is kept. The 1e8-sample benchmarks take minutes and 4.8 GB of disk
under benchmarks/_data/; ``--skip-big`` leaves their previous results in place.

Run: .venv/bin/python benchmarks/run_all.py [--skip-big] [--only bench_fit ...]
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
BENCHES = ["bench_fit", "bench_simulate", "bench_streaming", "bench_dask", "bench_dequantise",
           "bench_block_fit", "bench_mpc", "bench_estimation", "bench_output_error",
           "bench_energy_blind", "bench_pde"]
BIG = {"bench_streaming", "bench_dask", "bench_pde"}


def replace_section(text: str, name: str, body: str) -> str:
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    block = f"{start}\n{body.strip()}\n{end}"
    if start in text:
        return re.sub(re.escape(start) + r".*?" + re.escape(end), lambda _: block, text,
                      flags=re.S)
    return text.rstrip() + "\n\n" + block + "\n"


def main(argv: list[str]) -> int:
    chosen = [a for a in argv if not a.startswith("--")] or BENCHES
    if "--skip-big" in argv:
        chosen = [b for b in chosen if b not in BIG]
    results = HERE / "RESULTS.md"
    text = results.read_text() if results.exists() else "# Benchmark results\n"
    failed = 0
    for name in chosen:
        print(f"running {name} ...", file=sys.stderr, flush=True)
        run = subprocess.run([sys.executable, str(HERE / f"{name}.py")], capture_output=True,
                             text=True)
        if run.returncode != 0:
            failed += 1
            print(run.stderr[-3000:], file=sys.stderr)
            continue
        print(run.stdout)
        text = replace_section(text, name, run.stdout)
        results.write_text(text)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
