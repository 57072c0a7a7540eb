"""Cost of a run from Python against the same run from C++.

Both sides run the same C++ function (netlist copy and overrides,
elaboration, the solver, every metric of the netlist - what `pneumo simulate`
computes): "C++" times it in a loop inside the module without the
interpreter (pneumo._core.time_runs); "Python" times net.simulate(), which
adds the call, the GIL release, the numpy arrays and the Result object.
Runs alternate in blocks so that load on a shared machine hits both alike.
Prints the median wall and CPU time of each and the ratio Python / C++.

    PYTHONPATH=build/python python3 benchmarks/python_overhead.py [runs] [netlist]
"""
import statistics
import sys
import time
from pathlib import Path

import pneumo
from pneumo import _core

runs = int(sys.argv[1]) if len(sys.argv) > 1 else 60
path = sys.argv[2] if len(sys.argv) > 2 else Path(__file__).resolve().parents[1] / "netlists" / "cushion_rig.yaml"
net = pneumo.load(path)
net.simulate()  # warm up: first-touch of the libraries and caches

cpp_wall, cpp_cpu, py_wall, py_cpu = [], [], [], []
block = 5
for _ in range(max(1, runs // block)):
    for wall, cpu in _core.time_runs(net._core, [], block):
        cpp_wall.append(wall)
        cpp_cpu.append(cpu)
    for _ in range(block):
        w0, c0 = time.perf_counter(), time.thread_time()
        net.simulate()
        py_wall.append((time.perf_counter() - w0) * 1e3)
        py_cpu.append((time.thread_time() - c0) * 1e3)

med = statistics.median
print(f"{path}: {len(cpp_wall)} runs each (median)")
print(f"  C++     wall {med(cpp_wall):8.3f} ms   CPU {med(cpp_cpu):8.3f} ms")
print(f"  Python  wall {med(py_wall):8.3f} ms   CPU {med(py_cpu):8.3f} ms")
print(f"  ratio Python / C++: wall {med(py_wall) / med(cpp_wall):.3f}, CPU {med(py_cpu) / med(cpp_cpu):.3f}")
