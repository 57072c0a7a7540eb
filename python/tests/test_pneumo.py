"""The Python module against physics and against the `pneumo` command line.

Run by ctest (python_module) with PYTHONPATH=build/python, PNEUMO_BINARY the
built command and PNEUMO_SOURCE_DIR the repository.
"""

import csv
import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import pneumo

SOURCE = Path(os.environ.get("PNEUMO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
PNEUMO = os.environ.get("PNEUMO_BINARY", str(SOURCE / "build" / "pneumo"))
CUSHION_RIG = SOURCE / "netlists" / "cushion_rig.yaml"
TANK_FILLING = SOURCE / "netlists" / "tank_filling.yaml"


def cli(*args):
    return subprocess.run([PNEUMO, *map(str, args)], capture_output=True, text=True)


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    return rows[0], rows[1:]


# What the command line shows in a netlist's display units, back in SI (the
# module keeps SI): scale and offset of the units the shipped netlists use.
DISPLAY = {"": (1, 0), "1": (1, 0), "m": (1, 0), "s": (1, 0), "Pa": (1, 0), "K": (1, 0), "m/s": (1, 0), "J": (1, 0),
           "mm": (1e-3, 0), "bar": (1e5, 0), "barg": (1e5, 101325.0), "degC": (1, 273.15)}


def si(value, unit):
    scale, offset = DISPLAY[unit]
    return scale * value + offset


def rig_with_event_metrics(tmp_path):
    """The cushion rig with two more metrics, so that the command line writes
    the final x and the cushion entry time with all 17 digits (--metrics-out)."""
    text = CUSHION_RIG.read_text().replace(
        "\nmetrics:\n",
        "\nmetrics:\n  x_final: {final: x}\n  t_entry: {event: cylinder.cushion_entry}\n", 1)
    path = tmp_path / "cushion_rig.yaml"
    path.write_text(text)
    return path


def test_tank_filling_meets_the_adiabatic_closed_form():
    net = pneumo.load(TANK_FILLING)
    par = net.parameters
    assert par["p_source"].unit == "Pa" and par["V_tank"].unit == "m3"
    p1, T1 = 1e5, 293.15  # the tank's start state in the netlist
    p2, T_in, V = par["p_source"].value, par["T_source"].value, par["V_tank"].value
    R, kappa = 287.05, 1.4
    m_end = p1 * V / (R * T1) + (p2 - p1) * V / (kappa * R * T_in)
    T_end = p2 * V / (m_end * R)
    res = net.simulate()
    assert res.units["T"] == "K" and res.units["m"] == "kg"
    assert res["p"][-1] == pytest.approx(p2, rel=1e-3)
    assert res["m"][-1] == pytest.approx(m_end, rel=1e-3)
    assert res["T"][-1] == pytest.approx(T_end, rel=1e-3)
    # Filling only: the tank's mass never falls.
    assert np.all(np.diff(res["m"]) >= -1e-12)


def test_overrides_take_units_like_the_command_line():
    net = pneumo.load(TANK_FILLING)
    a = net.simulate(set={"p_source": "3 bar"})
    b = net.simulate(set={"p_source": 3e5})
    assert a["p"][-1] == pytest.approx(3e5, rel=1e-3)
    np.testing.assert_array_equal(a["p"], b["p"])
    # The netlist itself is unchanged by a run's overrides.
    assert net.parameters["p_source"].value == 2e5


def test_cushion_rig_equals_the_command_lines_results(tmp_path):
    path = rig_with_event_metrics(tmp_path)
    out, metrics_out = tmp_path / "out.csv", tmp_path / "metrics.csv"
    run = cli("simulate", path, "-q", "-o", out, "--metrics-out", metrics_out)
    assert run.returncode == 0, run.stderr
    _, metric_rows = read_csv(metrics_out)
    cli_metric = {r[0]: si(float(r[1]), r[2]) for r in metric_rows}

    res = pneumo.load(path).simulate()
    entry = res.events_of("cylinder", "cushion_entry")
    assert len(entry) == 1
    assert abs(res["x"][-1] - cli_metric["x_final"]) <= 1e-12
    assert abs(entry[0].t - cli_metric["t_entry"]) <= 1e-12
    assert res.metrics["t_entry"] == pytest.approx(entry[0].t, abs=1e-12)
    # Entry after the valve opens (10 ms), impact after entry.
    assert 0.01 < entry[0].t < entry[0].t + res.metrics["t_cushion"]
    # The results file holds 10 significant digits: every row of x agrees to those.
    header, rows = read_csv(out)
    cli_x = np.array([si(float(r[header.index("x [mm]")]), "mm") for r in rows])
    assert len(cli_x) == len(res)
    np.testing.assert_allclose(res["x"], cli_x, rtol=5e-10, atol=1e-12)
    assert res.units["p_EC"] == "Pa"
    assert res.stats["steps"] > 0 and res.stats["residual_evals"] > res.stats["steps"]


def test_sweep_equals_pneumo_sweep_on_the_same_grid(tmp_path):
    out = tmp_path / "sweep.csv"
    run = cli("sweep", CUSHION_RIG, "--grid", "z_EC=0.5:3:4", "--grid", "m_load=2 kg:5 kg:2",
              "--metrics", "t_cushion,p_EC_peak", "-j", "2", "-q", "-o", out)
    assert run.returncode == 0, run.stderr
    header, rows = read_csv(out)

    net = pneumo.load(CUSHION_RIG)
    study = pneumo.sweep(net, grid={"z_EC": "0.5:3:4", "m_load": ("2 kg", "5 kg", 2)},
                         metrics=["t_cushion", "p_EC_peak"], threads=2)
    assert len(study) == len(rows) == 8
    assert all(study.ok)
    names = [h.split(" [")[0] for h in header]
    units = [h.split(" [")[1].rstrip("]") if " [" in h else "" for h in header]
    for name in ("z_EC", "m_load", "t_cushion", "p_EC_peak", "steps"):
        k = names.index(name)
        cli_values = np.array([si(float(r[k]), units[k] if name in ("t_cushion", "p_EC_peak") else "") for r in rows])
        values = study.steps if name == "steps" else study[name]
        np.testing.assert_allclose(values, cli_values, rtol=1e-12, atol=0, err_msg=name)
    assert study.units["p_EC_peak"] == "Pa"
    # A wider cushion throttle brakes less: the piston spends less time in the cushion.
    for m in (2.0, 5.0):
        t = study["t_cushion"][study["m_load"] == m]
        assert np.all(np.diff(t) < 0)


def test_samples_give_the_runs_of_the_grid():
    net = pneumo.load(CUSHION_RIG)
    grid = pneumo.sweep(net, grid={"z_EC": [0.5, 2.0]}, metrics=["t_cushion"])
    samples = pneumo.sweep(net, samples=np.array([[2.0], [0.5]]), names=["z_EC"], metrics=["t_cushion"])
    np.testing.assert_array_equal(samples["t_cushion"], grid["t_cushion"][::-1])


def test_a_malformed_netlist_raises_netlist_error_naming_file_and_line(tmp_path):
    lines = TANK_FILLING.read_text().splitlines()
    n = next(i for i, l in enumerate(lines) if l.strip().startswith("valve:"))
    lines[n] = "  valve:  {type: iso6358_throttle, C: 0.4 furlong, b: 0.3}"
    bad = tmp_path / "bad.yaml"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(pneumo.NetlistError) as info:
        pneumo.load(bad).simulate()
    e = info.value
    assert f"{bad}:{n + 1}:" in str(e)
    assert (e.file, e.line, e.component, e.parameter) == (str(bad), n + 1, "valve", "C")
    # The same message as the command line, which exits with status 2.
    run = cli("simulate", bad, "-q", "-o", tmp_path / "bad.csv")
    assert run.returncode == 2
    assert run.stderr.strip() == str(e)


def test_a_run_the_solver_cannot_finish_raises_simulation_error_with_the_rows_so_far(tmp_path):
    path = SOURCE / "tests" / "data" / "bad_netlists" / "solver_failure.yaml"  # max_step 1 ns
    with pytest.raises(pneumo.SimulationError) as info:
        pneumo.load(path).simulate()
    e = info.value
    assert e.t < 1.0 and len(e.result) >= 1 and e.result.t[0] == 0.0
    # The command line's message, which exits with status 1.
    run = cli("simulate", path, "-q", "-o", tmp_path / "out.csv")
    assert run.returncode == 1
    assert f"pneumo: {e}" in run.stderr


def test_an_unknown_override_is_a_netlist_error():
    with pytest.raises(pneumo.NetlistError, match="--set no_such"):
        pneumo.load(TANK_FILLING).simulate(set={"no_such": 1.0})


def test_the_gil_is_released_while_a_sweep_runs():
    """A Python thread keeps counting while the sweep runs in C++: with the
    GIL held it could count only in the moments before and after the call."""
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())

    net = pneumo.load(CUSHION_RIG)
    counter = threading.Thread(target=count)
    counter.start()
    try:
        t0 = time.perf_counter()
        study = pneumo.sweep(net, grid={"z_EC": "0.5:3:40"}, metrics=["t_cushion"], threads=1)
        t1 = time.perf_counter()
    finally:
        stop.set()
        counter.join()
    assert all(study.ok)
    margin = 0.02  # s: more than Python's thread switch interval (5 ms)
    assert t1 - t0 > 4 * margin
    inside = sum(t0 + margin < t < t1 - margin for t in ticks)
    assert inside > 1000


def test_python_threads_may_simulate_one_netlist_at_once():
    net = pneumo.load(CUSHION_RIG)
    settings = [0.5, 1.0, 2.0, 3.0]
    alone = [net.simulate(set={"z_EC": z})["x"] for z in settings]
    together = [None] * len(settings)

    def run(k):
        together[k] = net.simulate(set={"z_EC": settings[k]})["x"]

    threads = [threading.Thread(target=run, args=(k,)) for k in range(len(settings))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(alone, together):
        np.testing.assert_array_equal(a, b)


def test_component_library():
    names = pneumo.components()
    assert "hose" in names and "cushioned_cylinder" in names
    hose = pneumo.component("hose")
    assert hose.type == "hose" and hose.ports
    assert all(p.unit for p in hose.parameters if p.kind == "scalar")
    with pytest.raises(KeyError):
        pneumo.component("no_such_component")


def test_to_pandas_when_pandas_is_present():
    pd = pytest.importorskip("pandas")
    res = pneumo.load(TANK_FILLING).simulate()
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == res.names[1:]
