"""OMSimulator (OpenModelica's FMI/SSP host, v3) as our users run it: its Python API in a
process of its own (``fixtures/omsimulator/run_api.py``, on this interpreter, which has numpy
and lxml) and its command line with README's C-host environment. Each run gets a folder of
its own (OMSimulator's temporary files, ``TMPDIR``, the result CSV) and is timed.

The ``omsimulator`` fixture (``conftest.py``) unpacks the prebuilt archive once per session;
a test then runs a model in one line::

    run = omsimulator.fmu(fmus["VerticalDynamics"], stop=10.0, step=0.01)
    run = omsimulator.ssp(ssp_files["yang2020"], stop=60.0, step=0.01)
    run = omsimulator.command_line(ssp_files["yang2020"], stop=60.0, step=0.01)

``fmu`` and ``lua`` (the command line running a Lua script, OMSimulator's scripting API) can
also set inputs after initialization and leave the model to OMSimulator's exit handlers
(``teardown="keep"``); each reports every call's outcome (:meth:`OMSRun.calls`) and goes on,
so the exit status is the host's teardown alone.
"""

import csv
import math
import os
import re
import subprocess
import sys
import tarfile
import time
from dataclasses import dataclass
from itertools import count
from pathlib import Path
from string import Template

import numpy as np
import pytest
from embedding import has_shared_libpython, preload_environment

DRIVER = Path(__file__).parent / "fixtures" / "omsimulator" / "run_api.py"
LUA_SCRIPT = Path(__file__).parent / "fixtures" / "omsimulator" / "run_fmu.lua"
PACKAGE = Path("oms-install") / "lib" / "x86_64-linux-gnu"
"""Where the unpacked archive keeps the ``OMSimulator`` Python package (and its library)."""
EXECUTABLE = Path("oms-install") / "bin" / "OMSimulator"
CALL = re.compile(r"^OMS (.+?) (ok|ends|failed: .*)$", re.MULTILINE)
"""A line the scripts print per call: ``OMS <call> ok`` or ``OMS <call> failed: <reason>``."""
TIMEOUT = 900.0
"""Seconds any one run may take (a 60 s system at 0.01 s takes far less)."""


@dataclass(frozen=True)
class OMSRun:
    """One OMSimulator process: its exit status, output, result CSV and wall time."""
    returncode: int
    stdout: str
    stderr: str
    result: Path
    seconds: float

    def calls(self) -> dict[str, str]:
        """What the Python API or Lua script reported per call: ``{"simulate": "ok", ...}``
        or ``"failed: <reason>"``."""
        return dict(CALL.findall(self.stdout))

    def table(self) -> dict[str, np.ndarray]:
        """The result CSV by column (``time``, ``<system>.<component>.<variable>``)."""
        with self.result.open(newline="") as handle:
            rows = list(csv.reader(handle, skipinitialspace=True))
        values = np.array(rows[1:], dtype=float)
        return {name: values[:, i] for i, name in enumerate(rows[0])}

    def describe(self) -> str:
        """Exit status and the ends of both outputs, for an assertion's message."""
        return (f"exit {self.returncode} after {self.seconds:.1f} s\nstdout: "
                f"{self.stdout[-3000:]}\nstderr: {self.stderr[-3000:]}")


class OMSimulator:
    """The unpacked OMSimulator in ``install``; runs write below ``work``."""

    def __init__(self, install: Path, work: Path) -> None:
        self.install = install
        self.work = work
        self._runs = count(1)

    def _folder(self, name: str) -> Path:
        folder = self.work / f"{next(self._runs):03d}_{name}"
        (folder / "tmp").mkdir(parents=True)
        return folder

    def _run(self, command: list[str], environment: dict[str, str], folder: Path) -> OMSRun:
        result = folder / "result.csv"
        started = time.perf_counter()
        done = subprocess.run(command, env={**environment, "TMPDIR": str(folder / "tmp")},
                              cwd=folder, capture_output=True, text=True, timeout=TIMEOUT,
                              check=False)
        return OMSRun(done.returncode, done.stdout, done.stderr, result,
                      time.perf_counter() - started)

    def _api(self, option: str, model: Path, stop: float, step: float | None,
             teardown: str, inputs: dict[str, float]) -> OMSRun:
        folder = self._folder(model.stem)
        command = [sys.executable, str(DRIVER), option, str(model), "--stop", repr(stop),
                   "--result", str(folder / "result.csv"), "--teardown", teardown,
                   *(f"--input={name}={value!r}" for name, value in inputs.items())]
        if step is not None:
            command += ["--step", repr(step)]
        environment = {**os.environ, "PYTHONPATH": str(self.install / PACKAGE)}
        return self._run(command, environment, folder)

    def fmu(self, fmu: Path, stop: float, step: float | None = None,
            teardown: str = "delete", inputs: dict[str, float] | None = None) -> OMSRun:
        """``fmu`` alone through the Python API for ``stop`` s at communication step ``step``
        (None: the host's default); ``teardown`` "delete" (terminate and delete the model) or
        "keep" (leave it to OMSimulator's exit handlers); ``inputs`` (Real) set after
        initialization."""
        return self._api("--fmu", fmu, stop, step, teardown, inputs or {})

    def ssp(self, ssp: Path, stop: float, step: float | None = None,
            teardown: str = "delete") -> OMSRun:
        """The SSP archive ``ssp`` through the Python API, as :meth:`fmu`."""
        return self._api("--ssp", ssp, stop, step, teardown, {})

    def lua(self, fmu: Path, stop: float, step: float | None = None,
            teardown: str = "delete", inputs: dict[str, float] | None = None) -> OMSRun:
        """``fmu`` alone through the command line running a Lua script (``run_fmu.lua``),
        as :meth:`fmu`."""
        folder = self._folder(fmu.stem)
        script = folder / "run.lua"
        script.write_text(Template(LUA_SCRIPT.read_text()).substitute(
            tmp=folder / "tmp", fmu=fmu, result=folder / "result.csv", stop=repr(stop),
            step=repr(step or 0.0), teardown=teardown,
            inputs=", ".join(f'["{name}"] = {lua_number(value)}'
                             for name, value in (inputs or {}).items())))
        return self._command([str(script)], folder)

    def command_line(self, model: Path, stop: float, step: float | None = None,
                     *options: str) -> OMSRun:
        """``OMSimulator MODEL --stopTime=stop [--stepSize=step] OPTIONS`` (an FMU or an SSP
        archive) with README's C-host environment and a temporary folder of its own."""
        folder = self._folder(model.stem)
        return self._command([str(model), f"--stopTime={stop!r}", f"--tempDir={folder / 'tmp'}",
                              f"--resultFile={folder / 'result.csv'}",
                              *([f"--stepSize={step!r}"] if step is not None else []),
                              *options], folder)

    def _command(self, arguments: list[str], folder: Path) -> OMSRun:
        if not has_shared_libpython():
            pytest.skip("this Python has no shared libpython to preload for OMSimulator's "
                        "command line")
        return self._run([str(self.install / EXECUTABLE), *arguments], preload_environment(),
                         folder)


def lua_number(value: float) -> str:
    """``value`` as a Lua expression (Lua has no literal for NaN or infinity)."""
    if math.isnan(value):
        return "(0/0)"
    if math.isinf(value):
        return "math.huge" if value > 0 else "-math.huge"
    return repr(float(value))


def unpack(archives: list[Path], folder: Path) -> OMSimulator:
    """Unpack the prebuilt archives into ``folder``; the OMSimulator found there."""
    for archive in archives:
        with tarfile.open(archive) as tar:
            # the "data" filter (no absolute paths, no links out) where this Python has it
            tar.extractall(folder, **({"filter": "data"} if hasattr(tarfile, "data_filter")
                                      else {}))
    if not (folder / EXECUTABLE).is_file() or not (folder / PACKAGE / "OMSimulator").is_dir():
        pytest.fail(f"{', '.join(a.name for a in archives)} holds no {EXECUTABLE} and "
                    f"{PACKAGE}/OMSimulator")
    return OMSimulator(folder, folder / "runs")
