"""Our FMUs in one host process, as Jupyter users, test suites and GUI tools load them.

fmpy's ``simulate_fmu`` extracts an FMU to a temporary folder and deletes it afterwards; every
FMU must still run after any other, in any order, and two builds of one FMU from different
core versions must each run their own code side by side (``altfusion.fmi.bundle``, PythonFMU
issue #228). Each scenario runs in a fresh interpreter, as a user's would, and must exit 0.
"""

import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from pythonfmu.builder import FmuBuilder

import build_fmu
from altfusion.constants import ISA_T0
from altfusion.fmi.bundle import stage_core, stage_script

STOP = 1.0
"""Seconds simulated per FMU: enough for every FMU's first samples (the slowest sensor, 1 Hz
GNSS, delivers its first at t = 0)."""


def run_host(script: str) -> dict:
    """Run ``script`` in a fresh interpreter; returns the JSON it prints last."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(script)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, f"host exited {done.returncode}:\n{done.stderr[-3000:]}"
    return json.loads(done.stdout.strip().splitlines()[-1])


SIMULATE_ALL = """
    import json, numpy as np
    from fmpy import simulate_fmu
    outcome = []
    for path in {paths}:
        try:
            result = simulate_fmu(path, stop_time={stop}, output_interval=0.01)
            values = np.array([list(row)[1:] for row in result], dtype=float)
            outcome.append([path, len(result), bool(np.isfinite(values).all()), ""])
        except Exception as error:
            outcome.append([path, 0, False, str(error)])
    print(json.dumps(outcome))
"""


def test_every_fmu_runs_after_every_other_in_one_process(fmus):
    """All FMUs one after another, then again in reverse order (each FMU after every other
    has run and its folder was deleted), in one process: every run completes with finite
    outputs at every output point."""
    order = [str(p) for p in sorted(fmus.values())]
    paths = json.dumps(order + order[::-1])
    outcome = run_host(SIMULATE_ALL.format(paths=paths, stop=STOP))
    rows = round(STOP / 0.01) + 1
    assert [(Path(p).name, n, finite, error) for p, n, finite, error in outcome] == [
        (Path(p).name, rows, True, "") for p in json.loads(paths)]


def build_with_core(script: Path, core_dir: Path, version: str, out: Path) -> Path:
    """The FMU of ``script`` built from the core package at ``core_dir`` as ``version``."""
    stage = out / "stage"
    core = stage_core(core_dir, [script], version, stage)
    staged = stage_script(script, core, stage)
    sys.path.insert(0, str(stage))
    try:
        return Path(FmuBuilder.build_FMU(staged, dest=out, project_files=[core]))
    finally:
        sys.path.remove(str(stage))


@pytest.fixture(scope="module")
def warmer_atmosphere(tmp_path_factory) -> Path:
    """Atmosphere built from a core whose ISA sea-level temperature is 10 K higher."""
    out = tmp_path_factory.mktemp("other_core")
    core = out / "src" / "altfusion"
    shutil.copytree(build_fmu.CORE, core, ignore=shutil.ignore_patterns("__pycache__"))
    constants = core / "constants.py"
    text = constants.read_text()
    assert "ISA_T0 = 288.15" in text
    constants.write_text(text.replace("ISA_T0 = 288.15", "ISA_T0 = 298.15"))
    return build_with_core(build_fmu.FMU_SRC / "atmosphere_slave.py", core,
                           "0.1.0+warmer000000", out)


SIDE_BY_SIDE = """
    import json, shutil
    from fmpy import extract, read_model_description, simulate_fmu
    from fmpy.fmi2 import FMU2Slave
    paths = {paths!r}
    temperatures = {{}}
    # Both loaded and stepped, interleaved, in one process
    slaves = []
    for path in paths:
        md = read_model_description(path)
        folder = extract(path)
        slave = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName=path)
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        vr = {{v.name: v.valueReference for v in md.modelVariables}}["T_air"]
        slaves.append((path, slave, vr, folder))
    for step in range(3):
        for path, slave, vr, folder in slaves:
            slave.doStep(currentCommunicationPoint=step * 0.01, communicationStepSize=0.01)
            temperatures[path] = slave.getReal([vr])[0]
    for path, slave, vr, folder in slaves:
        slave.terminate()
        slave.freeInstance()
        shutil.rmtree(folder, ignore_errors=True)
    # Then each again, from fresh folders, after the other's folder was deleted
    again = {{p: float(simulate_fmu(p, stop_time=0.1, output_interval=0.01)["T_air"][-1])
             for p in paths[::-1]}}
    print(json.dumps([temperatures, again]))
"""


def test_two_core_versions_run_side_by_side(fmus, warmer_atmosphere):
    """The built Atmosphere and one built from a core with ISA T0 + 10 K, in one process,
    each reports its own core's sea-level temperature (h = 0: T_air = T0 exactly)."""
    ours = str(fmus["Atmosphere"])
    paths = [ours, str(warmer_atmosphere)]
    stepped, again = run_host(SIDE_BY_SIDE.format(paths=paths))
    for temperatures in (stepped, again):
        assert temperatures[ours] == pytest.approx(ISA_T0, abs=1e-9)
        assert temperatures[str(warmer_atmosphere)] == pytest.approx(ISA_T0 + 10.0, abs=1e-9)
