"""FMU outputs in Initialization Mode follow the parameters and inputs set so far.

ECOS sets the SSP's parameter values after enterInitializationMode, and libcosim and ECOS read
outputs and set inputs in Initialization Mode until the initial values settle; the outputs
they read there must be those of the current values (FMI 2.0, the InitialUnknowns)."""

import pytest

from altfusion.cosim.instances import FmuInstance, fmu_info
from altfusion.physics.atmosphere import Atmosphere


@pytest.fixture
def atmosphere(fmus):
    info = fmu_info(fmus["Atmosphere"])
    instance = FmuInstance("atmosphere", info)
    yield instance, {name: var.value_reference for name, var in info.variables.items()}
    instance.free()


def test_an_input_set_in_initialization_mode_updates_the_outputs(atmosphere):
    instance, refs = atmosphere
    instance.fmu.setupExperiment(startTime=0.0)
    instance.fmu.enterInitializationMode()
    instance.fmu.setReal([refs["h"]], [1000.0])
    expected = Atmosphere(inputs={"h": 1000.0}).p_static
    assert instance.fmu.getReal([refs["p_static"]])[0] == expected  # 89874.6 Pa, not 101325


def test_a_parameter_set_in_initialization_mode_updates_the_outputs(atmosphere):
    instance, refs = atmosphere
    instance.fmu.setupExperiment(startTime=0.0)
    instance.fmu.enterInitializationMode()
    instance.fmu.setReal([refs["p0"]], [100000.0])
    assert instance.fmu.getReal([refs["p_static"]])[0] == 100000.0
    instance.fmu.exitInitializationMode()
    assert instance.fmu.getReal([refs["p_static"]])[0] == 100000.0
