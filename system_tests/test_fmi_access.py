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


def test_a_batch_of_parameters_inputs_and_outputs_reads_like_single_values(gnss):
    instance, refs = gnss
    instance.set("Real", [refs["h"], refs["vz"]], [250.0, -1.5])
    instance.exit_initialization()
    for k in range(12):                                   # one fix, at 1 s
        instance.do_step(k / 10, 0.1)
    names = ["gps_h", "step_size", "h", "gps_vz", "sample_period", "gps_time"]
    batch = instance.get("Real", [refs[n] for n in names])
    assert batch == [instance.get("Real", [refs[n]])[0] for n in names]
    assert batch[1:3] == [0.1, 250.0]
    counts = instance.get("Integer", [refs["gps_count"], refs["seed"], refs["gps_nsat"]])
    assert counts[:2] == [1, 3]
    assert instance.get("Boolean", [refs["gps_fix"]]) in ([True], [False])


def test_setting_inputs_and_a_parameter_together_reaches_the_core(gnss):
    instance, refs = gnss
    instance.set("Real", [refs["h"], refs["user_range_error"], refs["vz"]], [100.0, 7.0, 2.0])
    assert instance.get("Real", [refs["vz"], refs["user_range_error"], refs["h"]]) \
        == [2.0, 7.0, 100.0]
    instance.exit_initialization()
    expected = GnssReceiver(GnssReceiver.Params(seed=3, user_range_error=7.0),
                            step_size=0.1, inputs={"h": 100.0, "vz": 2.0})
    instance.do_step(0.0, 0.1)
    expected.do_step(0.0, 0.1)
    assert instance.get("Real", [refs["gps_h"], refs["gps_vz"]]) == [expected.gps_h,
                                                                    expected.gps_vz]


def test_a_reference_of_another_type_is_an_error_and_the_batch_is_not_kept(gnss):
    instance, refs = gnss
    with pytest.raises(CosimError, match="getReal failed: KeyError"):
        instance.get("Real", [refs["gps_h"], refs["gps_count"]])
    with pytest.raises(CosimError, match="setInteger failed: KeyError"):
        instance.set("Integer", [refs["h"]], [1])
    assert instance.get("Real", [refs["gps_h"]]) == [instance.get("Real", [refs["gps_h"]])[0]]
