"""ctlgraph from Python: declarative control graphs (block diagrams as YAML)
simulated at Rust speed.

    import ctlgraph
    result = ctlgraph.run("graphs/tutorial/pid_loop.yaml", set={"kp": 3.0})
    result.t, result["y"]          # numpy arrays
    result.checks, result.stats    # the graph's checks, solver statistics

    model = ctlgraph.load("graphs/tutorial/controller_io.yaml")
    model.set_input("y", 0.0)      # the graph's top-level inport
    model.advance_to(0.001)        # lands exactly there
    u = model.output("u")          # its top-level outport

    ctlgraph.linearize(path, open="ctrl.u")          # A, B, C, D, poles, margins
    ctlgraph.sweep(path, vary={"kp": "1..4:20"})      # the sweep table as columns

Errors in a graph file raise GraphError (with file, line, column, hint);
a run that stops early raises SimulationError.
"""

from ._native import (
    Check,
    GraphError,
    Model,
    Result,
    SimulationError,
    Snapshot,
    __version__,
    check,
    linearize,
    load,
    run,
    sweep,
)

__all__ = [
    "Check",
    "GraphError",
    "Model",
    "Result",
    "SimulationError",
    "Snapshot",
    "__version__",
    "check",
    "linearize",
    "load",
    "run",
    "sweep",
]
