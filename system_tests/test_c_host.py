"""A C host that uses only standard FMI 2.0 calls (``fixtures/c_host/fmi2_host.c``, compiled
here with the system compiler; libpython preloaded as README says) runs VerticalDynamics and
YangFusionKF: it exits with status 0 on every ``file:`` resource URI form (the FMUs extracted
to a folder whose name needs a percent-escape), and every failure reaches its logger while
``loggingOn`` is off: a refused state (fmi2DeSerializeFMUstate returns fmi2Error), a bad
parameter (fmi2ExitInitializationMode returns fmi2Error), a resource location that is not a
local file URI (fmi2Instantiate returns NULL). Teardown in any order: instances freed by the
host's exit handler, calls after the host finalized its own interpreter."""

import math
import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path
from urllib.parse import quote

import pytest
from embedding import has_shared_libpython, preload_environment
from fmpy import read_model_description

SOURCE = Path(__file__).parent / "fixtures" / "c_host" / "fmi2_host.c"
STEPS = 300
STEP = 0.01
CLIMB = 0.2 * 9.80665
"""Net acceleration of the climb the host flies (thrust 1.2 g on VerticalDynamics' 1.5 kg)."""
FORMS = {"file:/p": "file:", "file:///p": "file://", "file://localhost/p": "file://localhost"}
FMI2_ERROR = 3

VARIABLES = {
    "VerticalDynamics": {"THRUST": "thrust", "H": "h", "VZ": "vz", "AZ": "az"},
    "YangFusionKF": {
        "BARO_H": "baro_h", "BARO_TIME": "baro_time", "BARO_COUNT": "baro_count",
        "GPS_H": "gps_h", "GPS_VZ": "gps_vz", "GPS_TIME": "gps_time", "GPS_COUNT": "gps_count",
        "ACC_Z": "acc_z", "ACC_TIME": "acc_time", "ACC_COUNT": "acc_count",
        "H_EST": "h_est", "H_STD": "h_std", "H_VALID": "h_valid", "R_BARO": "R_baro"},
}


@pytest.fixture(scope="module")
def host(fmus, tmp_path_factory) -> dict:
    """The compiled host, the FMUs extracted to a folder named with a space, their GUIDs and
    the environment the host runs in."""
    compiler = os.environ.get("CC", "cc")
    if shutil.which(compiler) is None:
        pytest.skip(f"no C compiler ('{compiler}' is not on PATH)")
    if not has_shared_libpython():
        pytest.skip("this Python has no shared libpython for a C host to preload")
    work = tmp_path_factory.mktemp("c_host")
    folders, guids, defines = {}, {}, []
    for model, names in VARIABLES.items():
        description = read_model_description(str(fmus[model]))
        references = {v.name: v.valueReference for v in description.modelVariables}
        defines += [f"-DVR_{macro}={references[name]}" for macro, name in names.items()]
        folders[model] = work / "fmus dir" / model
        with zipfile.ZipFile(fmus[model]) as archive:
            archive.extractall(folders[model])
        guids[model] = description.guid
    binary = work / "fmi2_host"
    subprocess.run([compiler, "-O1", "-o", str(binary), str(SOURCE), *defines, "-ldl", "-lm"],
                   check=True, capture_output=True, text=True)
    return {"binary": binary, "folders": folders, "guids": guids, "env": preload_environment()}


def uri(prefix: str, folder: Path) -> str:
    return prefix + quote(str(folder / "resources"))


def run(host: dict, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(host["binary"]), *args], env=host["env"], capture_output=True,
                          text=True, timeout=120)


def both(host: dict, prefix: str) -> list[str]:
    """The arguments naming VerticalDynamics and YangFusionKF with ``prefix`` URIs."""
    args = []
    for model in VARIABLES:
        folder = host["folders"][model]
        args += [str(folder), host["guids"][model], uri(prefix, folder)]
    return [*args, str(STEPS)]


def errors_logged(stdout: str) -> list[str]:
    return re.findall(rf"^LOG [{FMI2_ERROR}4] \S+: (.*)$", stdout, flags=re.MULTILINE)


def last_report(stdout: str) -> dict[str, float]:
    line = [line for line in stdout.splitlines() if line.startswith("h ")][-1]
    fields = line.split()
    return {key: float(value) for key, value in zip(fields[::2], fields[1::2], strict=True)}


@pytest.mark.parametrize("form", FORMS)
def test_a_c_host_runs_two_fmus_and_exits_with_status_0(host, form):
    """3 s of a 0.2 g climb from rest: the altitude stays below the drag-free 0.5 a t^2 and
    above 80 % of it (drag at <= 6 m/s is small), the estimate, fed the true altitude as its
    barometer and GPS, lies within 3 of its own standard deviations."""
    done = run(host, "run", *both(host, FORMS[form]))
    assert done.returncode == 0, (done.returncode, done.stdout[-2000:], done.stderr[-2000:])
    assert "worst step status 0" in done.stdout and done.stdout.rstrip().endswith("done")
    assert errors_logged(done.stdout) == []
    values = last_report(done.stdout)
    drag_free = 0.5 * CLIMB * (STEPS * STEP) ** 2
    assert 0.8 * drag_free < values["h"] < drag_free
    assert math.isfinite(values["h_std"]) and values["h_std"] > 0
    assert abs(values["h_est"] - values["h"]) < 3 * values["h_std"]
    assert values["h_valid"] == 1


def test_refused_states_return_fmi2error_with_the_reason_while_logging_is_off(host):
    done = run(host, "state", *both(host, "file://"))
    assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-2000:])
    out = done.stdout
    assert "status corrupt deserialize 3" in out and "corrupt state is null 1" in out
    assert "status foreign deserialize 3" in out and "foreign state is null 1" in out
    errors = errors_logged(out)
    assert any("refused the state" in e and "checksum mismatch" in e for e in errors), errors
    assert any("foreign state: written by model 'VerticalDynamics'" in e for e in errors), errors
    # the instance stays usable: a good state restores and it steps on without error
    assert "status good deserialize 0" in out and "status good set 0" in out
    assert "worst status after refusals 0" in out


def test_a_bad_parameter_fails_initialization_with_the_reason_while_logging_is_off(host):
    folder = host["folders"]["YangFusionKF"]
    done = run(host, "badparam", str(folder), host["guids"]["YangFusionKF"],
               uri("file://", folder))
    assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-2000:])
    assert "status exit 3" in done.stdout and "status step 3" in done.stdout
    errors = errors_logged(done.stdout)
    assert errors and "parameter 'R_baro' = -1.0" in errors[0], done.stdout


BAD_LOCATIONS = {
    "another host": (lambda path: f"file://otherhost{path}", "names no local folder (expected "
                     "file:/path, file:///path or file://localhost/path)"),
    "relative": (lambda path: "file:fmus%20dir/resources", "is not an absolute file URI "
                 "(expected file:/path, file:///path or file://localhost/path)"),
    "bad escape": (lambda path: f"file://{path}%2", "has an invalid percent-escape"),
}


@pytest.mark.parametrize("kind", BAD_LOCATIONS)
def test_a_resource_location_that_is_no_local_file_uri_is_refused_naming_it(host, kind):
    folder = host["folders"]["YangFusionKF"]
    make, reason = BAD_LOCATIONS[kind]
    location = make(quote(str(folder / "resources")))
    done = run(host, "badparam", str(folder), host["guids"]["YangFusionKF"], location)
    assert "instantiate kf failed" in done.stdout
    assert errors_logged(done.stdout) == [
        f"fmi2Instantiate: resource location '{location}' {reason}"]


def test_instances_freed_by_the_hosts_exit_handler_see_python_alive_and_exit_0(host):
    """The host tears its instances down in an exit handler registered before the FMUs loaded,
    so it runs after every handler theirs registered (OMSimulator does this): the shim keeps
    the interpreter until then, so fmi2Terminate still runs the Python side (fmi2OK) and the
    process exits 0 (before: the shim's handler finalized Python first, exit 139)."""
    done = run(host, "atexit", *both(host, "file://"))
    assert done.returncode == 0, (done.returncode, done.stdout[-2000:], done.stderr[-2000:])
    lines = done.stdout.splitlines()
    assert lines[-3:] == ["main returns", "status terminate at exit 0 0", "freed at exit"], lines
    assert errors_logged(done.stdout) == []


def test_calls_after_the_host_finalized_python_return_a_status_without_touching_it(host):
    """An embedding host with its own interpreter finalizes it, then calls the FMUs: every call
    that needs Python returns fmi2Error saying why, fmi2Terminate fmi2OK, fmi2FreeInstance
    returns, and the process exits 0 (before: PyGILState_Ensure on the finalized interpreter,
    exit 139)."""
    done = run(host, "finalized", *both(host, "file://"))
    assert done.returncode == 0, (done.returncode, done.stdout[-2000:], done.stderr[-2000:])
    out = done.stdout
    assert "worst step status 0" in out and "status finalize 0" in out
    assert f"status get after finalization {FMI2_ERROR}" in out
    assert f"status step after finalization {FMI2_ERROR}" in out
    assert f"status get state after finalization {FMI2_ERROR}" in out
    assert "status terminate after finalization 0 0" in out and out.rstrip().endswith("done")
    errors = errors_logged(out)
    assert [e.split(":")[0] for e in errors] == ["fmi2GetReal", "fmi2DoStep", "fmi2GetFMUstate"]
    assert all("the Python interpreter of this process has been finalized" in e
               for e in errors), errors
