"""The command line's conventions (docs/cli.md): a user's mistake ends with one line
``error: ...`` on stderr naming the file, component or parameter and exit status 2; a run that
fails part way writes its results so far marked ``.incomplete`` and exits with status 1."""

import zipfile
from pathlib import Path

import pytest
from ulog_mutation import data_offsets, without_topic

from altfusion.cli import main

LOG = Path(__file__).resolve().parents[1] / "tests" / "data" / "flightlogs" / \
    "pyulog_sample_px4_events.ulg"


def damaged_ssp(source: Path, target: Path, edit) -> Path:
    """A copy of the SSP ``source`` whose members pass through ``edit(name, data)`` (None
    drops the member)."""
    with zipfile.ZipFile(source) as original, zipfile.ZipFile(target, "w") as copy:
        for name in original.namelist():
            data = edit(name, original.read(name))
            if data is not None:
                copy.writestr(name, data)
    return target


def run_cli(argv: list[str], capsys) -> tuple[int, str, str]:
    try:
        status = main(argv)
    except SystemExit as exit_:      # argparse's own exit
        status = exit_.code
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def cases(plant: Path, tmp: Path) -> dict[str, tuple[list[str], str]]:
    """argv and a fragment the one-line message must contain, by case."""
    (tmp / "hello.zip").write_bytes(b"hello")
    with zipfile.ZipFile(tmp / "other.zip", "w") as archive:
        archive.writestr("x.txt", "not an SSP")
    half_xml = damaged_ssp(plant, tmp / "half.ssp", lambda n, d: d[:len(d) // 2]
                           if n == "SystemStructure.ssd" else d)
    no_fmu = damaged_ssp(plant, tmp / "nofmu.ssp", lambda n, d: None
                         if n == "resources/Atmosphere.fmu" else d)
    (tmp / "a_file").write_text("")
    run = ["run", str(plant), "--stop", "1", "--out", str(tmp / "out")]
    return {
        "missing file": (["run", str(tmp / "nonexist.ssp")], "nonexist.ssp: no such file"),
        "not a zip": (["run", str(tmp / "hello.zip")], "hello.zip: not a valid SSP"),
        "zip, not SSP": (["run", str(tmp / "other.zip")], "other.zip: not a valid SSP"),
        "malformed XML": (["run", str(half_xml)], "half.ssp: not a valid SSP"),
        "FMU missing": (["run", str(no_fmu)], "Atmosphere.fmu missing"),
        "value not a number": (run + ["--set", "plant.mass=abc"], "'plant.mass' expects Real"),
        "integer with a fraction": (run + ["--set", "atmosphere.seed=2.5"],
                                    "'atmosphere.seed' expects Integer, not '2.5'"),
        "no component": (run + ["--set", "nosuch.x=1"], "no component 'nosuch'"),
        "no parameter": (run + ["--set", "plant.nosuch=1"], "no parameter 'nosuch'"),
        "no '='": (run + ["--set", "plant.mass"], "expected component.parameter=value"),
        "step_size by --set": (run + ["--set", "plant.step_size=nan"], "step_size"),
        "NaN parameter": (run + ["--set", "plant.mass=nan"], "parameter 'mass' = nan"),
        "infinite parameter": (run + ["--set", "plant.gravity=inf"], "'gravity' = inf"),
        "hanging sub-step": (run + ["--set", "plant.max_substep=1e-300"], "'max_substep'"),
        "stop NaN": (["run", str(plant), "--stop", "nan"], "--stop"),
        "stop negative": (["run", str(plant), "--stop", "-1"], "--stop"),
        "stop off the grid": (["run", str(plant), "--stop", "0.0033"],
                              "--stop 0.0033: must be a multiple of the step size 0.01 s"),
        "unwritable out": (["run", str(plant), "--out", str(tmp / "a_file" / "x")], "--out"),
        **{f"{command[0]} out a file": ([*command, "--out", str(tmp / "a_file")],
                                         f"--out {tmp / 'a_file'}: a file, not a folder")
           for command in (["run", str(plant)], ["mc", str(plant), "-n", "1"],
                           ["compare", str(plant), "-n", "1", "--estimators", "A,B"],
                           ["evaluate", "--models", str(plant.parent)],
                           ["reproduce", "yang2020", "--models", str(plant.parent)],
                           ["replay", str(LOG), "--models", str(plant.parent)])},
        "unknown command": (["nosuch"], "nosuch"),
        "unknown reproduction": (["reproduce", "nosuch"], "nosuch"),
        "missing log": (["replay", str(tmp / "none.ulg")], "none.ulg"),
        "log a folder": (["replay", str(tmp), "--models", str(plant.parent)],
                         f"{tmp}: a folder, not a ULog file"),
        "log not a ULog": (["replay", str(tmp / "hello.zip")], "hello.zip"),
        "offset NaN": (["replay", str(tmp / "hello.zip"), "--time-offset", "nan"],
                       "--time-offset"),
        "offset beyond the log": (["replay", str(LOG), "--time-offset", "1000", "--models",
                                   str(plant.parent)], "time offset 1000 s"),
        "no campaign": (["report", str(tmp / "nowhere")], "nowhere"),
        "no SSP for mc": (["mc", str(tmp / "nonexist.ssp")], "nonexist.ssp"),
        "unknown fault": (run + ["--fault", "gremlins"], "unknown fault 'gremlins'; known: "
                                                          "baro_step"),
        "fault without its sensor": (run + ["--fault", "baro_step"],
                                     "fault baro_step needs the baro sensor"),
        "unknown fault for mc": (["mc", str(plant), "-n", "1", "--fault", "gremlins", "--out",
                                  str(tmp / "mc")], "unknown fault 'gremlins'"),
        "stop beyond memory": (["run", str(plant), "--stop", "1e12", "--out", str(tmp / "o")],
                               "--stop 1e+12: recording 1.00e13 rows of"),
        "stop beyond any array": (["run", str(plant), "--stop", "1e308", "--out",
                                   str(tmp / "o")], "--stop 1e+308: recording 1.00e309 rows"),
        "mc stop beyond memory": (["mc", str(plant), "-n", "1", "--stop", "1e308", "--out",
                                   str(tmp / "mc")], "--stop 1e+308: recording 1.00e309 rows"),
        "mc stop NaN": (["mc", str(plant), "-n", "1", "--stop", "nan", "--out",
                         str(tmp / "mc")], "--stop nan: must be finite"),
        "mc stop zero": (["mc", str(plant), "-n", "1", "--stop", "0", "--out",
                          str(tmp / "mc")], "--stop 0: must be after the start time (0 s): a "
                                            "run of no duration has only its initial values"),
        "mc no runs": (["mc", str(plant), "-n", "0", "--out", str(tmp / "mc")],
                       "-n 0: the number of runs must be >= 1"),
        "mc negative seed": (["mc", str(plant), "-n", "1", "--seed", "-1", "--out",
                              str(tmp / "mc")], "--seed -1: the master seed must be >= 0"),
        "a folder": (["run", str(plant.parent)], "a folder; expected an SSP archive (a .ssp "
                                                 "file), such as"),
        "replay no estimator": (["replay", str(LOG), "--models", str(plant.parent),
                                 "--estimators", ","], "--estimators ',': names no estimator"),
        "evaluate no estimator": (["evaluate", "--estimators", ",", "--models",
                                   str(plant.parent), "--out", str(tmp / "ev")],
                                  "--estimators names no estimator"),
        "evaluate no runs": (["evaluate", "--runs", "0", "--models", str(plant.parent), "--out",
                              str(tmp / "ev")], "--runs 0: expected at least 1 run"),
        "evaluate unknown told mode": (["evaluate", "--told", "models,datasheet", "--models",
                                        str(plant.parent), "--out", str(tmp / "ev")],
                                       "unknown told modes datasheet; known: noise, models, "
                                       "nothing, misstated"),
        "evaluate told mode twice": (["evaluate", "--told", "noise,noise", "--models",
                                      str(plant.parent), "--out", str(tmp / "ev")],
                                     "--told must name each told mode once"),
        "plant mass": (run + ["--set", "plant.mass=1e-300"],
                       "component 'plant': initialization failed: parameter 'mass' = 1e-300: "
                       "must be >= 0.001"),
        "no sensor data": (["replay", str(without_sensors(tmp / "nosensors.ulg")), "--models",
                            str(plant.parent)], "nosensors.ulg: the sensor data span 0 s, less "
                                                "than one replay step (0.01 s): the sensor "
                                                "section is missing or damaged"),
        "damaged sensor data": (["replay", str(damaged_sensors(tmp / "damaged.ulg")),
                                 "--models", str(plant.parent)],
                                "damaged.ulg: the sensor data span 1e-06 s, less than one "
                                "replay step (0.01 s): the sensor section is missing or damaged "
                                "(samples: vehicle_air_data 0, vehicle_gps_position 1"),
    }


SENSOR_TOPICS = ("vehicle_air_data", "vehicle_gps_position", "sensor_combined",
                 "distance_sensor")


def without_sensors(target: Path) -> Path:
    """A copy of the sample log without a data message of any sensor topic."""
    source = LOG
    for topic in SENSOR_TOPICS:
        without_topic(source, target, topic)
        source = target
    return target


def damaged_sensors(target: Path) -> Path:
    """A copy of the sample log whose sensor samples are overwritten with 0xff bytes (time
    stamps and values alike)."""
    data = bytearray(LOG.read_bytes())
    for topic in SENSOR_TOPICS:
        for start, size in data_offsets(bytes(data), topic):
            data[start + 2:start + size] = b"\xff" * (size - 2)
    target.write_bytes(bytes(data))
    return target


@pytest.fixture
def all_cases(ssp_files, tmp_path):
    return cases(ssp_files["plant_yang2020"], tmp_path)


CASE_NAMES = [
    "missing file", "not a zip", "zip, not SSP", "malformed XML", "FMU missing",
    "value not a number", "integer with a fraction", "no component", "no parameter", "no '='",
    "step_size by --set",
    "NaN parameter", "infinite parameter", "hanging sub-step", "stop NaN", "stop negative",
    "stop off the grid", "unwritable out", "unknown command", "unknown reproduction",
    *(f"{command} out a file" for command in ("run", "mc", "compare", "evaluate", "reproduce",
                                              "replay")),
    "missing log", "log a folder", "log not a ULog", "offset NaN", "offset beyond the log",
    "no campaign",
    "no SSP for mc", "unknown fault", "fault without its sensor", "unknown fault for mc",
    "stop beyond memory", "stop beyond any array", "mc stop beyond memory", "mc stop NaN",
    "mc stop zero", "mc no runs", "mc negative seed",
    "a folder", "replay no estimator", "evaluate no estimator", "evaluate no runs",
    "evaluate unknown told mode", "evaluate told mode twice",
    "plant mass", "no sensor data", "damaged sensor data",
]


@pytest.mark.parametrize("case", CASE_NAMES)
def test_a_user_mistake_is_one_line_and_status_2(case, all_cases, capsys):
    argv, fragment = all_cases[case]
    status, _out, err = run_cli(argv, capsys)
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert fragment in lines[0]


@pytest.mark.parametrize("setting, message", [
    ("air_data.height_noise_std=1e6", "'height_noise_std' = 1000000.0: must be <= 1000.0"),
    ("air_data.drift_variance_rate=1e200", "'drift_variance_rate' = 1e+200: must be <= 100.0"),
    ("air_data.drift_rate=1e6", "'drift_rate' = 1000000.0: must be <= 0.1"),
    ("gnss.user_range_error=1e200", "'user_range_error' = 1e+200: must be <= 1000.0"),
    ("gnss.velocity_noise_std=1e200", "'velocity_noise_std' = 1e+200: must be <= 100.0"),
    ("radar.noise_std=1e200", "'noise_std' = 1e+200: must be <= 1000.0"),
    ("laser.noise_std=1e200", "'noise_std' = 1e+200: must be <= 100.0"),
    ("accelerometer.noise_std=1e200", "'noise_std' = 1e+200: must be <= 150.0"),
])
def test_noise_beyond_the_physics_is_refused_at_initialization(ssp_files, tmp_path, capsys,
                                                               setting, message):
    """A noise the sensor's physics cannot carry (a baro-height beyond the calibration's
    atmosphere gave complex numbers, a GNSS error of 1e200 an infinite RMS) is refused before
    the first step, naming the component and the parameter."""
    status, _out, err = run_cli(["run", str(ssp_files["sensors_yang2020"]), "--stop", "1",
                                 "--out", str(tmp_path), "--set", setting], capsys)
    assert status == 2, err
    component = setting.split(".")[0]
    assert err.strip() == (f"error: component '{component}': initialization failed: "
                           f"parameter {message}")


def test_a_boolean_that_is_neither_true_nor_false_is_refused(ssp_files, tmp_path, capsys):
    """``--set estimator.fault_detection=maybe`` ran with the fault layer off (any word but
    1, true and yes was taken as false); it is the user's mistake, said in one line."""
    status, _out, err = run_cli(["run", str(ssp_files["yang2020"]), "--stop", "1", "--out",
                                 str(tmp_path), "--set", "estimator.fault_detection=maybe"],
                                capsys)
    assert status == 2, err
    assert err.strip() == ("error: --set 'estimator.fault_detection=maybe': parameter "
                           "'estimator.fault_detection' expects Boolean, not 'maybe'")


def test_debug_shows_the_traceback(all_cases, capsys):
    argv, _fragment = all_cases["missing file"]
    with pytest.raises(ValueError, match="no such file"):
        main(["--debug"] + argv)


def test_a_run_failing_part_way_keeps_its_results_marked_incomplete(ssp_files, tmp_path,
                                                                     capsys):
    """A controller gain of 1e300 commands 1e308 N at the first altitude error; the plant
    refuses the thrust that drives its state non-finite: the run stops with status 1."""
    status, out, err = run_cli(
        ["run", str(ssp_files["plant_yang2020"]), "--stop", "10", "--out", str(tmp_path),
         "--set", "controller.kp=1e300", "--set", "controller.thrust_max=1e308"], capsys)
    assert status == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "drives the state non-finite" in lines[0]
    assert ".incomplete" in lines[0]
    csv = (tmp_path / "plant_yang2020.incomplete.csv").read_text().splitlines()
    assert csv[0].startswith("time [s],plant.h [m]") and len(csv) >= 2
    assert not (tmp_path / "plant_yang2020.csv").exists()
