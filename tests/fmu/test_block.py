"""The `fmu` block under ctlgraph's stepping API (Python): a run holding an
FMU instance returns to a snapshot and replays to the bit — the snapshot
copies the FMU's own state (FMI's serialised state) into a new instance.

Run by `.ci/run` beside test_fmpy.py (CTLGRAPH_BIN exports the FMU).
"""

import os
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("CTLGRAPH_BIN", str(ROOT / "target" / "debug" / "ctlgraph"))
# The FMU block unpacks into the cache this process names (before any graph loads).
os.environ["CTLGRAPH_CACHE_DIR"] = str(ROOT / "target" / "tmp" / "accelerate-cache")

import ctlgraph  # noqa: E402

GRAPH = """name: plant as an FMU, stepped
simulation: { stop: 5, solver: { method: rk4, step: 0.01 } }
blocks:
  cmd:   { type: inport, width: 2 }
  plant: { type: fmu, file: plant.fmu, sample_time: 0.05, parameters: { gain: 3 } }
  y:     { type: outport }
wires: [cmd -> plant.u, plant.y -> y]
"""


def test_a_snapshot_of_a_run_with_an_fmu_block_replays_to_the_bit(tmp_path):
    fmu = tmp_path / "plant.fmu"
    done = subprocess.run([BIN, "fmu", str(ROOT / "tests/fmu/plant_io.yaml"), "--out", str(fmu)], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    graph = tmp_path / "stepped.yaml"
    graph.write_text(GRAPH)
    sim = ctlgraph.load(str(graph))

    def run(times):
        out = []
        for k, t in enumerate(times):
            sim.set_input("cmd", [1.0 + 0.1 * k, -0.5])
            sim.advance_to(t)
            out.append(list(sim.output("y")))
        return out

    run([0.5, 1.0, 1.5])
    snapshot = sim.state()
    later = run([2.0, 2.5, 3.0, 3.5])
    sim.restore(snapshot)
    again = run([2.0, 2.5, 3.0, 3.5])
    assert later == again
    assert later[0] != later[-1]
