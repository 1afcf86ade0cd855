"""Our FMUs in OMSimulator (OpenModelica's FMI/SSP host, prebuilt in
``../shared/tools/omsimulator``; the ``omsimulator`` fixture unpacks it, ``omsimulator.py``
runs it), through its Python API and its command line, as docs/interop.md tells a user to.

Teardown in any order: OMSimulator tears down a model its user did not delete in its own exit
handlers, after a Python host has finalized its interpreter (Python API) or after every exit
handler our FMUs registered (command line). The process exits 0 whether or not the model was
deleted, after a run that succeeded and after one that failed (before the shim's fix: exit
139, PyGILState_Ensure on a finalized interpreter from pythonfmu's Terminate). The failure is
an input the FMU refuses (thrust = NaN: doStep returns fmi2Error at t = 0); the run that
succeeds steps 2^-7 s, a step every FMU accepts.

Each run is one OMSimulator process of about 1.5 s (measured: 1.3-2.1 s on the shared
2-core machine, 10 s of VerticalDynamics at 2^-7 s); its wall time is recorded as the test's
``omsimulator_seconds`` property.
"""

import math
import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from altfusion.cli import main
from altfusion.cosim import read_ssp
from altfusion.cosim.runner import simulate
from altfusion.systems import SYSTEMS

STOP = 10.0
STEP = 2.0**-7
"""A communication step exactly representable in binary: the host reaches the stop time in
whole steps."""
REFUSED = {"thrust": float("nan")}
REFUSAL = "input thrust = nan is not finite"
HOSTS = {"python api": "fmu", "command line": "lua"}
"""How each host interface runs one FMU: OMSimulator's Python API, or its command line on a
Lua script (OMSimulator's scripting API, which can set an input and skip the delete)."""


@pytest.mark.parametrize("teardown", ["delete", "keep"])
@pytest.mark.parametrize("outcome", ["succeeds", "fails"])
@pytest.mark.parametrize("host", HOSTS)
def test_omsimulator_exits_0_whether_or_not_the_model_was_deleted(
        omsimulator, fmus, record_property, host, outcome, teardown):
    run = getattr(omsimulator, HOSTS[host])(
        fmus["VerticalDynamics"], STOP, STEP, teardown,
        inputs=REFUSED if outcome == "fails" else None)
    record_property("omsimulator_seconds", round(run.seconds, 2))
    assert run.returncode == 0, run.describe()
    calls = run.calls()
    assert calls["script"] == "ends", run.describe()
    assert ("terminate" in calls and "delete" in calls) == (teardown == "delete"), calls
    if teardown == "delete":
        assert calls["terminate"] == calls["delete"] == "ok", calls
    if outcome == "succeeds":
        assert calls["simulate"] == "ok", run.describe()
        assert run.table()["time"][-1] == STOP
    else:
        assert calls["simulate"].startswith("failed"), run.describe()
        assert REFUSAL in run.stdout + run.stderr, run.describe()


def test_the_command_line_runs_an_fmu_and_exits_0(omsimulator, fmus, record_property):
    """``OMSimulator VerticalDynamics.fmu --stopTime=10 --stepSize=2^-7``: OMSimulator runs
    the FMU alone, writes every step and exits 0."""
    run = omsimulator.command_line(fmus["VerticalDynamics"], STOP, STEP)
    record_property("omsimulator_seconds", round(run.seconds, 2))
    assert run.returncode == 0, run.describe()
    time = run.table()["time"]
    assert time[-1] == STOP and len(set(time)) == round(STOP / STEP) + 1


# ------------------------------------------------------------------ any step, every model
MODELS = Path(__file__).resolve().parents[1] / "models"
FMU_NAMES = sorted(path.stem for path in MODELS.glob("*.fmu"))
"""Every built FMU (the ``fmus`` fixture fails the run if one is missing or stale)."""
SSP_NAMES = sorted(name for name in SYSTEMS if not name.startswith("replay_"))
"""Every catalog system but the log replays (their logs are not a host's business)."""
FMU_STOP, SSP_STOP, SSP_STEP = 10.0, 60.0, 0.01
RMS_FACTOR = 1.5
"""How far the estimate's RMS in OMSimulator may be from our runner's on the same seeds:
OMSimulator hands every input its source's value from the start of a 0.01 s step, our
runner a sensor's the plant's at the end of it (one step of delay, 0.1 m at 10 m/s), far below
the estimators' 1 m RMS."""


def expected_count(md, stop: float) -> int | None:
    """Samples a sensor FMU with its default schedule delivers over (0, stop], or None if it
    has no schedule."""
    start = {v.name: v.start for v in md.modelVariables}
    if "sample_period" not in start:
        return None
    period, offset, latency = (Fraction(start[name]) for name in
                               ("sample_period", "sample_offset", "latency"))
    first = offset if offset > 0 else period
    return max(0, math.floor((Fraction(repr(stop)) - latency - first) / period) + 1)


@pytest.mark.parametrize("step", [None, 0.01], ids=["default step", "0.01 s"])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_every_fmu_alone_ends_ok_at_the_hosts_default_step_and_at_0_01_s(
        omsimulator, fmus, record_property, name, step):
    """10 s of each FMU alone, as OMSimulator steps it: its default step (1e-3 s) or 0.01 s,
    each followed by a remainder step of about 1e-13 s before the stop time. A sensor
    delivers the samples of its default schedule, no more and no fewer."""
    run = omsimulator.fmu(fmus[name], FMU_STOP, step)
    record_property("omsimulator_seconds", round(run.seconds, 2))
    assert run.returncode == 0, run.describe()
    assert run.calls()["simulate"] == "ok", run.describe()
    table = run.table()
    assert table["time"][-1] == FMU_STOP
    expected = expected_count(read_model_description(str(fmus[name])), FMU_STOP)
    counts = [column for column in table if column.endswith("_count")]
    if expected is not None:
        assert counts and all(table[c][-1] == expected for c in counts), \
            {c: table[c][-1] for c in counts}


@pytest.fixture(scope="module")
def ssp_run(omsimulator, ssp_files):
    """The run of a catalog system through OMSimulator's Python API (SSP_STOP, SSP_STEP),
    made once per module: the tests of one file share an xdist worker."""
    runs = {}

    def run(system: str):
        if system not in runs:
            runs[system] = omsimulator.ssp(ssp_files[system], SSP_STOP, SSP_STEP)
        return runs[system]
    return run


@pytest.mark.parametrize("system", SSP_NAMES)
def test_every_catalog_ssp_runs_60_s_at_one_0_01_s_step_for_every_component(
        ssp_run, ssp_files, record_property, capsys, system):
    """Through OMSimulator's Python API, as it is: every component stepped at 0.01 s, each
    FMU ticking on the step_size the SSP binds; altfusion timing finds every sensor stream on
    its schedule in OMSimulator's result."""
    run = ssp_run(system)
    record_property("omsimulator_seconds", round(run.seconds, 2))
    assert run.returncode == 0, run.describe()
    assert run.calls()["simulate"] == "ok", run.describe()
    assert run.table()["time"][-1] == SSP_STOP
    if system != "plant_yang2020":                          # the one without a sensor
        capsys.readouterr()
        status = main(["timing", str(run.result), "--system", str(ssp_files[system])])
        assert status == 0, capsys.readouterr().out[-4000:]


def test_yang2020_gives_our_runners_answer_in_omsimulator(ssp_run, ssp_files):
    """The default system with unmodified FMUs, one 0.01 s step for every component: the
    estimate's RMS within RMS_FACTOR of our runner's over the same 60 s and seeds."""
    run = ssp_run("yang2020")
    assert run.returncode == 0, run.describe()
    table = run.table()
    loaded = read_ssp(ssp_files["yang2020"])
    metric = next(m for m in loaded.spec.metrics if m.estimate == "estimator.h_est")
    ours = simulate(loaded.spec, loaded.fmu_paths, stop_time=SSP_STOP)
    ours_rms = np.sqrt(np.mean((ours[metric.estimate] - ours[metric.truth]) ** 2))
    theirs = table[f"yang2020.{metric.estimate}"] - table[f"yang2020.{metric.truth}"]
    theirs_rms = np.sqrt(np.mean(theirs ** 2))
    assert ours_rms / RMS_FACTOR <= theirs_rms <= ours_rms * RMS_FACTOR, (theirs_rms, ours_rms)


def test_the_command_line_runs_the_default_system_as_it_is_and_exits_0(
        omsimulator, ssp_files, record_property):
    """``OMSimulator models/yang2020.ssp --stopTime=60 --stepSize=0.01``: the system type and
    the master's step come from the SSP's own OMSimulator annotation; no import error."""
    run = omsimulator.command_line(ssp_files["yang2020"], SSP_STOP, SSP_STEP)
    record_property("omsimulator_seconds", round(run.seconds, 2))
    assert run.returncode == 0, run.describe()
    assert not re.search(r"^error:", run.stdout + run.stderr, re.MULTILINE), run.describe()
    table = run.table()
    assert table["time"][-1] == SSP_STOP
    assert table["yang2020.yang2020.gnss.gps_count"][-1] == SSP_STOP / 0.1
