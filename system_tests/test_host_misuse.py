"""A host's illegal or absurd request is refused at fmi2Error with its reason, in one line,
and the instance goes on as before: a fixed parameter set while the instance steps, a doStep
at a time that is not a number, a communication step that would run 1e14 ticks."""

import pytest

from altfusion.cosim.instances import CosimError, FmuInstance, fmu_info
from altfusion.timegrid import MAX_TICKS_PER_STEP


@pytest.fixture
def atmosphere(fmus):
    """An Atmosphere instance stepping on a 0.01 s tick with p0 = 100000 Pa."""
    info = fmu_info(fmus["Atmosphere"])
    instance = FmuInstance("atmosphere", info)
    refs = {name: var.value_reference for name, var in info.variables.items()}
    instance.initialize({"p0": 100000.0}, 0.01, 0.0, 10.0)
    instance.exit_initialization()
    yield instance, refs
    instance.free()


def test_a_fixed_parameter_set_while_stepping_is_refused_and_kept(atmosphere):
    instance, refs = atmosphere
    instance.do_step(0.0, 0.01)
    with pytest.raises(CosimError) as refused:
        instance.set("Real", [refs["p0"]], [90000.0])
    assert "parameter 'p0' = 90000.0: fixed, it can be set before exitInitializationMode " \
           "only; the instance keeps 100000.0" in str(refused.value)
    assert "Traceback" not in str(refused.value)
    # The value read back is the one the core runs on: before the fix it read 90000.0
    # while the outputs stayed those of 100000.0.
    assert instance.get("Real", [refs["p0"], refs["p_static"]]) == [100000.0, 100000.0]
    instance.do_step(0.01, 0.01)


def test_a_step_running_more_ticks_than_one_dostep_may_is_refused_at_once(atmosphere):
    instance, refs = atmosphere
    with pytest.raises(CosimError, match=r"communication step 1000000000000.0 s would run "
                                         r"100000000000000 ticks of 0.01 s, more than "
                                         f"{MAX_TICKS_PER_STEP}"):
        instance.do_step(0.0, 1e12)
    instance.do_step(0.0, 0.01)                      # the clock did not move
    assert instance.get("Real", [refs["p_static"]]) == [100000.0]


def test_a_dostep_at_a_time_that_is_not_a_number_is_refused_naming_it(atmosphere):
    instance, _ = atmosphere
    with pytest.raises(CosimError) as refused:
        instance.do_step(float("nan"), 0.01)
    assert "doStep at t = nan s, but this component is at t = 0.0 s" in str(refused.value)
    assert "Traceback" not in str(refused.value)
    instance.do_step(0.0, 0.01)
