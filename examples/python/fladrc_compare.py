"""The FLADRC paper's comparison (graphs/fladrc/compare.yaml) from Python,
plotted with matplotlib:  python examples/python/fladrc_compare.py"""

import matplotlib.pyplot as plt

import ctlgraph

result = ctlgraph.run("graphs/fladrc/compare.yaml")
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
top.plot(result.t, result["y_fladrc"], label="FLADRC")
top.plot(result.t, result["y_fpid"], label="FPID")
top.set_ylabel("depth of cut y [mm]")
top.legend()
bottom.plot(result.t, result["e_fladrc"], label="FLADRC")
bottom.plot(result.t, result["e_fpid"], label="FPID")
bottom.set(xlabel="t [s]", ylabel="error e [mm]")
print("\n".join(str(c) for c in result.checks))
fig.savefig("fladrc_compare.png", dpi=120)
