"""The Estimator base's generalisations: timed streams and extra (stream-less) inputs."""

import math
from dataclasses import dataclass

from altfusion.estimators.base import BARO, RADAR, RADAR_TIMED, Estimator
from altfusion.fmi import estimator_variables
from altfusion.params import param


@dataclass(frozen=True)
class EchoParams:
    gain: float = param(1.0, "1", "Unused")


class Echo(Estimator):
    """Records what the base hands over: the fused samples and the held wind speed."""

    Params = EchoParams
    streams = (BARO, RADAR_TIMED)
    extra_inputs = ("wind_speed",)

    def initialize_filter(self) -> None:
        self.fused = []
        self.winds = []

    def propagate(self, dt: float) -> None:
        self.winds.append(self.held_input("wind_speed"))

    def fuse(self, stream, sample) -> None:
        self.fused.append((stream.prefix, sample))


def test_a_timed_stream_carries_the_time_stamp_as_a_value():
    assert RADAR_TIMED.values == ("radar_h", "radar_time")
    assert (RADAR_TIMED.count, RADAR_TIMED.valid, RADAR_TIMED.time) == (
        "radar_count", "radar_valid", "radar_time")
    assert RADAR_TIMED.timed() is RADAR_TIMED
    assert RADAR.timed() == RADAR_TIMED


def test_timed_samples_include_their_stamp():
    echo = Echo(step_size=0.1)
    echo.radar_h, echo.radar_time, echo.radar_count = 12.0, 0.1, 1
    echo.do_step(0.0, 0.1)
    assert echo.fused == [("radar", {"radar_h": 12.0, "radar_time": 0.1})]


def test_a_non_finite_time_stamp_makes_the_sample_ignored():
    echo = Echo(step_size=0.1)
    echo.radar_h, echo.radar_time, echo.radar_count = 12.0, math.nan, 1
    echo.do_step(0.0, 0.1)
    assert echo.fused == [] and echo.n_ignored == 1


def test_held_input_holds_the_last_finite_value_and_notes_each_run_of_bad_values_once():
    echo = Echo(step_size=0.1)
    for n, wind in enumerate([2.0, math.nan, math.inf, 3.0, -math.inf]):
        echo.wind_speed = wind
        echo.do_step(n * 0.1, 0.1)
    assert echo.winds == [2.0, 2.0, 2.0, 3.0, 3.0]
    assert echo.n_ignored == 3
    notes = [n for n in echo.take_notes() if "wind_speed: non-finite sample ignored" in n]
    assert len(notes) == 2  # one per run of non-finite values


def test_extra_inputs_default_to_zero_and_held_input_starts_from_zero_if_not_finite():
    assert Echo(step_size=0.1).wind_speed == 0.0
    echo = Echo(step_size=0.1, inputs={"wind_speed": math.nan})
    echo.do_step(0.0, 0.1)
    assert echo.winds == [0.0]


def test_estimator_variables_declare_stream_inputs_then_extra_inputs():
    variables = estimator_variables(Echo.streams, (), Echo.extra_inputs)
    names = [v.name for v in variables]
    assert names == ["baro_h", "baro_count", "radar_h", "radar_time", "radar_count",
                     "radar_valid", "wind_speed", "h_est", "vz_est", "h_std"]
    assert {v.name: v.unit for v in variables}["wind_speed"] == "m/s"
