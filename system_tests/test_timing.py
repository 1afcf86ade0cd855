"""``altfusion timing`` on yang2020 as every host runs it (our runner, libcosim, ECOS,
OMSimulator), and on result files with a sample removed or a stamp altered.

Runs are 20 s (200 GPS and 100 radio-altimeter samples, 2000 of the barometer and the
accelerometer) to keep CI cheap; the checks are exact, so a short run judges as much as a long
one."""

import csv
import re
from dataclasses import replace
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from altfusion.cli import main
from altfusion.cosim.results import Results
from altfusion.cosim.runner import simulate
from altfusion.cosim.ssp import read_ssp, write_ssp
from altfusion.estimators.baseline import BaselineKF
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, SystemSpec
from altfusion.systems.wiring import estimator_connections
from altfusion.timing.command import with_timing_record
from altfusion.timing.streams import Consumer, sensor_streams

STOP = 20.0
STREAMS = ("air_data.baro", "gnss.gps", "accelerometer.acc", "radar.radar")


def timing(argv: list[str], capsys) -> tuple[int, str, str]:
    status = main(["timing", *[str(a) for a in argv]])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def cells(out: str, stream: str, check: str) -> list[str]:
    """The cells of row ``check`` in the table of ``stream`` (cells are 2+ spaces apart)."""
    table = out.split(f"{stream} (", 1)[1].split("\n\n", 1)[0]
    row = next(line for line in table.splitlines() if line.strip().startswith(check))
    return re.split(r"\s{2,}", row.strip())


def assert_every_stream_holds(status: int, out: str) -> None:
    assert status == 0, out
    assert "all 4 recorded streams hold their declared timing" in out
    for stream in STREAMS:
        assert f"\n{stream} (" in out or out.startswith(f"{stream} (")


@pytest.fixture(scope="module")
def our_csv(ssp_files, tmp_path_factory) -> Path:
    """yang2020 run in our runner for 20 s by ``altfusion timing --csv``."""
    path = tmp_path_factory.mktemp("timing") / "yang2020.csv"
    assert main(["timing", str(ssp_files["yang2020"]), "--stop", str(STOP), "--csv",
                 str(path)]) == 0
    return path


def test_our_runner_keeps_every_streams_timing(ssp_files, capsys):
    status, out, _ = timing([ssp_files["yang2020"], "--stop", STOP], capsys)
    assert_every_stream_holds(status, out)
    assert cells(out, "air_data.baro", "samples expected") == [
        "samples expected / seen", "2000 / 2000"]                     # every 10 ms
    assert cells(out, "gnss.gps", "estimator.gps_count") == [
        "estimator.gps_count", "saw 200 of 200, latency 0 s", "<= 0.01 s", "ok"]


def test_libcosim_keeps_every_streams_timing_one_step_later(ssp_files, capsys):
    """libcosim's Jacobi master hands a count to the estimator at its next step: 0.01 s."""
    status, out, _ = timing([ssp_files["yang2020"], "--stop", STOP, "--engine", "libcosim"],
                            capsys)
    assert_every_stream_holds(status, out)
    assert cells(out, "gnss.gps", "estimator.gps_count") == [
        "estimator.gps_count", "saw 199 of 200 (1 after the last row), latency 0.01 s",
        "<= 0.01 s", "ok"]


def test_ecos_shows_a_slow_sensors_samples_before_they_are_taken(ssp_files, capsys):
    """ECOS steps the GNSS receiver (0.1 s) and the radio altimeter (0.2 s) at the start of
    their steps and shows, and hands the estimator, the sample of the step's end at once."""
    status, out, _ = timing([ssp_files["yang2020"], "--stop", STOP, "--engine", "ecos"],
                            capsys)
    assert status == 1
    assert "4 violation(s) in 2 of 4 streams:" in out
    assert cells(out, "gnss.gps", "estimator.gps_count") == [
        "estimator.gps_count", "saw 200 of 200, latency -0.09 s", "<= 0.01 s", "FAIL"]
    assert "gnss.gps: 200 samples shown before they were due (instant + latency): instant " \
           "0.1 s shown at 0.01 s" in out
    assert "radar.radar: 100 samples shown before they were due" in out


def test_ecos_keeps_every_streams_timing_with_every_sensor_at_the_base_step(
        ssp_files, tmp_path, capsys):
    loaded = read_ssp(ssp_files["yang2020"])
    spec = loaded.spec
    spec = replace(spec, components=tuple(replace(c, step_size=spec.base_step)
                                          for c in spec.components))
    ssp = write_ssp(spec, loaded.fmu_paths, tmp_path / "yang2020_base_step.ssp")
    status, out, _ = timing([ssp, "--stop", STOP, "--engine", "ecos"], capsys)
    assert_every_stream_holds(status, out)


def test_run_record_timing_writes_what_timing_checks_every_base_step(ssp_files, tmp_path,
                                                                     capsys):
    assert main(["run", str(ssp_files["yang2020"]), "--stop", "5", "--record", "timing",
                 "--out", str(tmp_path)]) == 0
    results = Results.from_csv(tmp_path / "yang2020.csv")
    assert results.time.size == 501                                  # every 0.01 s
    for stream in STREAMS:
        prefix = stream.split(".")[1]
        for column in (f"{stream}_count", f"{stream}_time", f"estimator.{prefix}_count"):
            assert column in results.columns
    assert "estimator.h_est" in results.columns                     # the system's own record
    capsys.readouterr()
    status, out, _ = timing([tmp_path / "yang2020.csv", "--system", ssp_files["yang2020"]],
                            capsys)
    assert_every_stream_holds(status, out)


def test_a_result_without_counts_names_the_option_that_records_them(ssp_files, tmp_path,
                                                                    capsys):
    assert main(["run", str(ssp_files["yang2020"]), "--stop", "1", "--out",
                 str(tmp_path)]) == 0
    capsys.readouterr()
    status, out, err = timing([tmp_path / "yang2020.csv", "--system", ssp_files["yang2020"]],
                              capsys)
    assert (status, out) == (2, "")
    assert err.startswith("error: the result records no sample count and stamp") and \
        err.strip().endswith("record them with altfusion run --record timing or altfusion "
                             "timing SYSTEM.ssp --engine HOST --csv OUT.csv")


def test_a_result_file_without_its_system_is_a_one_line_error(our_csv, capsys):
    status, out, err = timing([our_csv], capsys)
    assert (status, out) == (2, "")
    assert err == f"error: {our_csv}: a result file needs --system SYSTEM.ssp (the system it " \
                  f"is a result of)\n"


def delayed_gnss_system(fmus: dict[str, Path], target: Path) -> Path:
    """A GNSS receiver sampling at 0.02 + k·0.1 s and delivering 0.05 s later, and a
    barometer at 0.05 s, on the plant's truth, fused by BaselineKF."""
    sensors = ("air_data", "gnss")
    parameters = {"gnss": {"sample_period": 0.1, "sample_offset": 0.02, "latency": 0.05},
                  "air_data": {"sample_period": 0.05}}
    components = (plant_components("yang2020") + sensor_components(sensors,
                                                                    parameters=parameters)
                  + (ComponentSpec("estimator", "BaselineKF", 0.01, {}),))
    spec = SystemSpec("delayed_gnss", "a late GNSS", components,
                      plant_connections() + sensor_connections(sensors)
                      + estimator_connections(BaselineKF, sensors=sensors), stop_time=STOP)
    return write_ssp(spec, fmus, target)


def test_offset_and_latency_are_read_from_the_ssp_and_kept_in_every_host(fmus, tmp_path,
                                                                         capsys):
    ssp = delayed_gnss_system(fmus, tmp_path / "delayed_gnss.ssp")
    loaded = read_ssp(ssp)
    gnss = next(s for s in sensor_streams(loaded.spec, loaded.fmu_paths) if s.prefix == "gps")
    assert (gnss.period, gnss.offset, gnss.latency) == (Fraction("0.1"), Fraction("0.02"),
                                                        Fraction("0.05"))
    for engine, latency in (("ours", "0.05 s"), ("libcosim", "0.06 s")):
        status, out, _ = timing([ssp, "--stop", STOP, "--engine", engine], capsys)
        assert status == 0, out
        assert cells(out, "gnss.gps", "samples expected") == ["samples expected / seen",
                                                              "200 / 200"]   # 0.02..19.92 s
        assert cells(out, "gnss.gps", "delivery") == [
            "delivery (row - instant)", "0.05 s", "0.05 .. 0.05 s", "ok"]
        assert cells(out, "gnss.gps", "estimator.gps_count")[1].endswith(f"latency {latency}")


def test_the_relays_of_a_fault_system_are_followed_to_the_estimator(ssp_files):
    loaded = read_ssp(ssp_files["fault_demo_yang"])
    streams = {s.name: s for s in sensor_streams(loaded.spec, loaded.fmu_paths)}
    assert sorted(streams) == ["accelerometer.acc", "air_data.baro", "gnss.gps", "radar.radar"]
    assert streams["gnss.gps"].consumers == (
        Consumer("estimator", "gps_count", handover=0.02, relays=("fault",)),)


def test_a_gnss_outage_is_told_from_lost_samples_by_its_fix(ssp_files, tmp_path, capsys):
    """GnssReceiver's outage from 10 to 20 s: 100 instants without a new measurement while
    gps_fix is false pass; the same rows claiming a fix are 100 samples missing."""
    assert main(["run", str(ssp_files["sensors_yang2020"]), "--stop", "30", "--record",
                 "timing", "--set", "gnss.outage_windows=10 20", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    csv_path, system = tmp_path / "sensors_yang2020.csv", ssp_files["sensors_yang2020"]
    status, out, _ = timing([csv_path, "--system", system], capsys)
    assert status == 0, out
    assert cells(out, "gnss.gps", "no new measurement") == [
        "no new measurement", "100 instants", "while gps_fix false", "ok"]
    edited = _edited(csv_path, tmp_path / "fix.csv",
                     lambda columns: columns["gnss.gps_fix"].fill(1.0))
    status, out, _ = timing([edited, "--system", system], capsys)
    assert status == 1
    assert "gnss.gps: 100 samples missing while gps_fix was true: instant 10 s; " \
           "instant 10.1 s" in out


def _edited(source: Path, target: Path, edit) -> Path:
    results = Results.from_csv(source)
    edit(results.columns)
    return results.to_csv(target)


def _first_change(count: np.ndarray, after: int) -> int:
    return int(np.flatnonzero(np.diff(count[after:]) > 0)[0]) + after + 1


def test_a_sample_removed_from_a_result_file_is_reported(ssp_files, our_csv, tmp_path, capsys):
    def remove(columns):
        count, stamp = columns["air_data.baro_count"], columns["air_data.baro_time"]
        row = _first_change(count, 500)
        count[row], stamp[row] = count[row - 1], stamp[row - 1]

    status, out, _ = timing([our_csv, "--system", ssp_files["yang2020"]], capsys)
    assert status == 0, out
    edited = _edited(our_csv, tmp_path / "removed.csv", remove)
    status, out, _ = timing([edited, "--system", ssp_files["yang2020"]], capsys)
    assert status == 1
    assert "air_data.baro: 1 samples late or lost: instant 5.01 s shown at 5.02 s, due in " \
           "the row at 5.01 s" in out
    assert "air_data.baro: 1 rows where estimator.baro_count is ahead" in out
    assert cells(out, "air_data.baro", "estimator.baro_count")[-1] == "FAIL"


def test_an_altered_stamp_in_a_result_file_is_reported(ssp_files, our_csv, tmp_path, capsys):
    def alter(columns):
        count, stamp = columns["gnss.gps_count"], columns["gnss.gps_time"]
        row = _first_change(count, 500)
        stamp[row:row + 10] += 0.003

    edited = _edited(our_csv, tmp_path / "altered.csv", alter)
    status, out, _ = timing([edited, "--system", ssp_files["yang2020"]], capsys)
    assert status == 1
    assert "gnss.gps: 1 stamps off the schedule: 5.103 s at 5.1 s (+0.003 s" in out


def _omsimulator_layout(results: Results, system: str, consumers: list[str],
                        path: Path) -> Path:
    """``results`` written as OMSimulator writes a result: 'time', then
    '<system>.<component>.<variable>', and a second row at each time after the exchange, in
    which the consumers' inputs already hold the next step's values."""
    names = list(results.columns)
    data = np.column_stack([results.time] + [results.columns[n] for n in names])
    exchanged = data.copy()
    for name in consumers:
        column = names.index(name) + 1
        exchanged[:-1, column] = data[1:, column]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle, quoting=csv.QUOTE_NONNUMERIC)
        writer.writerow(["time"] + [f"{system}.{n}" for n in names])
        for row, after in zip(data, exchanged, strict=True):
            writer.writerow([float(v) for v in row])
            writer.writerow([float(v) for v in after])
    return path


def test_a_result_in_omsimulators_layout_is_checked_as_ours(ssp_files, tmp_path, capsys):
    """Our Jacobi master (every input latched, as OMSimulator's one-step master) written in
    OMSimulator's layout: the same verdict and latencies as libcosim's."""
    loaded = read_ssp(ssp_files["yang2020"])
    spec = with_timing_record(loaded.spec, loaded.fmu_paths)
    results = simulate(spec, loaded.fmu_paths, stop_time=STOP, master="jacobi")
    consumers = [n for n in results.columns if n.startswith("estimator.")
                 and n.endswith("_count")]
    path = _omsimulator_layout(results, "yang2020", consumers, tmp_path / "oms.csv")
    status, out, _ = timing([path, "--system", ssp_files["yang2020"]], capsys)
    assert_every_stream_holds(status, out)
    assert "(OMSimulator layout, 2001 rows" in out
    assert cells(out, "gnss.gps", "estimator.gps_count") == [
        "estimator.gps_count", "saw 199 of 200 (1 after the last row), latency 0.01 s",
        "<= 0.01 s", "ok"]


# ------------------------------------------------------------------------------ OMSimulator
def test_omsimulator_keeps_yang2020s_timing(omsimulator, ssp_files, capsys):
    """yang2020 as it is, in OMSimulator's Python API at one 0.01 s step for every component:
    its result, in OMSimulator's layout, holds every stream's timing, the estimator seeing
    each sample one step later (OMSimulator's master is of Jacobi type)."""
    run = omsimulator.ssp(ssp_files["yang2020"], STOP, 0.01)
    assert run.returncode == 0, run.describe()
    assert run.result.read_text().startswith('"time","yang2020.')
    status, out, _ = timing([run.result, "--system", ssp_files["yang2020"]], capsys)
    assert_every_stream_holds(status, out)
    assert "(OMSimulator layout, 2001 rows" in out
    assert cells(out, "gnss.gps", "estimator.gps_count") == [
        "estimator.gps_count", "saw 199 of 200 (1 after the last row), latency 0.01 s",
        "<= 0.01 s", "ok"]
