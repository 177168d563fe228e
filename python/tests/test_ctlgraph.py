"""ctlgraph from Python: the same numbers as the CLI, threads, errors with
positions, stepping, snapshots, docstrings.

Run from the repository root after building the CLI (`cargo build`); the
CLI binary is $CTLGRAPH_BIN, or target/debug/ctlgraph.
"""

import csv
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import ctlgraph

ROOT = Path(__file__).resolve().parents[2]
CLI = Path(os.environ.get("CTLGRAPH_BIN", ROOT / "target" / "debug" / "ctlgraph"))


def graph(name):
    return str(ROOT / "graphs" / name)


def cli_csv(tmp_path, args):
    """Runs `ctlgraph run ARGS --out FILE` and reads the CSV exactly."""
    assert CLI.exists(), f"build the CLI first (cargo build): no {CLI}"
    out = tmp_path / "out.csv"
    done = subprocess.run([str(CLI), "run", *args, "--out", str(out)], capture_output=True)
    assert done.returncode in (0, 1), done.stderr  # 1: a check failed, the CSV is whole
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header, values = rows[0], np.array([[float(v) for v in row] for row in rows[1:]])
    return {name: values[:, k] for k, name in enumerate(header)}


@pytest.mark.parametrize(
    "name, cli_args, kwargs",
    [
        ("tutorial/pid_loop.yaml", ["--set", "kp=3.5"], {"set": {"kp": 3.5}}),
        ("fladrc/fladrc.yaml", ["--seed", "7"], {"seed": 7}),
        ("milling/hinf.yaml", ["--stop-time", "0.05"], {"stop": 0.05}),
    ],
)
def test_results_equal_the_cli_csv_bit_for_bit(tmp_path, name, cli_args, kwargs):
    expected = cli_csv(tmp_path, [graph(name), *cli_args])
    result = ctlgraph.run(graph(name), **kwargs)
    assert ["t", *result.names] == list(expected)
    assert np.array_equal(result.t, expected["t"])
    for column in result.names:
        assert result[column].dtype == np.float64
        assert np.array_equal(result[column], expected[column]), column


def test_a_value_changed_after_a_run_still_equals_the_cli(tmp_path):
    # The second run compiles on the first's structure (the graph cache);
    # its numbers are a fresh compile's, so the CLI's.
    first = ctlgraph.run(graph("tutorial/pid_loop.yaml"), set={"kp": 1.0})
    expected = cli_csv(tmp_path, [graph("tutorial/pid_loop.yaml"), "--set", "kp=3.5"])
    again = ctlgraph.run(graph("tutorial/pid_loop.yaml"), set={"kp": 3.5})
    assert not np.array_equal(first["y"], again["y"])
    for column in again.names:
        assert np.array_equal(again[column], expected[column]), column


def test_checks_and_stats():
    result = ctlgraph.run(graph("tutorial/pid_loop.yaml"))
    assert [c.name for c in result.checks][2] == "steady"
    assert all(c.passed for c in result.checks) and result.passed
    steady = result.checks[2]
    assert steady.op == "<" and steady.bound == 1e-3 and 0 <= steady.measured < 1e-3
    assert result.stats["major_steps"] == len(result.t) - 1  # every major step recorded, t = 0 too
    assert result.stats["evaluations"] > result.stats["solver_steps"] > 0
    failing = ctlgraph.run(graph("tutorial/pid_loop.yaml"), set={"ki": 0, "kp": "wn / 5"})
    assert not failing.passed and not failing.checks[2].passed
    with pytest.raises(KeyError, match="recorded: t, r, y, u, e"):
        failing["nope"]


def test_threads_run_graphs_in_parallel_with_the_same_results():
    seeds = list(range(1, 9))
    alone = [ctlgraph.run(graph("fladrc/fladrc.yaml"), seed=s)["y"] for s in seeds]
    with ThreadPoolExecutor(max_workers=4) as pool:
        together = list(pool.map(lambda s: ctlgraph.run(graph("fladrc/fladrc.yaml"), seed=s)["y"], seeds))
    for a, b in zip(alone, together):
        assert np.array_equal(a, b)
    assert not np.array_equal(alone[0], alone[1]), "the seeds change the noise"


def test_a_bad_graph_raises_graph_error_at_its_position(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("blocks:\n  r: { type: step }\n  g: { type: gain, kk: 2 }\nwires: [r -> g]\n")
    with pytest.raises(ctlgraph.GraphError) as caught:
        ctlgraph.run(str(bad))
    e = caught.value
    assert (e.file, e.line, e.column) == (str(bad), 3, 20)
    assert e.message == "block `g` (gain): unknown parameter `kk`"
    assert e.hint == "did you mean `k`?"
    assert str(e).startswith(f"{bad}:3:20: block `g`")
    with pytest.raises(ctlgraph.GraphError) as caught:
        ctlgraph.check(str(tmp_path / "missing.yaml"))
    assert caught.value.line is None and caught.value.file.endswith("missing.yaml")


def test_a_run_that_blows_up_raises_simulation_error(tmp_path):
    unstable = tmp_path / "unstable.yaml"
    unstable.write_text(
        "simulation: { stop: 10, solver: { method: rk4, step: 0.01 } }\n"
        "blocks:\n  one: { type: constant, value: 1 }\n  x: { type: integrator }\n"
        "  square: { type: fcn, expr: \"u1 * u1 * u1\" }\n  s: { type: sum, signs: \"++\" }\n"
        "wires: [one -> s.u1, square -> s.u2, s -> x, x -> square]\n"
    )
    with pytest.raises(ctlgraph.SimulationError, match="not finite|inf|NaN"):
        ctlgraph.run(str(unstable))


def test_stepping_equals_running():
    # 1 ms chunks on the fixed-step grid: the same numbers, bit for bit.
    result = ctlgraph.run(graph("fladrc/fladrc.yaml"))
    model = ctlgraph.load(graph("fladrc/fladrc.yaml"))
    for k in range(1, 2001):
        t = k * 1e-3
        model.advance_to(t)
        assert model.time == pytest.approx(t, abs=1e-12)
        i = int(np.argmin(np.abs(result.t - t)))
        assert model.signal("y") == result["y"][i], t


def test_inputs_outputs_and_snapshots():
    model = ctlgraph.load(graph("tutorial/controller_io.yaml"))
    assert model.inputs == ["y"] and model.outputs == ["u"]
    assert [b["name"] for b in model.blocks()] == ["r", "y", "e", "pid"]
    assert model.signals() == ["r", "y", "u", "e"]
    model.advance_to(0.2)
    model.set_input("y", 0.25)
    # The command at this instant already sees the measurement.
    assert model.signal("e") == 0.75
    snapshot = model.state()
    model.advance_to(0.5)
    later = model.output("u")
    model.restore(snapshot)
    assert model.time == snapshot.time == 0.2
    model.advance_to(0.5)
    assert model.output("u") == later
    with pytest.raises(ctlgraph.GraphError, match="did you mean `y`"):
        model.set_input("yy", 1.0)
    with pytest.raises(ctlgraph.SimulationError, match="cannot advance"):
        model.advance_to(0.1)


def test_an_accelerated_model_steps_as_the_interpreted_one(monkeypatch):
    # The cache the Rust tests fill (tests/accelerate.rs).
    monkeypatch.setenv("CTLGRAPH_CACHE_DIR", str(ROOT / "target" / "tmp" / "accelerate-cache"))
    name = graph("tutorial/controller_io.yaml")
    slow, fast = ctlgraph.load(name, set={"kp": 3}), ctlgraph.load(name, set={"kp": 3}, accelerate="require")
    assert fast.accelerated and not slow.accelerated and "accelerated" in repr(fast)
    assert fast.inputs == slow.inputs and fast.signals() == slow.signals()
    saved = None
    for k in range(1, 401):
        # A host's loop: measure, read the command at that instant, step on.
        for model in (slow, fast):
            model.set_input("y", 0.8 * np.sin(0.01 * k))
        assert fast.output("u") == slow.output("u"), k
        for model in (slow, fast):
            model.advance_to(k * 1e-3)
        assert fast.signal("e") == slow.signal("e") and fast.time == slow.time, k
        if k == 200:
            saved = fast.state()
    last = fast.output("u")
    fast.restore(saved)
    assert fast.time == saved.time == pytest.approx(0.2)
    for k in range(201, 401):
        fast.set_input("y", 0.8 * np.sin(0.01 * k))
        fast.advance_to(k * 1e-3)
    assert fast.output("u") == last
    with pytest.raises(ctlgraph.GraphError, match="did you mean `y`"):
        fast.set_input("yy", 1.0)
    with pytest.raises(ctlgraph.GraphError, match="another run"):
        fast.restore(slow.state())
    with pytest.raises(ctlgraph.SimulationError, match="cannot advance"):
        fast.advance_to(0.1)


def test_to_pandas():
    pandas = pytest.importorskip("pandas")
    frame = ctlgraph.run(graph("tutorial/pid_loop.yaml")).to_pandas()
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame.columns) == ["r", "y", "u", "e"] and frame.index.name == "t"


def test_help_shows_the_docstrings():
    assert "Runs the graph file" in ctlgraph.run.__doc__
    assert "step by step" in ctlgraph.Model.__doc__
    assert "file, line, column" in ctlgraph.GraphError.__doc__


def test_the_readmes_python_snippet_prints_what_it_shows():
    readme = (ROOT / "README.md").read_text()
    section = readme.split("## From Python", 1)[1]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    shown = section.split("prints\n\n", 1)[1].split("\n\n", 1)[0]
    expected = [line[4:] for line in shown.splitlines()]
    printed = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert printed == expected


def test_linearize_is_the_clis(tmp_path):
    out = tmp_path / "lin.json"
    args = [str(CLI), "linearize", graph("tutorial/pid_loop.yaml"), "--open", "ctrl.u", "--out", str(out)]
    subprocess.run(args, check=True, capture_output=True)
    expected = json.loads(out.read_text())
    lin = ctlgraph.linearize(graph("tutorial/pid_loop.yaml"), open="ctrl.u")
    for name in "ABCD":
        assert np.array_equal(lin[name], np.array(expected[name.lower()])), name
    assert lin["states"] == expected["states"] and lin["loop_transfer"]
    poles = sorted((p.real, p.imag) for p in lin["poles"])
    assert poles == sorted((p["re"], p["im"]) for p in expected["poles"])
    assert 0 < lin["margins"]["phase_margin"] < 90
    with pytest.raises(ctlgraph.GraphError, match="no block `nope`"):
        ctlgraph.linearize(graph("tutorial/pid_loop.yaml"), open="nope")


def test_sweep_is_the_clis(tmp_path):
    out = tmp_path / "sweep.csv"
    args = ["sweep", graph("tutorial/pid_loop.yaml"), "--vary", "kp=1..4:4", "--vary", "kd=0,0.1", "--out", str(out)]
    done = subprocess.run([str(CLI), *args], capture_output=True)
    assert done.returncode in (0, 1), done.stderr
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    table = ctlgraph.sweep(graph("tutorial/pid_loop.yaml"), vary={"kp": "1..4:4", "kd": [0.0, 0.1]}, jobs=2)
    assert list(table["kp"]) == [float(r["kp"]) for r in rows]
    assert list(table["kd"]) == [float(r["kd"]) for r in rows]
    assert table["status"] == [r["status"] for r in rows]
    assert np.array_equal(table["steady"], [float(r["steady"]) for r in rows])
    assert table["steady passed"] == [r["steady passed"] == "true" for r in rows]


def test_accelerated_runs_and_sweeps_equal_the_interpreted(monkeypatch):
    # The cache the Rust tests fill (tests/accelerate.rs), so the step is
    # built once per checkout.
    monkeypatch.setenv("CTLGRAPH_CACHE_DIR", str(ROOT / "target" / "tmp" / "accelerate-cache"))
    name = graph("tutorial/pid_loop.yaml")
    plain = ctlgraph.run(name, set={"kp": 2.5})
    fast = ctlgraph.run(name, set={"kp": 2.5}, accelerate="require")
    assert "build_seconds" in fast.stats or "load_seconds" in fast.stats
    assert "load_seconds" not in plain.stats and "build_seconds" not in plain.stats
    for column in plain.names:
        assert np.array_equal(plain[column], fast[column]), column
    vary = {"kp": "1..4:3"}
    assert np.array_equal(
        ctlgraph.sweep(name, vary=vary)["steady"], ctlgraph.sweep(name, vary=vary, accelerate=True)["steady"]
    )


def test_without_a_toolchain_an_accelerated_run_warns_and_interprets(monkeypatch, tmp_path):
    monkeypatch.setenv("CTLGRAPH_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("PATH", "/nonexistent")
    with pytest.warns(RuntimeWarning, match="running interpreted, not accelerated: no Rust toolchain"):
        result = ctlgraph.run(graph("tutorial/first_order.yaml"), accelerate=True)
    assert len(result.t) > 100
    with pytest.raises(ctlgraph.GraphError, match="--accelerate=require: cannot accelerate"):
        ctlgraph.run(graph("tutorial/first_order.yaml"), accelerate="require")
    with pytest.raises(ValueError, match="accelerate"):
        ctlgraph.run(graph("tutorial/first_order.yaml"), accelerate="fast")
