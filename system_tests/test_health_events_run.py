"""``altfusion run`` says what each estimator did in words: the fault suite's baro_step read as
rejections, isolation, fallback and re-admission, and ``status`` decoded by bit name."""

import subprocess
import sys
from pathlib import Path

import pytest

from altfusion.cosim.results import Results
from altfusion.health_events import events_csv, health_events

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def baro_step_run(ssp_files, tmp_path_factory):
    out = tmp_path_factory.mktemp("baro_step")
    completed = subprocess.run(
        [sys.executable, "-m", "altfusion.cli", "run", str(ssp_files["fault_flight"]),
         "--fault", "baro_step", "--stop", "140", "--out", str(out)],
        capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert completed.returncode == 0, completed.stderr[-3000:]
    return out, completed.stdout


def block(stdout: str, estimator: str) -> list[str]:
    """The lines of ``estimator``'s health events."""
    lines = stdout.split("health events")[1].splitlines()
    start = lines.index(f"  {estimator}")
    rest = lines[start + 1:]
    return rest[:next((i for i, line in enumerate(rest) if not line.startswith("    ")),
                      len(rest))]


def test_the_baro_step_is_said_in_words(baro_step_run):
    """The barometer steps by 200 m at 130 s (docs/faults.md): every estimator rejects it
    within one recorded row and isolates it after reset_timeout = 2.5 s. AltitudeEKF's range
    aid holds from the radio altimeter's first second on the ground to the climb above its
    25 m limit."""
    out, stdout = baro_step_run
    events = out / "fault_flight+baro_step.events.csv"
    assert f"health events (all in {events}):" in stdout
    said = block(stdout, "AltitudeEKF")
    assert said[0] == "       0.10 s  initialized"
    assert said[1] == "       1.20 s  range aid started: a rangefinder is the height"
    assert said[2] == "      68.00 s  range aid stopped"
    assert said[3].startswith("     130.00 s  rejected baro in 26 recorded rows between 130.0 "
                              "and 132.5 s")
    assert said[4].startswith("     132.50 s  isolated baro (test ratio ")
    assert said[5] == "     132.50 s  height carried by gps, radar, laser"
    for estimator in ("BaselineKF", "YangFusionKF", "XuSHAEKF"):
        assert any(line.startswith("     132.50 s  isolated baro")
                   for line in block(stdout, estimator)), estimator
    results = Results.from_csv(out / "fault_flight+baro_step.csv")
    assert events.read_text() == events_csv(health_events(results))


def test_the_summary_decodes_status_by_bit_name(baro_step_run):
    _out, stdout = baro_step_run
    line = next(line for line in stdout.splitlines() if line.startswith("AltitudeEKF.status"))
    assert "final INITIALIZED BARO_REJECTED BARO_ISOLATED GPS_FUSED" in line
    assert line.endswith("also seen RANGE_AID BARO_FUSED")


def test_the_estimators_notes_are_said_and_kept(baro_step_run):
    """What each estimator logged (its notes: here the failed baro's rejections, one line a
    second, and AltitudeEKF's range aid) is printed as a count and the first line, and
    written whole, one line each after the estimator's name; before, `run` dropped them."""
    out, stdout = baro_step_run
    kept = out / "fault_flight+baro_step.warnings.txt"
    assert f"warnings (all in {kept}):" in stdout
    lines = kept.read_text().splitlines()
    for estimator in ("BaselineKF", "YangFusionKF", "XuSHAEKF", "AltitudeEKF"):
        written = [line.removeprefix(f"{estimator}: ") for line in lines
                   if line.startswith(f"{estimator}: ")]
        assert f"  {estimator}: {len(written)}, first: {written[0]}" in stdout.splitlines()
        assert any("baro: sample rejected" in line for line in written), estimator
    assert str(kept) in stdout.splitlines()[-1]


def test_a_campaign_run_re_run_alone_says_its_notes(ssp_files, tmp_path):
    """`mc --run i`, the way to look into one run of a campaign, prints and writes its
    components' warnings as `run` does (before, only its metrics and signal ranges)."""
    def mc(*extra: str) -> str:
        completed = subprocess.run(
            [sys.executable, "-m", "altfusion.cli", "mc", str(ssp_files["fault_flight"]),
             "--fault", "baro_step", "-n", "1", "--stop", "135", "--out", str(tmp_path),
             *extra], capture_output=True, text=True, timeout=600, cwd=ROOT)
        assert completed.returncode == 0, completed.stderr[-3000:]
        return completed.stdout

    mc()
    stdout = mc("--run", "0")
    kept = tmp_path / "rerun_00000.warnings.txt"
    assert f"warnings (all in {kept}):" in stdout
    assert any(line.startswith("  XuSHAEKF: ") and "baro: sample rejected" in line
               for line in stdout.splitlines())
    assert "XuSHAEKF: t = 130.0 s: baro: sample rejected" in kept.read_text()
    assert "identical to run 0 of the campaign" in stdout
