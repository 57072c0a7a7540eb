"""Catalogue-free diagnosis benchmark on the meter-out cylinder (issue #37).

Generates measured runs of netlists/meter_out_cylinder.yaml with withheld
faults written in forms of their own - extra components, other parameters,
edits of the CSV - never the declared fault's own parameter, diagnoses
each case with `pneumo diagnose` WITHOUT --effects (the components'
declared faults and the measurement faults only) and reports:
  named first  - single cases whose verdict starts with the expected fault
                 (or with one of them, where a form sits where two act alike)
  flagged      - cases whose effect no component declares, reported as
                 unexplained (or with an empty verdict)
  nulls clean  - cases without any withheld effect that name nothing
  invisible    - single or double cases whose planted effect moves the
                 signals so little (excess over the noise, from the truth's
                 and the model's own simulations) that a diagnosis would see
                 a gap under 1.1 times the noise: printed, scored apart
  first group  - besides: single cases whose expected fault is in the
                 verdict's first group, the candidates the diagnosis says
                 these runs cannot tell apart ("grp" where not first)
Run by hand, not in CI (minutes per case):

    python3 benchmarks/meter_out_declared.py [--seed N] [--cases K] [--pneumo build/pneumo] [--work DIR]

Each case: three runs (supply 5, 6, 7 bar g; two calibration, one
validation), 200 Hz, noise x 0.05 mm, p 3 kPa; magnitudes drawn
log-uniformly per form between a weak and a strong value.
"""
import argparse
import csv
import json
import math
import random
import re
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BASE = (ROOT / "netlists" / "meter_out_cylinder.yaml").read_text()
# The runs' operating point: the supply pressure (and the rod side's start).
MODEL = (BASE.replace("components:", "parameters:\n  p_supply: 6 bar g\n\ncomponents:", 1)
         .replace("supply:   {type: pressure_source, p: 6 bar g", "supply:   {type: pressure_source, p: p_supply")
         .replace("p0_rod: 6 bar g", "p0_rod: p_supply"))
SIGNALS = ["x", "v", "p_cap", "p_rod"]
NOISE = {"x": 5e-5, "v": 2e-3, "p_cap": 3e3, "p_rod": 3e3}


OUTPUT_INTERVAL = 5e-3  # s, the netlist's simulation.output_interval
P_AMBIENT = 101325.0    # Pa, the netlist's ambient


def to_si(value, header):
    """A result value in its column's unit ("x [mm]", "p [barg]") in SI."""
    unit = header.split(" [")[1].rstrip("]") if " [" in header else ""
    scale = {"mm": 1e-3, "bar": 1e5, "barg": 1e5, "kPa": 1e3, "ms": 1e-3}.get(unit, 1.0)
    offset = {"barg": P_AMBIENT, "degC": 273.15}.get(unit, 0.0)
    return value * scale + offset


def add_components(text, comps, conns):
    text = text.replace("\nconnections:", "\n" + "".join("  %s\n" % c for c in comps) + "\nconnections:", 1)
    return text.replace("\noutputs:", "\n" + "".join("  - %s\n" % c for c in conns) + "\noutputs:", 1)


def set_param(text, comp, key, value):
    """Sets (or adds) KEY of component COMP in its flow map."""
    m = re.search(r"^  %s:\s*\{" % re.escape(comp), text, re.M)
    start = m.end()
    depth, i = 1, start
    while depth:
        depth += {"{": 1, "}": -1}.get(text[i], 0)
        i += 1
    body = text[start:i - 1]
    if re.search(r"(^|[\s,])%s:" % re.escape(key), body):
        body = re.sub(r"((?:^|[\s,])%s:\s*)([^,}]+(?:\[[^\]]*\])?[^,}]*)" % re.escape(key), r"\g<1>%s" % value, body, count=1)
    else:
        body = body + ", %s: %s" % (key, value)
    return text[:start] + body + text[i - 1:]


# The withheld forms each benchmark plants, as (expected candidate or None
# for undeclared, lo, hi, apply(text, k) -> text, csv edit or None), k drawn
# log-uniformly in [lo, hi]. Each is written in a form of its own, never the
# declared fault's parameter. The expected candidate may be a frozenset:
# a form that sits where two declared faults act alike (a gap at a port
# that two components share), either named is right.
def piston_leak(cyl, lo, hi):
    """A laminar-ish throttle (b 0.05) of C = k dm3/(s*bar) across the piston."""
    return ("%s.piston_seal_leak" % cyl, lo, hi, lambda t, k: add_components(
        t, ["seal_gap: {type: iso6358_throttle, C: %g dm3/(s*bar), b: 0.05}" % k],
        ["[%s.cap, seal_gap.a]" % cyl, "[seal_gap.b, %s.rod]" % cyl]), None)


def rod_leak(cyl, lo, hi):
    """A nozzle of k mm from the rod side to the atmosphere."""
    return ("%s.rod_seal_leak" % cyl, lo, hi, lambda t, k: add_components(
        t, ["rod_gap: {type: nozzle, d: %g mm}" % k, "rod_air: {type: atmosphere}"],
        ["[%s.rod, rod_gap.a]" % cyl, "[rod_gap.b, rod_air.port]"]), None)


def needle(flow, C, b, lo, hi):
    """The flow control's needle turned: C k times its C (dm3/(s*bar)), another b."""
    return ("%s.misadjusted" % flow, lo, hi, lambda t, k: set_param(
        set_param(t, flow, "C", "%g dm3/(s*bar)" % (C * k)), flow, "b", str(b)), None)


def heavier(load, m, lo, hi):
    """The load k times its mass m (kg)."""
    return ("%s.mass_off" % load, lo, hi, lambda t, k: set_param(t, load, "m", "%g kg" % (m * k)), None)


def sluggish(valve, t_ms, lo, hi):
    """The valve's switching time k times t_ms."""
    return ("%s.slow_switching" % valve, lo, hi, lambda t, k: set_param(
        t, valve, "t_switch_time", "%g ms" % (t_ms * k)), None)


def seal_friction(cyl, load, F, kv, lo, hi):
    """A seal running dry: a second friction on the rod with a Stribeck hump
    and a speed law |v|^0.6 of its own - not the cylinder's law rescaled:
    (k - 1) x (F N, 0.4 F N at rest, kv N at 1 m/s)."""
    return ("%s.friction_running" % cyl, lo, hi, lambda t, k: add_components(
        t, ["seal_drag: {type: friction_element, friction: custom, friction_b0: %g N, friction_FS0: %g N, "
            "friction_vS: 20 mm/s, friction_kv0: %g N, friction_a: 0.6}" % (F * (k - 1), 0.4 * F * (k - 1), kv * (k - 1))],
        ["[%s.flange, seal_drag.flange]" % load]), None)


def silencer_dirt(lo, hi):
    """Dirt behind the silencer (a throttle of k dm3/(s*bar), b 0.2, before
    the atmosphere `air`), the silencer's own b 0.4."""
    return ("silencer.misadjusted", lo, hi, lambda t, k: add_components(
        set_param(t, "silencer", "b", "0.4"), ["dirt: {type: iso6358_throttle, C: %g dm3/(s*bar), b: 0.2}" % k], []).replace(
        "  - [silencer.b, air.port]", "  - [silencer.b, dirt.a]\n  - [dirt.b, air.port]"), None)


def supply_line(lo, hi):
    """A throttled supply line (k dm3/(s*bar), b 0.3) with a 20 cm3 tank
    between the source and the valve's P."""
    return ("supply.supply_sag", lo, hi, lambda t, k: add_components(
        t, ["line_S: {type: iso6358_throttle, C: %g dm3/(s*bar), b: 0.3}" % k, "tank_S: {type: volume, V: 20 cm3, p0: 6 bar g}"], []).replace(
        "  - [supply.port, valve.P]", "  - [supply.port, line_S.a]\n  - [line_S.b, tank_S.port, valve.P]"), None)


def zero_offset(signal, lo, hi):
    """k (SI) added to the signal in the CSV: the transducer's zero."""
    return ("%s.offset" % signal, lo, hi, lambda t, k: t, (signal, "offset"))


def process_force(load, lo, hi):
    """Undeclared: k N against the stroke on the load."""
    return (None, lo, hi, lambda t, k: add_components(
        t, ["push: {type: force_source, F: %g N}" % -k], ["[%s.flange, push.flange]" % load]), None)


FORMS = {
    "piston_leak_laminar": piston_leak("cyl", 0.003, 0.03),
    "rod_leak_nozzle": rod_leak("cyl", 0.05, 0.4),
    "needle_turned": needle("flow_cap", 0.1, 0.4, 0.5, 1.8),
    "silencer_dirt": silencer_dirt(0.3, 2.0),
    "supply_line": supply_line(0.3, 1.5),
    "seal_friction": seal_friction("cyl", "load", 20, 60, 1.4, 3.0),
    "heavier_tool": heavier("load", 2, 2.0, 6.0),
    "sluggish_spool": sluggish("valve", 10, 3.0, 12.0),
    "transducer_zero": zero_offset("p_cap", 0.05e5, 0.3e5),
    # undeclared: a load force on the rod (a spring-back, a process force)
    "process_force": process_force("load", 15.0, 60.0),
}


# Two faults planted together: both must be named. After the shuffled
# single cases, so that those stay as each seed drew them before.
DOUBLES = [("piston_leak_laminar", "heavier_tool"), ("needle_turned", "transducer_zero"),
           ("sluggish_spool", "supply_line")]


def plant(model, table, forms, rng):
    """MODEL with FORMS (names in TABLE) planted at magnitudes drawn
    log-uniformly; returns (expected, magnitude, truth, csv edit, its
    magnitude), expected and magnitude tuples for more than one form."""
    truth, ks, expected, edit, ek = model, [], [], None, 0.0
    for form in forms:
        exp, lo, hi, apply, e = table[form]
        k = math.exp(rng.uniform(math.log(lo), math.log(hi)))
        truth = apply(truth, k)
        ks.append(k)
        expected.append(exp)
        if e:
            edit, ek = e, k
    if len(forms) == 1:
        return expected[0], ks[0], truth, edit, ek
    return tuple(expected), tuple(ks), truth, edit, ek


def new_case(work, seed, i, forms, model, table, rng):
    """An empty folder for case I of FORMS ("null": nothing planted) and
    what plant() returns for it, with the case's name."""
    form = "+".join(forms)
    case = work / ("seed%d_%02d_%s" % (seed, i, form))
    subprocess.run(["rm", "-rf", str(case)], check=True)
    case.mkdir(parents=True)
    if form == "null":
        return case, form, "", 0.0, model, None, 0.0
    return (case, form) + plant(model, table, forms, rng)


# The runs: (name, role, supply pressure in bar g).
POINTS = (("cal1", "calibration", 5), ("cal2", "calibration", 7), ("val", "validation", 6))


def simulate(pneumo, netlist, p_supply, out_csv, work, name="truth.yaml"):
    path = work / name
    path.write_text(netlist)
    subprocess.run([pneumo, "simulate", str(path), "--set", "p_supply=%s bar g" % p_supply, "-o", str(out_csv), "-q"],
                   check=True)


def sampled_rows(pneumo, netlist, p_supply, raw, interval, name="truth.yaml"):
    """The netlist simulated at P_SUPPLY: its output grid's rows in SI, keyed
    by output name. Result columns are "NAME [UNIT]" in the netlist's display
    units (mm, bar g); rows written at events are not samples."""
    simulate(pneumo, netlist, p_supply, raw, raw.parent, name)
    rows = []
    for r in csv.DictReader(raw.open()):
        row = {k.split(" [")[0]: to_si(float(v), k) for k, v in r.items()}
        step = row["t"] / interval
        if abs(step - round(step)) < 1e-6 and (not rows or row["t"] > rows[-1]["t"]):
            rows.append(row)
    raw.unlink()
    return rows


def write_runs(pneumo, truth, runs_dir, rng, csv_edit, k, signals=SIGNALS, noise=NOISE, interval=OUTPUT_INTERVAL,
               points=POINTS):
    """Writes the runs of TRUTH with noise; returns each run's noiseless
    values (the CSV edit applied), {run name: [{signal: value}]}."""
    runs_dir.mkdir(parents=True)
    clean = {}
    for name, role, ps in points:
        rows = sampled_rows(pneumo, truth, ps, runs_dir.parent / ("%s_raw.csv" % name), interval)
        clean[name] = []
        with (runs_dir / (name + ".csv")).open("w") as f:
            f.write("t," + ",".join(signals) + "\n")
            for r in rows:
                vals, exact = [], {"t": r["t"]}
                for s in signals:
                    y = float(r[s])
                    if csv_edit and csv_edit[0] == s:
                        y += k
                    exact[s] = y
                    vals.append("%.10g" % (y + rng.gauss(0, noise[s])))
                clean[name].append(exact)
                f.write("%.10g,%s\n" % (r["t"], ",".join(vals)))
        (runs_dir / (name + ".yaml")).write_text(
            "data: %s.csv\nrole: %s\noperating_point:\n  p_supply: %d bar g\n" % (name, role, ps))
    return clean


def planted_excess(pneumo, model, clean, work, signals=SIGNALS, noise=NOISE, interval=OUTPUT_INTERVAL,
                   points=POINTS):
    """How far the planted effect moves the signals, in noise units: the RMS
    over every run, signal and sample of (truth - model) / noise, from the
    noiseless truth and the model's own simulation (not from the diagnosis).
    A diagnosis sees a gap of about sqrt(1 + excess^2) times the noise."""
    total, count = 0.0, 0
    for name, role, ps in points:
        model_rows = {round(r["t"] / interval): r for r in sampled_rows(pneumo, model, ps, work / "model_raw.csv", interval, "model.yaml")}
        for r in clean[name]:
            m = model_rows.get(round(r["t"] / interval))
            if m is None:
                continue
            for s in signals:
                total += ((r[s] - m[s]) / noise[s]) ** 2
                count += 1
    return math.sqrt(total / max(count, 1))


# A planted fault whose expected gap sqrt(1 + excess^2) stays below this
# (in noise units) is not "just above noise": the data hardly show it. Such a
# case is scored apart, as invisible, and not counted as named or missed.
VISIBLE_GAP = 1.1


def accepted(expected):
    """The names that count as the expected fault (a frozenset: any of them)."""
    return expected if isinstance(expected, frozenset) else frozenset([expected])


def diagnose_case(pneumo, model, case, form, expected, k, stats, extra=(), excess=None):
    """Diagnoses CASE/runs without a catalogue, scores the verdict into STATS
    and prints one line: expected None is an undeclared effect, "" a null, a
    tuple two effects planted together (both must be in the verdict).
    EXCESS: the planted effect's size in noise units (planted_excess)."""
    t0 = time.time()
    r = subprocess.run([pneumo, "diagnose", str(model), "--runs", str(case / "runs"), "--out", str(case / "report"),
                        "-q", *extra], capture_output=True, text=True)
    secs = time.time() - t0
    if r.returncode:
        print("%-34s diagnose failed: %s" % (case.name, r.stdout[-300:] + r.stderr[-300:]))
        return secs
    rep = json.loads((case / "report" / "report.json").read_text())
    verdict, unexplained = rep["verdict"], rep["unexplained"] is not None
    if form == "null":
        kind, ok = "null", not verdict
    elif expected is None:
        kind, ok = "undeclared", unexplained or not verdict
    elif isinstance(expected, tuple):
        kind, ok = "double", all(accepted(e) & set(verdict) for e in expected)
    else:
        kind, ok = "single", bool(verdict) and verdict[0] in accepted(expected)
    if excess is not None and kind in ("single", "double") and math.sqrt(1 + excess ** 2) < VISIBLE_GAP:
        kind += " (invisible)"
    stats.setdefault(kind, [0, 0])
    stats[kind][0] += ok
    stats[kind][1] += 1
    # Apart from the strict score: the expected fault among the first slot's
    # group - the candidates the diagnosis says these runs cannot tell apart.
    groups = rep.get("verdict_groups") or [[]]
    if kind == "single":
        stats.setdefault("single, in the first group", [0, 0])
        stats["single, in the first group"][0] += bool(accepted(expected) & set(groups[0]))
        stats["single, in the first group"][1] += 1
    print("%-34s k=%-9s %s-> %-44s %-4s %s (%.0f s)" % (
        case.name, "/".join("%.3g" % x for x in (k if isinstance(k, tuple) else (k,))),
        "" if excess is None else "excess %-6.3g " % excess, "+".join(verdict) or "(none)",
        "ok" if ok else "MISS" if kind != "single" or not accepted(expected) & set(groups[0]) else "grp",
        "unexplained flagged;" if unexplained else "", secs), flush=True)
    return secs


def common_arguments(work):
    """The options every catalogue-free benchmark takes; WORK the default folder."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=0, help="first K cases only (0: all)")
    ap.add_argument("--pneumo", default=str(ROOT / "build" / "pneumo"))
    ap.add_argument("--work", default=work)
    ap.add_argument("--only", help="diagnose only the cases that plant this form (the others' runs are still drawn)")
    return ap


def run_plan(a, rng, plan, model, forms, signals=SIGNALS, noise=NOISE, interval=OUTPUT_INTERVAL, measure=True,
             only=None, extra=(), after=None):
    """Plants, runs and diagnoses each case of PLAN (tuples of FORMS names,
    ("null",) for none) in A.work, the first A.cases only if given, and
    prints the scores. MEASURE: each case's size in noise units too (three
    simulations more). ONLY: diagnose only the cases planting that form (the
    others' runs are still drawn). AFTER(case, seconds) runs after each
    diagnosis."""
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    (work / "model.yaml").write_text(model)
    stats = {"single": [0, 0], "double": [0, 0], "undeclared": [0, 0], "null": [0, 0]}
    for i, case_forms in enumerate(plan[:a.cases] if a.cases else plan):
        case, form, expected, k, truth, edit, ek = new_case(work, a.seed, i, case_forms, model, forms, rng)
        clean = write_runs(a.pneumo, truth, case / "runs", rng, edit, ek, signals, noise, interval)
        if only and only not in case_forms:
            continue
        excess = planted_excess(a.pneumo, model, clean, case, signals, noise, interval) if measure and form != "null" else None
        secs = diagnose_case(a.pneumo, work / "model.yaml", case, form, expected, k, stats, extra, excess)
        if after:
            after(case, secs)
    for kind, (ok, n) in stats.items():
        print("%-11s %d of %d" % (kind, ok, n))


def main():
    ap = common_arguments("/tmp/pneumo_meter_out_declared")
    ap.add_argument("--doubles", action="store_true", help="also the cases of two faults planted together")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    plan = [(f,) for f in FORMS] + [("null",), ("null",)]
    rng.shuffle(plan)
    if a.doubles:
        plan += DOUBLES
    run_plan(a, rng, plan, MODEL, FORMS, only=a.only)


if __name__ == "__main__":
    main()
