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

import pytest

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
