"""The command line's conventions (docs/cli.md): a user's mistake ends with one line
``error: ...`` on stderr naming the file, component or parameter and exit status 2; a run that
fails part way writes its results so far marked ``.incomplete`` and exits with status 1."""

import zipfile
from pathlib import Path

import pytest

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
        "no component": (run + ["--set", "nosuch.x=1"], "no component 'nosuch'"),
        "no parameter": (run + ["--set", "plant.nosuch=1"], "no parameter 'nosuch'"),
        "no '='": (run + ["--set", "plant.mass"], "expected component.parameter=value"),
        "step_size by --set": (run + ["--set", "plant.step_size=nan"], "step_size"),
        "NaN parameter": (run + ["--set", "plant.mass=nan"], "parameter 'mass' = nan"),
        "infinite parameter": (run + ["--set", "plant.gravity=inf"], "'gravity' = inf"),
        "hanging sub-step": (run + ["--set", "plant.max_substep=1e-300"], "'max_substep'"),
        "stop NaN": (["run", str(plant), "--stop", "nan"], "--stop"),
        "stop negative": (["run", str(plant), "--stop", "-1"], "--stop"),
        "stop off the grid": (["run", str(plant), "--stop", "0.0033"], "stop_time"),
        "unwritable out": (["run", str(plant), "--out", str(tmp / "a_file" / "x")], "--out"),
        "unknown command": (["nosuch"], "nosuch"),
        "unknown reproduction": (["reproduce", "nosuch"], "nosuch"),
        "missing log": (["replay", str(tmp / "none.ulg")], "none.ulg"),
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
    }


@pytest.fixture
def all_cases(ssp_files, tmp_path):
    return cases(ssp_files["plant_yang2020"], tmp_path)


CASE_NAMES = [
    "missing file", "not a zip", "zip, not SSP", "malformed XML", "FMU missing",
    "value not a number", "no component", "no parameter", "no '='", "step_size by --set",
    "NaN parameter", "infinite parameter", "hanging sub-step", "stop NaN", "stop negative",
    "stop off the grid", "unwritable out", "unknown command", "unknown reproduction",
    "missing log", "log not a ULog", "offset NaN", "offset beyond the log", "no campaign",
    "no SSP for mc", "unknown fault", "fault without its sensor", "unknown fault for mc",
]


@pytest.mark.parametrize("case", CASE_NAMES)
def test_a_user_mistake_is_one_line_and_status_2(case, all_cases, capsys):
    argv, fragment = all_cases[case]
    status, _out, err = run_cli(argv, capsys)
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert fragment in lines[0]


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
