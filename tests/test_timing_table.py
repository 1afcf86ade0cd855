"""Result files of every host read as 'component.variable' columns (altfusion.timing.table),
and the one-line errors for what is not a result of the system."""

from pathlib import Path

import pytest

from altfusion.errors import UsageError
from altfusion.timing.table import column_name, read_result

COMPONENTS = {"gnss", "estimator"}


def test_our_layout_drops_the_units(tmp_path):
    path = tmp_path / "ours.csv"
    path.write_text("time [s],gnss.gps_count,gnss.gps_time [s],plant.h [m]\n"
                    "0.0,0.0,0.0,10.0\n0.1,1.0,0.1,10.5\n")
    table = read_result(path, COMPONENTS)
    assert table.layout == "altfusion"
    assert list(table.columns) == ["gnss.gps_count", "gnss.gps_time"]   # plant: not asked
    assert table.columns["gnss.gps_time"].tolist() == [0.0, 0.1]


def test_omsimulator_layout_keeps_the_first_row_of_each_time(tmp_path):
    """OMSimulator writes a row after each step and one after the exchange: an input column
    changes in the second (as in system_tests' OMSimulator runs)."""
    path = tmp_path / "oms.csv"
    path.write_text('"time","yang2020.gnss.gps_count","yang2020.estimator.gps_count"\n'
                    "0, 0, 0\n0.1, 1, 0\n0.1, 1, 1\n0.2, 2, 1\n0.2, 2, 2\n0.2, 2, 2\n")
    table = read_result(path, COMPONENTS)
    assert table.layout == "OMSimulator"
    assert table.time.tolist() == [0.0, 0.1, 0.2]
    assert table.columns["estimator.gps_count"].tolist() == [0, 0, 1]


@pytest.mark.parametrize(("header", "name"), [
    ("model.root.gnss.gps_count", "gnss.gps_count"),
    ("root.gnss.gps_count", "gnss.gps_count"),
    ("gnss.gps_time [s]", "gnss.gps_time"),
    ("yang2020.plant.h", None),
])
def test_column_names_lose_system_prefixes(header, name):
    assert column_name(header, COMPONENTS) == name


@pytest.mark.parametrize(("text", "message"), [
    (None, "no such file"),
    ("Time,StepCount,gps_count\n0,0,0\n", "unknown column layout (first column ['Time']"),
    ("time [s],plant.h\n0,1\n", "no column names a component of the system"),
    ("time [s],gnss.gps_count\n0,zero\n", "not a result table"),
    ("time [s],gnss.gps_count\n1,0\n0,1\n", "the time column decreases"),
])
def test_what_is_no_result_of_the_system_is_one_usage_error(tmp_path, text, message):
    path = tmp_path / "result.csv"
    if text is not None:
        path.write_text(text)
    with pytest.raises(UsageError, match=message.replace("[", r"\[").replace("(", r"\(")):
        read_result(path, COMPONENTS)


def test_a_result_without_rows_is_refused(tmp_path: Path):
    path = tmp_path / "empty.csv"
    path.write_text("time [s],gnss.gps_count\n")
    with pytest.raises(UsageError, match="0 rows"):
        read_result(path, COMPONENTS)
