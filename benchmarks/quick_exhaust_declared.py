"""Catalogue-free diagnosis of a single-acting cylinder behind a
quick-exhaust valve (issue #37: the everyday circuit the issue names beside
the meter-out cylinder and the sequence).

netlists/quick_exhaust_cylinder.yaml: a 3/2 valve, a hose, a meter-in
one-way flow control, a quick-exhaust valve with a silencer at its exhaust,
a single-acting cylinder with its return spring and a load; extend at 0.1 s,
exhaust at 1.2 s. Measured runs with one withheld fault written in a form
of its own (a laminar gap venting the cap port - a worn piston seal or the
quick-exhaust valve's disc -, the needle turned with
another b, dirt behind the silencer, a throttled supply line with a tank, a
second friction with a Stribeck hump, a heavier load, a slower spool, a
transducer zero in the CSV), a process force no component declares, three
doubles and two nulls; supply 5 and 7 bar g (calibration) and 6 bar g
(validation); position and cap pressure at 200 Hz (0.05 mm, 3 kPa noise).
Each case is diagnosed by `pneumo diagnose` WITHOUT --effects and scored as
in meter_out_declared.py. Run by hand, not in CI:

    python3 benchmarks/quick_exhaust_declared.py [--seed N] [--cases K] [--pneumo build/pneumo] [--work DIR]
"""
import random
from pathlib import Path

from meter_out_declared import (add_components, common_arguments, heavier, needle, process_force, run_plan,
                                seal_friction, silencer_dirt, sluggish, supply_line, zero_offset)

ROOT = Path(__file__).resolve().parent.parent
MODEL = (ROOT / "netlists" / "quick_exhaust_cylinder.yaml").read_text()
SIGNALS = ["x", "p_cap"]
NOISE = {"x": 5e-5, "p_cap": 3e3}


def cap_leak(lo, hi):
    """A laminar-ish gap (b 0.05) of k dm3/(s*bar) from the cap port to the
    atmosphere: the spring side is vented, so a worn piston seal vents there -
    and the quick-exhaust valve sits at that port, so a worn disc vents
    there too. Either is the fault: the gap drains the port's stream, as the
    disc's leak does, where the seal's drains the chamber's gas (a
    temperature apart while the chamber is still warm from its filling)."""
    return (frozenset({"cyl.piston_seal_leak", "qev.disc_leak"}), lo, hi, lambda t, k: add_components(
        t, ["seal_gap: {type: iso6358_throttle, C: %g dm3/(s*bar), b: 0.05}" % k, "leak_air: {type: atmosphere}"],
        ["[cyl.cap, seal_gap.a]", "[seal_gap.b, leak_air.port]"]), None)


FORMS = {
    "cap_leak": cap_leak(0.003, 0.03),
    "needle_turned": needle("flow", 0.06, 0.5, 0.5, 1.8),
    "exhaust_dirt": silencer_dirt(0.3, 2.0),
    "supply_line": supply_line(0.1, 0.5),
    "seal_friction": seal_friction("cyl", "load", 15, 50, 1.4, 3.0),
    "heavier_tool": heavier("load", 1.5, 2.0, 6.0),
    "sluggish_spool": sluggish("valve", 8, 3.0, 12.0),
    "transducer_zero": zero_offset("p_cap", 0.05e5, 0.3e5),
    # undeclared: a process force against the stroke
    "process_force": process_force("load", 10.0, 40.0),
}
DOUBLES = [("cap_leak", "heavier_tool"), ("needle_turned", "transducer_zero"), ("sluggish_spool", "supply_line")]


def main():
    ap = common_arguments("/tmp/pneumo_quick_exhaust_declared")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    plan = [(f,) for f in FORMS]
    rng.shuffle(plan)
    plan += DOUBLES + [("null",), ("null",)]
    run_plan(a, rng, plan, MODEL, FORMS, SIGNALS, NOISE, 5e-3, only=a.only)


if __name__ == "__main__":
    main()
