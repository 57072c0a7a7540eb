"""Catalogue-free diagnosis of a six-cylinder line (issue #37, "scale with
the circuit").

netlists/assembly_line.yaml: six cylinders, each with its valve, two flow
controls, two tubes, a load and two limit switches - about a hundred
declared faults. Measured runs of the line with one withheld fault (written
in a form of its own: an extra component, another parameter, an edit of the
CSV; never the declared fault's parameter), or two such faults in
different cylinders, or none, at supply 5 and 7 bar g
(calibration) and 6 bar g (validation), the six positions at 200 Hz with
0.05 mm noise; each case diagnosed by `pneumo diagnose` WITHOUT --effects.
Prints per case the verdict, whether the faulty cylinder's fault is named
first, and the wall time with the number of candidates (the cost per
candidate). Run by hand, not in CI:

    python3 benchmarks/assembly_line_declared.py [--seed N] [--cases K] [--threads T] [--pneumo build/pneumo]
"""
import json
import random
from pathlib import Path

from meter_out_declared import (common_arguments, heavier, needle, piston_leak, process_force, rod_leak, run_plan,
                                sluggish, zero_offset)

ROOT = Path(__file__).resolve().parent.parent
# The line's outputs every 5 ms (1 ms in the netlist): the fit's rows.
MODEL = (ROOT / "netlists" / "assembly_line.yaml").read_text().replace("output_interval: 1 ms", "output_interval: 5 ms")
SIGNALS = ["x_A", "x_B", "x_C", "x_D", "x_E", "x_F"]
NOISE = {s: 5e-5 for s in SIGNALS}
INTERVAL = 5e-3

# The withheld forms (meter_out_declared.py's builders): name -> (expected
# candidate or None for undeclared, lo, hi, apply, csv edit).
FORMS = {
    "piston_leak_D": piston_leak("cyl_D", 0.005, 0.05),
    "rod_leak_F": rod_leak("cyl_F", 0.1, 0.5),
    "needle_B_rod": needle("flow_B_rod", 0.25, 0.35, 0.4, 0.7),
    "heavier_C": heavier("load_C", 8, 1.5, 3.0),
    "sluggish_E": sluggish("valve_E", 15, 3.0, 8.0),
    "x_A_zero": zero_offset("x_A", 0.5e-3, 3e-3),
    # undeclared: a process force against the press
    "press_force": process_force("load_D", 30.0, 120.0),
}


# Two faults planted together, in different cylinders: both must be named.
DOUBLES = [("piston_leak_D", "heavier_C"), ("needle_B_rod", "x_A_zero"), ("rod_leak_F", "sluggish_E")]


def candidates(report):
    rep = json.loads((report / "report.json").read_text())
    return len(rep["effects"])


def main():
    ap = common_arguments("/tmp/pneumo_assembly_line_declared")
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    plan = [(f,) for f in FORMS] + DOUBLES + [("null",)]
    rng.shuffle(plan)

    def cost(case, secs):
        if (case / "report" / "report.json").exists():
            n = candidates(case / "report")
            print("    %d candidates, %.0f s wall on %d threads: %.2f s per candidate" % (n, secs, a.threads, secs / max(n, 1)),
                  flush=True)

    run_plan(a, rng, plan, MODEL, FORMS, SIGNALS, NOISE, INTERVAL, measure=False, only=a.only,
             extra=("--threads", str(a.threads)), after=cost)


if __name__ == "__main__":
    main()
