"""Ctrl-C on ``altfusion run``: exit status 130 (as ``altfusion mc``), one line on stderr,
and the results so far written marked ``.incomplete``, whenever it comes: never a traceback,
never an FMU's "Fatal py exception" (a KeyboardInterrupt raised inside an FMU's Python code)."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

INTERRUPTED = 130
STOP = 2000.0
"""Simulated seconds asked for: far more than any machine simulates before the signal."""
STOPPED_WITHIN = 20.0
"""Seconds the run may take to stop after Ctrl-C (one base step of seven estimators takes
milliseconds; generous for a shared machine)."""


def wait_for_fmus(process: subprocess.Popen, timeout: float = 60.0) -> None:
    """Return once ``process`` has loaded an FMU's library (it is building the simulation):
    Ctrl-C during Python's own start-up, before ``altfusion`` runs, is Python's to report."""
    maps = Path(f"/proc/{process.pid}/maps")
    deadline = time.monotonic() + timeout
    while "pythonfmu-export" not in maps.read_text():
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.02)


@pytest.mark.parametrize("after", [0.0, 4.0, 8.0])
def test_ctrl_c_on_run_exits_130_with_the_partial_result_marked_incomplete(ssp_files,
                                                                           tmp_path, after):
    """Interrupted while the FMUs are being instantiated (0 s after the first FMU library is
    loaded) or while stepping (4 and 8 s later). The flight is 2000 s long so that no machine
    finishes it before the signal: 200 s of seven estimators took 15 s on a loaded machine
    here and under 8 s on CI."""
    process = subprocess.Popen(
        [sys.executable, "-m", "altfusion.cli", "run", str(ssp_files["fault_flight"]),
         "--fault", "baro_step", "--stop", str(STOP), "--out", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for_fmus(process)
    time.sleep(after)
    process.send_signal(signal.SIGINT)
    sent = time.monotonic()
    _out, err = process.communicate(timeout=120)
    assert time.monotonic() - sent < STOPPED_WITHIN
    assert process.returncode == INTERRUPTED, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: interrupted"), err
    assert not (tmp_path / "fault_flight+baro_step.csv").exists()
    if lines[0] != "error: interrupted":
        assert "results so far written (marked .incomplete)" in lines[0]
        rows = (tmp_path / "fault_flight+baro_step.incomplete.csv").read_text().splitlines()
        stopped_at = float(lines[0].split("after t = ")[1].split(" s")[0])
        assert len(rows) >= 2 and float(rows[-1].split(",")[0]) == stopped_at < STOP
    assert after == 0.0 or "results so far written" in lines[0]
