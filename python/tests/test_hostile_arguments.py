"""Hostile arguments to the Python API (issue #29): grid counts however they
are typed, sample matrices the wrong way round, names given twice, and an
expression deep enough to exhaust the C++ stack, which killed python3."""
import os
from pathlib import Path

import numpy as np
import pytest

import pneumo

SOURCE = Path(os.environ.get("PNEUMO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
CUSHION_RIG = SOURCE / "netlists" / "cushion_rig.yaml"


@pytest.mark.parametrize("count", [2.0, np.int64(2), np.int32(2), np.float64(2.0)])
def test_a_grid_count_of_any_numeric_type_is_a_count(count):
    net = pneumo.load(CUSHION_RIG)
    study = pneumo.sweep(net, grid={"z_EC": (1.0, 2.0, count)}, metrics=["t_cushion"])
    # Two points from 1 to 2, not the three values 1, 2 and the count.
    np.testing.assert_array_equal(study["z_EC"], [1.0, 2.0])


@pytest.mark.parametrize("count", [2.5, "two", True, float("nan")])
def test_a_grid_count_that_is_not_a_whole_number_is_refused(count):
    net = pneumo.load(CUSHION_RIG)
    with pytest.raises(ValueError, match="COUNT must be a whole number"):
        pneumo.sweep(net, grid={"z_EC": (1.0, 2.0, count)}, metrics=["t_cushion"])


def test_a_transposed_samples_matrix_is_refused_not_reshaped():
    net = pneumo.load(CUSHION_RIG)
    runs = np.array([[1.0, 3.0], [1.5, 3.5], [2.0, 4.0]])  # 3 runs of (z_EC, m_load)
    with pytest.raises(ValueError, match="looks transposed"):
        pneumo.sweep(net, samples=runs.T, names=["z_EC", "m_load"], metrics=["t_cushion"])


def test_a_name_given_twice_is_refused():
    net = pneumo.load(CUSHION_RIG)
    with pytest.raises(pneumo.NetlistError, match="'z_EC' is given twice"):
        pneumo.sweep(net, samples=np.array([[1.0, 2.0]]), names=["z_EC", "z_EC"], metrics=["t_cushion"])


def test_a_deeply_nested_metric_expression_is_a_netlist_error(tmp_path):
    text = CUSHION_RIG.read_text().replace(
        "\nmetrics:\n", "\nmetrics:\n  deep: {expr: \"" + "(" * 30000 + "1" + ")" * 30000 + "\"}\n", 1)
    path = tmp_path / "deep.yaml"
    path.write_text(text)
    with pytest.raises(pneumo.NetlistError, match="nested more than"):
        pneumo.load(path)
