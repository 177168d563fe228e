"""Co-simulation: a Python function is the plant, a graph the controller.

Every millisecond the loop measures the plant, sets the graph's input `y`
(a top-level inport of graphs/tutorial/controller_io.yaml), reads the
command `u` (its top-level outport) and advances both by 1 ms.

    python examples/python/cosim.py
"""

import ctlgraph

WN, ZETA, TICK = 10.0, 0.3, 1e-3


def plant(state, u, dt, substeps=10):
    """y'' + 2 zeta wn y' + wn^2 y = wn^2 u, by explicit midpoint steps."""
    y, v = state
    h = dt / substeps
    for _ in range(substeps):
        a = WN * WN * (u - y) - 2 * ZETA * WN * v
        ym, vm = y + 0.5 * h * v, v + 0.5 * h * a
        am = WN * WN * (u - ym) - 2 * ZETA * WN * vm
        y, v = y + h * vm, v + h * am
    return y, v


controller = ctlgraph.load("graphs/tutorial/controller_io.yaml")
state = (0.0, 0.0)
for k in range(3000):
    controller.set_input("y", state[0])
    u = controller.output("u")
    state = plant(state, u, TICK)
    controller.advance_to((k + 1) * TICK)
    if (k + 1) % 500 == 0:
        print(f"t = {controller.time:.1f} s: y = {state[0]:+.5f}, u = {u:+.5f}")
