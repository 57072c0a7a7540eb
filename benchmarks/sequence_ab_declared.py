"""Catalogue-free diagnosis of the two-cylinder sequence A+ B+ B- A-
(issue #37's second everyday circuit).

netlists/sequence_ab.yaml: two cylinders on their valves with meter-out
flow controls, limit switches and a sequencer - 19 components. Measured
runs with one withheld fault written in a form of its own (an extra
component, another parameter, an edit of the CSV; never the declared
fault's own parameter: a limit switch set 3-10 mm early as its position, so
that B starts before A is out; B's valve late to actuate as an on-delay
timer on its command), two such faults in different cylinders, an effect
no component declares (a process force against B; a return spring on B),
or none; supply 5 and 7 bar g
(calibration) and 6 bar g (validation); both positions and both cap
pressures at 200 Hz (0.05 mm, 3 kPa noise). Each case is diagnosed by
`pneumo diagnose` WITHOUT --effects and scored as in
meter_out_declared.py (named first, doubles both named, undeclared
flagged, nulls clean, invisible cases apart). Run by hand, not in CI:

    python3 benchmarks/sequence_ab_declared.py [--seed N] [--cases K] [--pneumo build/pneumo] [--work DIR]
"""
import random
from pathlib import Path

from meter_out_declared import (add_components, common_arguments, heavier, needle, piston_leak, process_force,
                                rod_leak, run_plan, seal_friction, set_param, sluggish, zero_offset)

ROOT = Path(__file__).resolve().parent.parent
# Outputs every 5 ms (1 ms in the netlist): the fit's rows.
MODEL = (ROOT / "netlists" / "sequence_ab.yaml").read_text().replace("output_interval: 1 ms", "output_interval: 5 ms")
SIGNALS = ["x_A", "x_B", "p_cap_A", "p_cap_B"]
NOISE = {"x_A": 5e-5, "x_B": 5e-5, "p_cap_A": 3e3, "p_cap_B": 3e3}
INTERVAL = 5e-3

# The withheld forms (meter_out_declared.py's builders): name -> (expected
# candidate or None for undeclared, lo, hi, apply, csv edit).
FORMS = {
    "piston_leak_B": piston_leak("cyl_B", 0.005, 0.03),
    "rod_leak_A": rod_leak("cyl_A", 0.1, 0.4),
    "needle_A_rod": needle("flow_A_rod", 0.3, 0.35, 0.4, 0.8),
    "heavier_B": heavier("load_B", 2, 2.0, 5.0),
    "sluggish_A": sluggish("valve_A", 15, 3.0, 10.0),
    "seal_friction_A": seal_friction("cyl_A", "load_A", 20, 30, 1.5, 3.0),
    "x_B_zero": zero_offset("x_B", 0.3e-3, 2e-3),
    "switch_a1_early": ("a1.misplaced", 3.0, 10.0, lambda t, k: set_param(t, "a1", "position", "%g mm" % (100 - k)),
                        None),
    # undeclared: a load force on B's rod
    "process_force_B": process_force("load_B", 10.0, 40.0),
}
# Drawn after the cases above (so that those stay as each seed drew them
# before these were added).
LATER = {
    # B's solenoid valve late to actuate: an on-delay timer of k ms on its command
    "late_valve_B": ("valve_B.delay_actuate", 5.0, 40.0, lambda t, k: add_components(
        t.replace("  - [seq.B, valve_B.command]", "  - [seq.B, late.in]"), ["late: {type: timer, delay: %g ms}" % k],
        ["[late.y, valve_B.command]"]), None),
    # undeclared: a return spring of k N/m on B's load, slack at B's retracted end
    "spring_B": (None, 300.0, 3000.0, lambda t, k: add_components(
        t, ["spring: {type: spring_damper, k: %g N/m}" % k, "frame: {type: fixed_position}"],
        ["[frame.flange, spring.a]", "[spring.b, load_B.flange]"]), None),
}

# Two faults planted together, in different cylinders: both must be named.
DOUBLES = [("piston_leak_B", "sluggish_A"), ("heavier_B", "needle_A_rod")]


def main():
    a = common_arguments("/tmp/pneumo_sequence_ab_declared").parse_args()
    rng = random.Random(a.seed)
    plan = [(f,) for f in FORMS] + DOUBLES + [("null",), ("null",)]
    rng.shuffle(plan)
    plan += [(f,) for f in LATER]
    run_plan(a, rng, plan, MODEL, {**FORMS, **LATER}, SIGNALS, NOISE, INTERVAL, only=a.only)


if __name__ == "__main__":
    main()
