"""Nothing left in the temporary folder: every ``altfusion`` command removes the SSP archives
it unpacked and the FMUs it extracted when it exits, in its Monte Carlo worker processes too
(which leave by ``os._exit``, skipping :mod:`atexit`), after success and after a user's
mistake. Before, each run of the yang2020 system left eight extracted FMUs (about 1 MiB each)
in ``/tmp`` and each worker its own: a day of test suites had filled 19 GB."""

import os
import subprocess
import sys

import pytest


def altfusion(args: list[str], tmp_path) -> tuple[subprocess.CompletedProcess, list[str]]:
    """Run ``altfusion ARGS`` with its own empty temporary folder; what is left in it after."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    completed = subprocess.run([sys.executable, "-m", "altfusion.cli", *args],
                               env={**os.environ, "TMPDIR": str(scratch)},
                               capture_output=True, text=True, timeout=600)
    return completed, sorted(p.name for p in scratch.iterdir())


@pytest.mark.parametrize("command", [
    ["run", "{yang2020}", "--stop", "5", "--out", "{out}"],
    ["mc", "{yang2020}", "-n", "3", "--stop", "2", "--workers", "2", "--quiet", "--out",
     "{out}"],
    ["run", "{fault_flight}", "--fault", "baro_step", "--stop", "2", "--out", "{out}"],
    ["run", "{yang2020}", "--stop", "5", "--set", "plant.mass=-1", "--out", "{out}"],
], ids=["run", "mc-two-workers", "fault", "refused-parameter"])
def test_no_temporary_folder_outlives_a_command(ssp_files, tmp_path, command):
    args = [a.format(**ssp_files, out=tmp_path / "out") for a in command]
    completed, left = altfusion(args, tmp_path)
    assert completed.returncode == (2 if "plant.mass=-1" in args else 0), completed.stderr
    assert left == []
