"""100 runs of the PID tutorial from a Python loop beside the same 100 runs
from the CLI in one process (`ctlgraph sweep --seeds 1..100 --jobs 1`),
measured side by side, 7 rounds, medians. Run from the repository root
with a release build of both (`pip install ./python`, `cargo build --release`):

    python python/bench/hundred_runs.py
"""

import statistics
import subprocess
import tempfile
import time

import ctlgraph

GRAPH = "graphs/tutorial/pid_loop.yaml"


def python_loop():
    start = time.perf_counter()
    for _ in range(100):
        ctlgraph.run(GRAPH)
    return time.perf_counter() - start


def cli(out):
    start = time.perf_counter()
    args = ["target/release/ctlgraph", "sweep", GRAPH, "--seeds", "1..100", "--jobs", "1", "--out", out]
    subprocess.run(args, check=True, capture_output=True)
    return time.perf_counter() - start


with tempfile.TemporaryDirectory() as tmp:
    out = f"{tmp}/runs.csv"
    python_loop(), cli(out)  # warm up
    rounds = [(python_loop(), cli(out)) for _ in range(7)]
py = statistics.median(r[0] for r in rounds)
sweep = statistics.median(r[1] for r in rounds)
print(f"Python loop: {1e3 * py:.1f} ms; CLI sweep: {1e3 * sweep:.1f} ms; Python / CLI = {py / sweep:.2f}")
