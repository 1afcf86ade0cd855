"""PX4 EKF2's height-fusion cases flown through the AltitudeEKF FMU, as a host drives it.

The cases of ``tests/test_altitude_ekf.py`` that mirror PX4's unit tests
(test_EKF_height_fusion.cpp: baro and GNSS steps, fail-over in both reference modes, the
all-sources-fail reset, GNSS returning inconsistent after dead reckoning;
test_EKF_accelerometer.cpp: the bias learnt), with PX4's tolerances as stated there, run
again on the built FMU: the same seeded hover, every sample set through FMI (fmpy), the
outputs read back through FMI. Same flight, same seeds: the FMU must reach what the core
reaches.
"""

import sys
from pathlib import Path

import pytest

from altfusion.cosim.instances import PY_TYPES, FmuInstance, fmu_info
from altfusion.estimators.altitude_ekf import AltitudeEKF

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_altitude_ekf as px4  # noqa: E402

PX4_CASES = [
    pytest.param(px4.test_baro_step_is_isolated_and_gnss_carries_the_height, {},
                 id="baro_step"),
    pytest.param(px4.test_reference_step_resets_the_height_to_it_when_nothing_contradicts_it,
                 {}, id="gnss_step_gps_ref_reset"),
    *(pytest.param(px4.test_a_jumping_reference_contradicted_by_another_source_is_isolated,
                   {"height_ref": ref}, id=f"reference_jump_contradicted_{ref}_ref")
      for ref in ("gps", "baro")),
    pytest.param(px4.test_all_height_sources_fail_one_reset_within_0_2_m, {},
                 id="all_height_sources_fail_reset"),
    *(pytest.param(px4.test_fail_over_keeps_the_height_until_every_source_is_lost,
                   {"height_ref": ref}, id=f"fail_over_{ref}_ref") for ref in ("gps", "baro")),
    pytest.param(px4.test_gnss_returning_inconsistent_is_not_readmitted, {},
                 id="gnss_dead_reckoning_restart_inconsistent"),
    pytest.param(px4.test_silent_sensors_turn_h_valid_false_within_aiding_timeout, {},
                 id="silent"),
    pytest.param(px4.test_accelerometer_bias_learnt_to_0_03_in_60_s, {},
                 id="accelerometer_bias"),
]


class FmuEstimator:
    """An AltitudeEKF FMU instance behind the attributes the flight uses on the core object:
    an input set by assigning it, an output or input read by name (each through FMI),
    ``do_step``, ``clock``, ``dt``, ``time`` and the parameters as ``params``."""

    def __init__(self, fmu: Path, params: dict):
        info = fmu_info(fmu)
        instance = FmuInstance("ekf", info)
        instance.initialize(params, px4.STEP, 0.0, 1e6)
        instance.exit_initialization()
        core = px4.core_estimator(params)             # its clock and parameters only
        self.__dict__.update(_info=info, _instance=instance, clock=core.clock, dt=core.dt,
                             params=core.params, time=0.0)

    def _variable(self, name: str):
        variable = self._info.variables.get(name)
        if variable is None or variable.causality not in ("input", "output"):
            raise AttributeError(name)
        return variable

    def __getattr__(self, name: str):
        variable = self._variable(name)
        return self._instance.get(variable.type, [variable.value_reference])[0]

    def __setattr__(self, name: str, value) -> None:
        variable = self._variable(name)
        self._instance.set(variable.type, [variable.value_reference],
                           [PY_TYPES[variable.type](value)])

    def do_step(self, current_time: float, step_size: float) -> None:
        self._instance.do_step(current_time, step_size)
        self.__dict__["time"] = current_time + step_size

    def free(self) -> None:
        self._instance.terminate()
        self._instance.free()


@pytest.fixture
def flown_on_the_fmu(fmus, monkeypatch):
    """Every Flight built during the test flies the FMU; each instance freed afterwards."""
    flown: list[FmuEstimator] = []

    def make(params: dict) -> FmuEstimator:
        flown.append(FmuEstimator(fmus[AltitudeEKF.__name__], params))
        return flown[-1]

    monkeypatch.setattr(px4.Flight, "make_estimator", staticmethod(make))
    yield flown
    for estimator in flown:
        estimator.free()


@pytest.mark.parametrize("case, arguments", PX4_CASES)
def test_px4_height_fusion_case_through_the_fmu(flown_on_the_fmu, case, arguments):
    case(**arguments)
    assert flown_on_the_fmu, "the case flew no FMU"
