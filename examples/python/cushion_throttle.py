"""The cushion rig at three settings of the cushion throttle (z_EC, turns open):
time in the cushion, impact speed and peak cushion pressure of each, and x(t)
of the three strokes plotted when matplotlib is installed.

    PYTHONPATH=build/python python3 examples/python/cushion_throttle.py [out.png]
"""
import sys
from pathlib import Path

import pneumo

NETLIST = Path(__file__).resolve().parents[2] / "netlists" / "cushion_rig.yaml"
net = pneumo.load(NETLIST)
runs = {}
for z in (0.5, 1.5, 3.5):
    res = net.simulate(set={"z_EC": f"{z} rev"})
    runs[z] = res
    m = res.metrics
    print(f"z_EC = {z} rev: {m['t_cushion'] * 1e3:6.1f} ms in the cushion, impact at "
          f"{m['v_impact']:+.3f} m/s, peak cushion pressure {m['p_EC_peak'] / 1e5:.2f} bar")

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed (apt-get install python3-matplotlib): no plot")
    sys.exit(0)

fig, ax = plt.subplots()
for z, res in runs.items():
    ax.plot(res.t, res["x"] * 1e3, label=f"z_EC = {z} rev")
ax.set_xlabel("t [s]")
ax.set_ylabel("x [mm]")
ax.set_title("cushion rig: piston position")
ax.legend()
out = sys.argv[1] if len(sys.argv) > 1 else "cushion_throttle.png"
fig.savefig(out, dpi=120)
print(f"plotted {out}")
