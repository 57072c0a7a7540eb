"""Ctrl-C during a long C++ call (issue #29): Python sees its signals only
between bytecodes, so before pneumo took them itself a KeyboardInterrupt
waited for the whole sweep to end."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

SOURCE = Path(os.environ.get("PNEUMO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CUSHION_RIG = SOURCE / "netlists" / "cushion_rig.yaml"

# 100,000 runs of the rig take about half an hour on two threads.
SCRIPT = """
import sys, pneumo
net = pneumo.load(sys.argv[1])
print("running", flush=True)
try:
    pneumo.sweep(net, grid={"z_EC": "0.5:3:100000"}, metrics=["t_cushion"], threads=2)
    print("finished", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
res = net.simulate()
print("after", res.metrics["t_cushion"], flush=True)
"""


def test_ctrl_c_stops_a_long_sweep_at_the_next_step_and_pneumo_runs_again():
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT, str(CUSHION_RIG)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "running"
        time.sleep(1.5)  # well inside the sweep
        proc.send_signal(signal.SIGINT)
        sent = time.monotonic()
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    waited = time.monotonic() - sent
    assert proc.returncode == 0, err
    lines = out.split("\n")
    assert lines[0] == "interrupted", out
    # The process carried on: a run after the interrupt is not interrupted.
    assert lines[1].startswith("after ") and float(lines[1].split()[1]) > 0.0, out
    # A run of the rig takes about 20 ms; the sweep stopped within seconds, not at its end.
    assert waited < 20.0, waited
