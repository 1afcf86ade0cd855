"""The Estimator base's generalisations: timed streams and extra (stream-less) inputs."""

import copy
import math
from dataclasses import dataclass
from pathlib import Path

from altfusion.estimators.base import Estimator, HealthParams, Status, status_bits
from altfusion.estimators.streams import BARO, BARO_T, RADAR
from altfusion.fmi import estimator_variables
from altfusion.fmi.state import StateHeader, dump, load
from altfusion.params import param


@dataclass(frozen=True)
class EchoParams(HealthParams):
    gain: float = param(1.0, "1", "Unused")


class Echo(Estimator):
    """Records what the base hands over: the fused samples and the held wind speed."""

    Params = EchoParams
    streams = (BARO, RADAR)
    extra_inputs = ("wind_speed",)

    def initialize_filter(self) -> None:
        self.fused = []
        self.winds = []

    def propagate(self, dt: float) -> None:
        self.winds.append(self.held_input("wind_speed"))

    def fuse(self, stream, sample) -> None:
        self.fused.append((stream.prefix, sample))

    def reset_height(self, source, innovation, variance) -> None:
        raise AssertionError("Echo gates nothing")


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


class AirEcho(Echo):
    """Echo of the baro stream with the air temperature beside its height."""

    streams = (BARO_T,)
    extra_inputs = ()

    def propagate(self, dt: float) -> None:
        pass


def test_an_implausible_auxiliary_value_is_left_out_of_the_sample_and_noted_per_run():
    """The air temperature at its unconnected start value (0 K) or beyond 400 K: the baro
    sample is fused without it, each counted in n_ignored, one note per run of them."""
    echo = AirEcho(step_size=0.1)
    for n, temperature in enumerate([0.0, 0.0, 288.15, 500.0]):
        echo.baro_h, echo.baro_T, echo.baro_time, echo.baro_count = 10.0, temperature, \
            n * 0.1, n + 1
        echo.do_step(n * 0.1, 0.1)
    assert [sample.get("baro_T") for _, sample in echo.fused] == [None, None, 288.15, None]
    assert all(sample["baro_h"] == 10.0 for _, sample in echo.fused)
    assert echo.n_ignored == 3
    notes = [n for n in echo.take_notes() if "baro_T:" in n and "plausible" in n]
    assert len(notes) == 2  # one per run of implausible values


def test_extra_inputs_default_to_zero_and_held_input_starts_from_zero_if_not_finite():
    assert Echo(step_size=0.1).wind_speed == 0.0
    echo = Echo(step_size=0.1, inputs={"wind_speed": math.nan})
    echo.do_step(0.0, 0.1)
    assert echo.winds == [0.0]


def test_estimator_variables_declare_stream_inputs_then_extra_inputs():
    variables = estimator_variables(Echo.streams, (), Echo.extra_inputs)
    names = [v.name for v in variables]
    assert names[:10] == ["baro_h", "baro_count", "baro_time", "radar_h", "radar_count",
                          "radar_time", "radar_valid", "wind_speed", "h_est", "vz_est"]
    assert names[10:] == ["h_std", "h_valid", "status", "n_rejected", "n_ignored",
                          "n_height_resets", "baro_test_ratio", "baro_rejected",
                          "radar_test_ratio", "radar_rejected"]
    assert {v.name: v.unit for v in variables}["wind_speed"] == "m/s"


def test_every_status_bit_is_documented_with_its_mask():
    """docs/estimator_health.md lists each bit of status_bits() as `| bit | mask | name |`."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "estimator_health.md").read_text()
    for name, mask in status_bits().items():
        assert f"| {mask.bit_length() - 1} | 0x{mask:08X} | `{name}` |" in doc, name


def test_a_sample_stamped_ahead_of_the_clock_is_held_until_due_and_an_absurd_one_refused():
    """ECOS shows a 10 Hz sample of t = 0.3 s at t = 0.1 s: it is fused at 0.3 s, not before;
    a stamp more than max_sample_lead (1 s) ahead is refused, counted in radar_rejected and
    flagged SAMPLE_REFUSED for its step."""
    echo = Echo(step_size=0.1)
    echo.radar_h, echo.radar_time, echo.radar_count = 12.0, 0.3, 1
    for n in range(3):
        assert echo.fused == []
        echo.do_step(n * 0.1, 0.1)
    assert echo.fused == [("radar", {"radar_h": 12.0, "radar_time": 0.3})]
    echo.radar_time, echo.radar_count = 1.5, 2
    echo.do_step(0.3, 0.1)
    assert echo.status & Status.SAMPLE_REFUSED
    for n in range(4, 20):
        echo.do_step(n * 0.1, 0.1)
    assert len(echo.fused) == 1 and echo.radar_rejected == echo.n_rejected == 1
    assert not echo.status & Status.SAMPLE_REFUSED


def test_a_stale_or_out_of_order_sample_is_refused_and_counted():
    """A radar sample stamped 10 s behind the clock (more than max_sample_delay, 3 s) is not
    fused as if current (issue 30: a GNSS sample 10 s old was fused, counted nowhere); one
    stamped before the stream's last sample neither; both count in radar_rejected. Samples
    slightly behind (early_late_samples: 0.02 s) pass."""
    echo = Echo(step_size=0.1)
    for n in range(119):
        echo.do_step(n * 0.1, 0.1)
    echo.radar_h, echo.radar_time, echo.radar_count = 12.0, 11.98, 1   # 0.02 s behind
    echo.do_step(echo.time, 0.1)
    assert echo.fused == [("radar", {"radar_h": 12.0, "radar_time": 11.98})]
    echo.radar_time, echo.radar_count = 12.1 - 10.0, 2                 # 10 s old
    echo.do_step(echo.time, 0.1)
    assert echo.status & Status.SAMPLE_REFUSED and echo.radar_rejected == 1
    echo.radar_time, echo.radar_count = 11.9, 3                        # before the last
    echo.do_step(echo.time, 0.1)
    assert echo.status & Status.SAMPLE_REFUSED and echo.radar_rejected == 2
    echo.radar_time, echo.radar_count = 12.3, 4
    echo.do_step(echo.time, 0.1)
    assert len(echo.fused) == 2 and echo.radar_rejected == echo.n_rejected == 2
    assert not echo.status & Status.SAMPLE_REFUSED
    assert echo.n_ignored == 0


def test_a_held_sample_survives_a_saved_and_restored_state():
    """A host that saves the state while an early sample waits (fmi2GetFMUstate: a deep copy;
    fmi2SerializeFMUstate: bytes) and restores it fuses that sample when due, as the
    estimator that ran on does: the restored state holds copies of the Stream constants, so
    nothing may be keyed by a Stream's identity."""
    header = StateHeader("Echo", "guid", "0.1.0+x")
    echo = Echo(step_size=0.1)
    echo.radar_h, echo.radar_time, echo.radar_count = 12.0, 0.3, 1
    echo.do_step(0.0, 0.1)
    restored = [copy.deepcopy(echo), load(dump(header, echo, __name__), header, __name__)]
    for estimator in (echo, *restored):
        for n in (1, 2):
            estimator.do_step(n * 0.1, 0.1)
        assert estimator.fused == [("radar", {"radar_h": 12.0, "radar_time": 0.3})]


def _hover_with_a_step(source: str, step: float) -> tuple[list[int], object]:
    """BaselineKF over a 100 m hover at 10 Hz, baro 5 m and GPS 10 m noise; ``source``'s
    readings step by ``step`` from t = 60 s to the end (120 s). Returns the status after
    each step from the fault on, and the estimator."""
    import numpy as np
    from stream_feeder import StreamFeeder

    from altfusion.estimators.baseline import BaselineKF, BaselineKFParams

    estimator = BaselineKF(BaselineKFParams(R_baro=25.0, R_gps=100.0), step_size=0.1)
    feeder = StreamFeeder(estimator)
    rng = np.random.default_rng(5)
    statuses = []
    for k in range(1200):
        faulty = k >= 600
        baro = 100.0 + 5.0 * rng.standard_normal() + (step if faulty and source == "baro" else 0)
        gps = 100.0 + 10.0 * rng.standard_normal() + (step if faulty and source == "gps" else 0)
        feeder.step(baro={"baro_h": baro}, gps={"gps_h": gps, "gps_fix": True})
        if faulty:
            statuses.append(estimator.status)
    return statuses, estimator


def test_an_isolated_source_with_an_offset_state_is_re_admitted_with_its_new_offset():
    """A baro stepped by 200 m (a constant offset, 40 of its σ) while the GPS agrees: isolated
    (its ISOLATED bit within 10 s), then, rejected for twice reset_timeout with every
    innovation of its window on the same side, re-admitted with BaselineKF's baro bias moved
    onto it: at the end the bias is within 3 of its σ of the 200 m, the baro is fused again
    and the height within 3 h_std of the truth. The GPS, the height reference (no offset
    state), stepped the same way, stays isolated to the end (PX4: a GNSS back off is not
    re-admitted)."""
    from altfusion.estimators.base import SourceBit, source_bit

    statuses, estimator = _hover_with_a_step("baro", 200.0)
    isolated = [s & source_bit("baro", SourceBit.ISOLATED) != 0 for s in statuses]
    assert any(isolated[:100]) and not isolated[-1]
    assert statuses[-1] & source_bit("baro", SourceBit.FUSED)
    assert abs(estimator.bias - 200.0) <= 3.0 * math.sqrt(estimator.P[2][2])
    assert abs(estimator.h_est - 100.0) <= 3.0 * estimator.h_std
    statuses, estimator = _hover_with_a_step("gps", 200.0)
    isolated = [s & source_bit("gps", SourceBit.ISOLATED) != 0 for s in statuses]
    assert any(isolated[:100]) and all(isolated[100:])
