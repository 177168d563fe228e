"""ctlgraph's FMUs in a real importer: FMPy (PyPI) validates every FMU these
tests export and simulates it; the numbers equal `ctlgraph run` (and the
stepping API, for an input table) at every communication point.

Run by `.ci/run` in its virtual environment (FMPy and ctlgraph's Python
package installed), with CTLGRAPH_BIN naming the command line to export
with. The FMU binary is built once into the library cache the Rust tests
use (target/tmp/accelerate-cache), so it reuses their compiled crates.
"""

import csv
import os
import shutil
import subprocess
from pathlib import Path

import ctlgraph
import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]
BIN = os.environ.get("CTLGRAPH_BIN", str(ROOT / "target" / "debug" / "ctlgraph"))
ENV = dict(os.environ, CTLGRAPH_CACHE_DIR=str(ROOT / "target" / "tmp" / "accelerate-cache"))


def export(graph, out, fmi="3", sets=()):
    args = [BIN, "fmu", str(ROOT / graph), "--out", str(out), "--fmi", fmi]
    for s in sets:
        args += ["--set", s]
    done = subprocess.run(args, capture_output=True, text=True, env=ENV, timeout=900)
    assert done.returncode == 0, done.stderr
    assert f"FMI {fmi}.0 co-simulation FMU" in done.stdout
    problems = validate_fmu(str(out))
    assert problems == [], problems
    return out


def run_csv(graph, tmp_path, sets=()):
    """`ctlgraph run`'s rows: {column: array}."""
    out = tmp_path / (Path(graph).stem + ".csv")
    args = [BIN, "run", str(ROOT / graph), "--out", str(out)]
    for s in sets:
        args += ["--set", s]
    done = subprocess.run(args, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    with open(out) as f:
        rows = list(csv.reader(f))
    return {h: np.array([float(r[i]) for r in rows[1:]]) for i, h in enumerate(rows[0])}


def at_times(reference, times, name):
    """The reference column `name` at `times` (each a row's time within 1e-12)."""
    index = np.searchsorted(reference["t"], times - 1e-12)
    assert np.all(np.abs(reference["t"][index] - times) <= 1e-12)
    return reference[name][index]


@pytest.mark.parametrize("fmi", ["3", "2"])
def test_the_ladrc_loop_as_an_fmu_equals_ctlgraph_run(tmp_path, fmi):
    # The paper's LADRC loop with its plant inside (no ports: the recorded
    # signals are the outputs), every 1e-3 s: ten of its 1e-4 steps.
    fmu = export("graphs/fladrc/ladrc.yaml", tmp_path / "ladrc.fmu", fmi)
    result = simulate_fmu(str(fmu), stop_time=2.0, output_interval=1e-3, output=["y", "u", "e", "d"])
    assert len(result) == 2001
    reference = run_csv("graphs/fladrc/ladrc.yaml", tmp_path)
    for name in ["y", "u", "e", "d"]:
        want = at_times(reference, result["time"], name)
        assert np.max(np.abs(result[name] - want)) <= 1e-12, name
    assert np.max(np.abs(result["y"])) > 0.5  # the loop moved


def test_zero_crossings_inside_the_fmu_land_where_ctlgraph_run_does(tmp_path):
    fmu = export("tests/fmu/thermostat_rk4.yaml", tmp_path / "thermostat.fmu")
    result = simulate_fmu(str(fmu), stop_time=60.0, output_interval=0.05, output=["T", "heating"])
    reference = run_csv("tests/fmu/thermostat_rk4.yaml", tmp_path)
    for name in ["T", "heating"]:
        assert np.max(np.abs(result[name] - at_times(reference, result["time"], name))) <= 1e-12, name
    switches = np.count_nonzero(np.diff(result["heating"]))
    assert switches >= 30  # the relay switched at its located crossings
    assert np.max(result["T"][result["time"] > 10]) < 21.0 + 1e-9


@pytest.mark.parametrize("fmi", ["3", "2"])
def test_an_input_table_drives_the_fmu_as_the_stepping_api_drives_the_graph(tmp_path, fmi):
    # The vector inport `u` (FMI 2: u[1], u[2]) from FMPy's input table,
    # one row per communication point: piecewise constant on that grid.
    graph = "tests/fmu/plant_io.yaml"
    fmu = export(graph, tmp_path / "plant.fmu", fmi, sets=["tau=0.25"])
    h, n = 0.05, 100
    times = np.arange(n + 1) * h
    u1, u2 = np.sin(3 * times), np.where(times < 2, 1.0, -0.5)
    if fmi == "3":
        # An FMI 3 array input takes a column of rows of its length.
        table = np.zeros(n + 1, dtype=[("time", float), ("u", float, (2,))])
        table["time"], table["u"] = times, np.stack([u1, u2], axis=1)
        result = simulate_fmu(str(fmu), stop_time=n * h, output_interval=h, input=table, output=["y"])
        outputs = np.stack(list(result["y"]))
    else:
        table = np.array(list(zip(times, u1, u2)), dtype=[("time", float), ("u[1]", float), ("u[2]", float)])
        result = simulate_fmu(str(fmu), stop_time=n * h, output_interval=h, input=table, output=["y[1]", "y[2]"])
        outputs = np.stack([result["y[1]"], result["y[2]"]], axis=1)
    sim = ctlgraph.load(str(ROOT / graph), set={"tau": 0.25})
    expected = []
    for k, t in enumerate(times):
        if k > 0:
            sim.advance_to(t)
        expected.append(list(sim.output("y")))
        sim.set_input("u", [u1[k], u2[k]])
    assert np.max(np.abs(outputs - np.array(expected))) <= 1e-12
    assert abs(outputs[-1, 1] - 2 * -0.5) < 0.01  # y → gain·u


@pytest.mark.parametrize("fmi", ["3", "2"])
def test_two_instances_are_independent_and_a_saved_state_replays_to_the_bit(tmp_path, fmi):
    fmu = export("graphs/tutorial/controller_io.yaml", tmp_path / "pid.fmu", fmi)
    md = read_model_description(str(fmu))
    unzipped = extract(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    Slave = FMU3Slave if fmi == "3" else FMU2Slave
    get = (lambda s, r: s.getFloat64(r)) if fmi == "3" else (lambda s, r: s.getReal(r))
    put = (lambda s, r, v: s.setFloat64(r, v)) if fmi == "3" else (lambda s, r, v: s.setReal(r, v))
    slaves = []
    for name, kp in [("a", 2.0), ("b", 6.0)]:
        s = Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        s.instantiate()
        put(s, [vr["kp"]], [kp])
        if fmi == "3":
            s.enterInitializationMode(startTime=0.0, stopTime=3.0)
        else:
            s.setupExperiment(startTime=0.0, stopTime=3.0)
            s.enterInitializationMode()
        s.exitInitializationMode()
        slaves.append(s)
    h = 1e-3

    def steps(s, first, count, measurement):
        out = []
        for k in range(first, first + count):
            put(s, [vr["y"]], [measurement(k * h)])
            s.doStep(k * h, h)
            out.append(get(s, [vr["u"]])[0])
        return np.array(out)

    plant = lambda t: 0.5 * (1 - np.exp(-t))
    a, b = steps(slaves[0], 0, 500, plant), steps(slaves[1], 0, 500, plant)
    assert np.max(np.abs(a - b)) > 0.1  # kp differs: independent instances
    # Each equals ctlgraph's stepping API with its own kp.
    for out, kp in [(a, 2.0), (b, 6.0)]:
        sim = ctlgraph.load(str(ROOT / "graphs/tutorial/controller_io.yaml"), set={"kp": kp})
        want = []
        for k in range(500):
            sim.set_input("y", [plant(k * h)])
            sim.advance_to((k + 1) * h)
            want.append(sim.output("u"))  # a scalar output is a float
        assert np.max(np.abs(out - np.array(want))) <= 1e-12
    # Save, run on, restore, run again: the same bits; and once more from
    # the state serialised and read back into the other instance's FMU.
    s = slaves[0]
    state = s.getFMUState() if fmi == "3" else s.getFMUstate()
    later = steps(s, 500, 300, plant)
    (s.setFMUState if fmi == "3" else s.setFMUstate)(state)
    again = steps(s, 500, 300, plant)
    assert later.tobytes() == again.tobytes()
    serialized = s.serializeFMUState(state) if fmi == "3" else s.serializeFMUstate(state)
    s.reset()
    back = s.deserializeFMUState(serialized) if fmi == "3" else s.deSerializeFMUstate(serialized)
    (s.setFMUState if fmi == "3" else s.setFMUstate)(back)
    replayed = steps(s, 500, 300, plant)
    assert later.tobytes() == replayed.tobytes()
    for s in slaves:
        s.terminate()
        s.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)


def test_bad_use_is_an_error_status_with_a_logged_message(tmp_path):
    fmu = export("tests/fmu/plant_io.yaml", tmp_path / "plant.fmu")
    md = read_model_description(str(fmu))
    unzipped = extract(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    messages = []

    def log(env, status, category, message):
        messages.append((status, message.decode()))

    def slave(name):
        s = FMU3Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        s.instantiate(logMessage=log)
        return s

    # An input of the wrong size: u holds two values.
    s = slave("size")
    with pytest.raises(Exception):
        s.setFloat64([vr["u"]], [1.0])
    assert any(st == 3 and "hold 2 value(s), given room for 1" in m for st, m in messages), messages
    # A parameter that makes the graph invalid: refused at initialisation,
    # with the graph's positioned message.
    s.setFloat64([vr["tau"]], [0.0])
    s.enterInitializationMode(startTime=0.0, stopTime=5.0)
    with pytest.raises(Exception):
        s.exitInitializationMode()
    assert any(st == 3 and "plant_io.yaml:" in m for st, m in messages), messages
    s.freeInstance()
    # A missing resource: instantiation fails, saying which file.
    (Path(unzipped) / "resources" / "ctlgraph.json").unlink()
    with pytest.raises(Exception):
        slave("missing")
    assert any("ctlgraph.json" in m for _, m in messages), messages
    shutil.rmtree(unzipped, ignore_errors=True)


def test_a_van_der_pol_fmu_under_a_silent_ctlgraph_controller_gives_fmpys_open_loop(tmp_path):
    # The plant of graphs/fmu/, exported; in a graph, an `fmu` block driven
    # by a PD controller whose gains are zero; beside it, FMPy's open loop.
    fmu = export("graphs/fmu/van_der_pol.yaml", tmp_path / "van_der_pol.fmu")
    graph = tmp_path / "loop.yaml"
    text = (ROOT / "graphs/fmu/loop.yaml").read_text()
    graph.write_text(text.split("\nchecks:")[0] + "\n")
    out = tmp_path / "loop.csv"
    done = subprocess.run(
        [BIN, "run", str(graph), "--out", str(out), "--set", "kp=0", "--set", "kd=0"],
        capture_output=True, text=True, env=ENV, timeout=300,
    )
    assert done.returncode == 0, done.stderr
    with open(out) as f:
        rows = list(csv.reader(f))
    ours = {h: np.array([float(r[i]) for r in rows[1:]]) for i, h in enumerate(rows[0])}
    assert np.all(ours["u"] == 0.0)
    result = simulate_fmu(str(fmu), stop_time=20.0, output_interval=0.01, output=["x"])
    want = at_times(ours, result["time"], "x")
    assert np.max(np.abs(result["x"] - want)) <= 1e-12
    assert np.max(np.abs(result["x"][result["time"] > 10])) > 1.9  # the limit cycle, undamped
