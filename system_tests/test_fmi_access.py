"""Batched fmi2Get*/fmi2Set* through the adapter base: any list of value references, any
mix of parameters, inputs and outputs, and a clear error for a reference of another type.

The adapter reads inputs and outputs straight from the core and keeps one accessor per list
of value references it was asked for; these tests pin that the fast path returns what the
per-variable getters and setters would."""

import pytest

from altfusion.cosim.instances import CosimError, FmuInstance, fmu_info
from altfusion.sensors.gnss import GnssReceiver


@pytest.fixture
def gnss(fmus):
    info = fmu_info(fmus["GnssReceiver"])
    instance = FmuInstance("gnss", info)
    instance.initialize({"seed": 3}, 0.1, 0.0, 10.0)
    yield instance, {name: var.value_reference for name, var in info.variables.items()}
    instance.free()


def stepped_core(params: GnssReceiver.Params, inputs: dict[str, float], steps: int):
    """The core object behind the FMU, stepped like it (0.1 s steps from 0)."""
    core = GnssReceiver(params, step_size=0.1, inputs=inputs)
    for k in range(steps):
        core.do_step(k / 10, 0.1)
    return core


def step(instance: FmuInstance, steps: int) -> None:
    for k in range(steps):
        instance.do_step(k / 10, 0.1)


def test_a_batch_of_parameters_inputs_and_outputs_reads_the_core_values(gnss):
    instance, refs = gnss
    instance.set("Real", [refs["h"], refs["vz"]], [250.0, -1.5])
    instance.exit_initialization()
    step(instance, 12)                                    # one fix, at 1 s
    core = stepped_core(GnssReceiver.Params(seed=3), {"h": 250.0, "vz": -1.5}, 12)
    names = ["gps_h", "step_size", "h", "gps_vz", "sample_period", "gps_time"]
    assert instance.get("Real", [refs[n] for n in names]) == [
        core.gps_h, 0.1, 250.0, core.gps_vz, core.params.sample_period, core.gps_time]
    assert instance.get("Integer", [refs["gps_count"], refs["seed"], refs["gps_nsat"]]) \
        == [1, 3, core.gps_nsat]
    assert instance.get("Boolean", [refs["gps_fix"]]) == [core.gps_fix]


def test_setting_inputs_and_a_parameter_together_reaches_the_core(gnss):
    instance, refs = gnss
    instance.set("Real", [refs["h"], refs["user_range_error"], refs["vz"]], [100.0, 7.0, 2.0])
    assert instance.get("Real", [refs["vz"], refs["user_range_error"], refs["h"]]) \
        == [2.0, 7.0, 100.0]
    instance.exit_initialization()
    step(instance, 12)
    core = stepped_core(GnssReceiver.Params(seed=3, user_range_error=7.0),
                        {"h": 100.0, "vz": 2.0}, 12)
    assert core.gps_count == 1
    assert instance.get("Real", [refs["gps_h"], refs["gps_vz"]]) == [core.gps_h, core.gps_vz]


def test_a_reference_of_another_type_is_an_error_and_later_calls_still_work(gnss):
    instance, refs = gnss
    with pytest.raises(CosimError, match="getReal failed: KeyError"):
        instance.get("Real", [refs["gps_h"], refs["gps_count"]])
    with pytest.raises(CosimError, match="setInteger failed: KeyError"):
        instance.set("Integer", [refs["h"]], [1])
    instance.exit_initialization()
    core = stepped_core(GnssReceiver.Params(seed=3), {}, 0)
    assert instance.get("Real", [refs["gps_h"], refs["gps_time"]]) == [core.gps_h,
                                                                      core.gps_time]
