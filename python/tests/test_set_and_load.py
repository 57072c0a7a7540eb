"""One `--set` everywhere, and pneumo.load() validating as a run would
(issue #30): a component parameter set from Python is the same as writing
it in the netlist, and a netlist a run would refuse is refused at load."""
import os
from pathlib import Path

import numpy as np
import pytest

import pneumo

SOURCE = Path(os.environ.get("PNEUMO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CUSHION_RIG = SOURCE / "netlists" / "cushion_rig.yaml"


def test_a_component_parameter_set_from_python_is_the_same_as_writing_it(tmp_path):
    edited = tmp_path / "rig_40.yaml"
    edited.write_text(CUSHION_RIG.read_text().replace("bore: 32 mm", "bore: 40 mm", 1))
    by_set = pneumo.load(CUSHION_RIG).simulate(set={"cylinder.bore": "40 mm"})
    written = pneumo.load(edited).simulate()
    shipped = pneumo.load(CUSHION_RIG).simulate()
    np.testing.assert_array_equal(by_set["x"], written["x"])
    assert by_set.metrics["t_move"] == written.metrics["t_move"]
    assert by_set.metrics["t_move"] != shipped.metrics["t_move"]


def test_a_simulation_key_set_from_python_ends_the_run_there():
    res = pneumo.load(CUSHION_RIG).simulate(set={"simulation.t_end": "50 ms"})
    assert res.t[-1] == pytest.approx(0.05, abs=1e-12)


def test_a_bad_component_setting_names_the_option():
    net = pneumo.load(CUSHION_RIG)
    with pytest.raises(pneumo.NetlistError, match=r"--set cylinder.bore=40: .*no unit"):
        net.simulate(set={"cylinder.bore": "40"})
    with pytest.raises(pneumo.NetlistError, match=r"--set cylinder.borr=40 mm: unknown parameter"):
        net.simulate(set={"cylinder.borr": "40 mm"})


@pytest.mark.parametrize("edit, says", [
    (("type: translational_mass", "type: translational_mas"), "unknown component type"),
    (("bore: 32 mm", "bore: 32 mm\n    bore_typo: 1 mm"), "unknown parameter"),
])
def test_load_refuses_what_a_run_would_refuse(tmp_path, edit, says):
    bad = tmp_path / "bad.yaml"
    text = CUSHION_RIG.read_text()
    assert edit[0] in text
    bad.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(pneumo.NetlistError, match=says) as info:
        pneumo.load(bad)
    assert info.value.file == str(bad) and info.value.line > 0
