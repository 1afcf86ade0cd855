"""The native shim's direct access (``altfusion/fmi/shim/fmi2_shim.c``, "direct access"): while
an instance steps, fmi2Get of inputs, outputs and parameters (strings included), fmi2Set of
inputs and fmi2DoStep reach the slave without pythonfmu's bridge, with the values and statuses
pythonfmu's path gives; anything else (Initialization Mode, an output set by mistake, after
fmi2Terminate) still goes through pythonfmu, and a reset instance is served with its new slave
object.

Which path served a call is seen from the slave class's accessors, which pythonfmu calls and
the shim does not: they are wrapped to count their calls."""

import ctypes
import math
import sys

import pytest
from pythonfmu.enums import Fmi2Status

from altfusion.cosim.instances import CosimError, FmuInstance, fmu_info
from altfusion.sensors.gnss import GnssReceiver

ACCESSORS = ("get_real", "get_integer", "get_boolean", "get_string", "set_real", "set_integer",
             "set_boolean")
FMI2_OK, FMI2_DISCARD, FMI2_FATAL = 0, 2, 4
FMI2_LAST_SUCCESSFUL_TIME = 2


def slave_class():
    """The GnssReceiver FMU's slave class, as pythonfmu imported it (its module stays)."""
    return next(module.GnssReceiver for name, module in list(sys.modules.items())
                if name.startswith("gnss_receiver_slave_"))


@pytest.fixture
def gnss(fmus, monkeypatch):
    """A GnssReceiver instance in Initialization Mode (seed 3, 0.1 s steps), its value
    references, the accessor calls pythonfmu made (a list, cleared by the test at will) and
    the do_step outcomes the test asks for ({time: False or an exception})."""
    info = fmu_info(fmus["GnssReceiver"])
    FmuInstance("probe", info).free()                 # imports the slave class
    cls = slave_class()
    calls: list[str] = []
    outcomes: dict[float, object] = {}
    def counting(method: str):
        original = getattr(cls, method)

        def counted(self, *args):
            calls.append(method)
            return original(self, *args)
        return counted

    for method in ACCESSORS:
        monkeypatch.setattr(cls, method, counting(method))

    def do_step(self, current_time, step_size, _original=cls.do_step):
        outcome = outcomes.get(current_time, True)
        if isinstance(outcome, Exception):
            raise outcome
        if outcome is False:
            self._log(Fmi2Status.warning, "refused 100% of this step")
            return False
        return _original(self, current_time, step_size)
    monkeypatch.setattr(cls, "do_step", do_step)
    instance = FmuInstance("gnss", info)
    instance.initialize({"seed": 3}, 0.1, 0.0, 10.0)
    yield instance, {n: v.value_reference for n, v in info.variables.items()}, calls, outcomes
    instance.free()


def stepped_core(inputs: dict[str, float], steps: int) -> GnssReceiver:
    core = GnssReceiver(GnssReceiver.Params(seed=3), step_size=0.1, inputs=inputs)
    for k in range(steps):
        core.do_step(k / 10, 0.1)
    return core


def raw(instance: FmuInstance, name: str, restype, *argtypes):
    """The FMI function ``name`` of the instance's library without fmpy's status check."""
    function = getattr(ctypes.CDLL(instance.fmu.dll._name), name)
    function.restype, function.argtypes = restype, [ctypes.c_void_p, *argtypes]
    return lambda *args: function(instance.fmu.component, *args)


def test_while_stepping_inputs_and_outputs_bypass_pythonfmu_with_its_values(gnss):
    instance, refs, calls, _ = gnss
    calls.clear()
    instance.set("Real", [refs["h"], refs["vz"]], [250.0, -1.5])
    assert calls == ["set_real"]                       # Initialization Mode: pythonfmu's path
    instance.exit_initialization()
    calls.clear()
    for k in range(12):                                # one fix, at 1 s
        instance.do_step(k / 10, 0.1)
    core = stepped_core({"h": 250.0, "vz": -1.5}, 12)
    assert instance.get("Real", [refs["gps_h"], refs["h"], refs["gps_vz"], refs["gps_time"]]) \
        == [core.gps_h, 250.0, core.gps_vz, core.gps_time]
    assert instance.get("Integer", [refs["gps_count"], refs["gps_nsat"]]) \
        == [1, core.gps_nsat]
    assert instance.get("Boolean", [refs["gps_fix"]]) == [core.gps_fix]
    instance.set("Real", [refs["vz"], refs["h"]], [2.0, 100.0])
    assert instance.get("Real", [refs["h"], refs["vz"]]) == [100.0, 2.0]
    assert calls == []                                 # all of it direct

    assert instance.get("Real", [refs["gps_h"], refs["step_size"], refs["sample_period"]]) \
        == [core.gps_h, 0.1, core.params.sample_period]
    assert instance.get("Integer", [refs["seed"], refs["gps_count"]]) == [3, 1]
    assert instance.fmu.getString([refs["dop_mode"], refs["outage_windows"]]) \
        == [core.params.dop_mode.encode(), core.params.outage_windows.encode()]
    assert calls == []                                 # parameters too, strings too
    with pytest.raises(CosimError, match="setReal failed"):
        instance.set("Real", [refs["gps_h"]], [1.0])   # an output: pythonfmu refuses it
    assert calls[-1] == "set_real"
    calls.clear()
    instance.terminate()
    assert instance.get("Real", [refs["h"]]) == [100.0]
    assert calls == ["get_real"]                       # after fmi2Terminate: pythonfmu


def test_a_refused_or_failed_step_keeps_its_status_message_and_last_successful_time(gnss):
    instance, _, _, outcomes = gnss
    last_successful = raw(instance, "fmi2GetRealStatus", ctypes.c_int, ctypes.c_int,
                          ctypes.POINTER(ctypes.c_double))
    step = raw(instance, "fmi2DoStep", ctypes.c_int, ctypes.c_double, ctypes.c_double,
               ctypes.c_int)

    def do_step(time: float, size: float) -> int:
        return step(time, size, 1)
    time = ctypes.c_double()
    assert last_successful(FMI2_LAST_SUCCESSFUL_TIME, ctypes.byref(time)) == FMI2_OK
    assert math.isnan(time.value)                      # pythonfmu's before any step
    instance.exit_initialization()
    outcomes.update({0.2: False, 0.3: RuntimeError("the slave broke")})
    assert do_step(0.0, 0.1) == do_step(0.1, 0.1) == FMI2_OK
    last_successful(FMI2_LAST_SUCCESSFUL_TIME, ctypes.byref(time))
    assert time.value == 0.1 + 0.1
    assert do_step(0.2, 0.1) == FMI2_DISCARD           # do_step returned False
    last_successful(FMI2_LAST_SUCCESSFUL_TIME, ctypes.byref(time))
    assert time.value == 0.2
    instance.errors()
    assert instance.warnings == ["refused 100% of this step"]   # '%' as logged
    assert do_step(0.3, 0.1) == FMI2_FATAL             # an exception escaped, as pythonfmu
    assert any("the slave broke" in message for message in instance.errors())


def test_a_reset_instance_is_served_with_its_new_slave(gnss):
    instance, refs, calls, _ = gnss
    instance.set("Real", [refs["h"]], [250.0])
    instance.exit_initialization()
    for k in range(12):
        instance.do_step(k / 10, 0.1)
    instance.reset()                                   # pythonfmu makes a new slave object
    instance.initialize({"seed": 3}, 0.1, 0.0, 10.0)
    instance.set("Real", [refs["h"], refs["vz"]], [80.0, 0.5])
    instance.exit_initialization()
    calls.clear()
    for k in range(12):
        instance.do_step(k / 10, 0.1)
    core = stepped_core({"h": 80.0, "vz": 0.5}, 12)
    assert instance.get("Real", [refs["gps_h"], refs["h"]]) == [core.gps_h, 80.0]
    assert calls == []
