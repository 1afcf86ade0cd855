"""SensorFaults: the sensor streams passed through, with one named fault scenario applied.

The component sits between the sensors and their consumers (``altfusion.systems.faults``
inserts it). Its inputs are the sensor outputs of the signal contract, prefixed ``raw_``
(``raw_baro_h``, ``raw_gps_count``...), plus the true altitude ``h`` and the thrust
``thrust`` for the faults that depend on them; its outputs carry the contract names
(``baro_h``, ``gps_count``...). Without a fault every output equals its input. A new sample
(its ``raw_<prefix>_count`` changed) is passed on as one new sample (the output count
increments, the stamp follows), its values changed by the scenario; validity flags pass
through at every step.

The scenarios (``docs/faults.md``; their magnitudes are the parameters, defaults from the
production autopilots' tests and reports listed there). t0 is ``fault_start``:

================================  ============================================================
``none``                          every stream passed through unchanged
``baro_step``                     baro height + ``baro_step`` from t0 (a failed barometer)
``baro_drift``                    baro height drifting + ``baro_drift`` linearly over
                                  ``baro_drift_time`` from t0, on top of a warm-up drift of
                                  ``warmup_drift`` over the first ``warmup_time`` of the run
``gnss_step``                     GNSS height + ``gps_jump`` from t0 - ``gps_jump_lead`` (a
                                  small jump), + ``gps_step`` more from t0; both stay
``gnss_outage_return_off``        no GNSS fix for ``gps_outage`` before t0 (from 0 at the
                                  earliest); from t0 it returns ``gps_return_offset`` off
``failover``                      the GNSS stops at t0, the barometer ``failover_interval``
                                  later, the range sensors (radar, laser) after another
``all_fail``                      GNSS + ``all_fail_gps`` and baro + ``all_fail_baro`` from t0
``silent``                        every sensor stops at t0
``wild_sample``                   from t0, every ``wild_interval``, the next sample of one
                                  input in turn carries an absurd value (:data:`WILD_PROBES`)
``acc_bias``                      accelerometer bias drawn uniformly from [``acc_bias_min``,
                                  ``acc_bias_max``] from t0; from t0 + ``clip_delay`` for
                                  ``clip_duration`` the samples clip at ± ``acc_clip``
                                  alternately (vibration beyond the full scale)
``ground_effect``                 from t0, within ``ground_effect_zone`` of ``ground_h`` the
                                  baro height errs by up to ``ground_effect_takeoff_error``
                                  before the vehicle first leaves the zone (take-off) and by
                                  up to ``ground_effect_error`` after (landing): the full
                                  error within ``ground_effect_height``, tapering linearly to
                                  0 at the edge of the zone
``prop_wash``                     from t0 the baro height errs by ``prop_wash_error`` ×
                                  thrust / ``full_thrust`` (thrust clipped to [0, full])
``range_terrain``                 range sensors (radar, laser): over a box of ``terrain_box``
                                  for ``range_phase`` from t0 (readings lower by that much),
                                  then stuck at their last reading for ``range_phase``, then
                                  reading ``range_low`` (below the laser's minimum range,
                                  flagged valid) for ``range_phase``, a gap of ``range_phase``
                                  between phases
``weather_front``                 from t0 the static pressure falls by ``front_drop`` over
                                  ``front_time`` (a weather front), the baro height rising
                                  by the hypsometric equivalent
``early_late_samples``            from t0 GNSS and radar samples stamped ``stamp_lead`` ahead
                                  of the instant they arrive (as ECOS shows a slow component's
                                  sample), baro, accelerometer and laser samples ``stamp_lag``
                                  behind it
================================  ============================================================

A stopped sensor's outputs hold and its count freezes (the wire keeps its last value). A
baro height offset dh moves the pressure by the hypsometric equation, p' = p·exp(-g·dh /
(R·T)) with the module's own temperature, so that height and pressure stay consistent.
"""

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from altfusion.component import Component
from altfusion.constants import G0, ISA_T0, R_AIR
from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.timegrid import TickClock

STREAMS: dict[str, tuple[str, ...]] = {
    "baro": ("baro_h", "baro_p", "baro_T"),
    "gps": ("gps_h", "gps_vz", "gps_vdop", "gps_nsat"),
    "acc": ("acc_z",),
    "radar": ("radar_h",),
    "laser": ("laser_h",),
}
"""Sample values of each stream passed through (count and stamp besides)."""

VALIDITY: dict[str, str] = {"gps": "gps_fix", "radar": "radar_valid", "laser": "laser_valid"}
"""Validity flag of each stream that has one."""

RANGE_SOURCES = ("radar", "laser")


def stream_signals(prefix: str) -> tuple[str, ...]:
    """Every contract signal of stream ``prefix``: values, validity flag, count, stamp."""
    validity = (VALIDITY[prefix],) if prefix in VALIDITY else ()
    return (*STREAMS[prefix], *validity, f"{prefix}_count", f"{prefix}_time")


PASSED_SIGNALS: tuple[str, ...] = tuple(name for prefix in STREAMS
                                        for name in stream_signals(prefix))
"""Every signal the component passes through; input ``raw_<name>`` drives output ``<name>``."""

SCENARIOS = ("none", "baro_step", "baro_drift", "gnss_step", "gnss_outage_return_off",
             "failover", "all_fail", "silent", "wild_sample", "acc_bias", "ground_effect",
             "prop_wash", "range_terrain", "weather_front", "early_late_samples")
"""Values of the ``scenario`` parameter: ``none`` and the fault suite in docs/faults.md order."""

WILD_PROBES: tuple[tuple[str, float], ...] = (
    ("baro_h", 1100.0), ("baro_h", 1e308), ("gps_h", 1100.0), ("gps_h", 1e308),
    ("gps_vz", 100.0), ("acc_z", 1000.0), ("acc_z", 1e308), ("radar_h", 1100.0),
    ("laser_h", 1100.0), ("gps_time", 1e308),
)
"""The absurd samples of ``wild_sample``, in order: (signal, value) (docs/faults.md: a height
of 1100 m, 1e308, acc_z 1000 m/s², gps_vz 100 m/s; and a GNSS stamp of 1e308 s)."""


@dataclass(frozen=True)
class SensorFaultsParams:
    scenario: str = param("none", None, "Fault scenario: " + " | ".join(SCENARIOS))
    seed: int = param(0, None, "Seed of the scenario's random draws (acc_bias)", min=0)
    fault_start: float = param(120.0, "s", "Time t0 the scenario's fault starts", min=0.0)
    baro_step: float = param(200.0, "m", "baro_step: baro height step (PX4 baro jump test)")
    baro_drift: float = param(5.0, "m", "baro_drift: drift reached after baro_drift_time")
    baro_drift_time: float = param(100.0, "s", "baro_drift: duration of the drift",
                                   positive=True)
    warmup_drift: float = param(9.0, "m", "baro_drift: warm-up drift over warmup_time from "
                                          "the start of the run (ArduPilot #2022: 8-10 m)")
    warmup_time: float = param(600.0, "s", "baro_drift: duration of the warm-up drift",
                               positive=True)
    gps_step: float = param(100.0, "m", "gnss_step: GNSS height step at t0 (PX4 test)")
    gps_jump: float = param(6.0, "m", "gnss_step: small GNSS jump before the step "
                                      "(PX4 #21820)")
    gps_jump_lead: float = param(60.0, "s", "gnss_step: the small jump comes this long "
                                            "before t0", min=0.0)
    gps_outage: float = param(600.0, "s", "gnss_outage_return_off: outage ending at t0",
                              min=0.0)
    gps_return_offset: float = param(50.0, "m", "gnss_outage_return_off: GNSS height error "
                                                "after the outage")
    failover_interval: float = param(40.0, "s", "failover: time between the stops of GNSS, "
                                                "baro and range sensors", min=0.0)
    all_fail_gps: float = param(10.0, "m", "all_fail: GNSS height step")
    all_fail_baro: float = param(5.0, "m", "all_fail: baro height step")
    wild_interval: float = param(5.0, "s", "wild_sample: time between two absurd samples",
                                 positive=True)
    acc_bias_min: float = param(0.1, "m/s2", "acc_bias: smallest bias drawn")
    acc_bias_max: float = param(0.4, "m/s2", "acc_bias: largest bias drawn")
    acc_clip: float = param(156.9, "m/s2", "acc_bias: clipping level (16 g full scale)",
                            positive=True)
    clip_delay: float = param(150.0, "s", "acc_bias: clipping episode starts t0 + this",
                              min=0.0)
    clip_duration: float = param(1.0, "s", "acc_bias: duration of the clipping episode",
                                 min=0.0)
    ground_h: float = param(0.0, "m", "ground_effect: ground height (MSL)")
    ground_effect_error: float = param(-4.0, "m", "ground_effect: baro error near the "
                                                  "ground on landing (PX4 EKF2_GND_EFF_DZ)")
    ground_effect_takeoff_error: float = param(2.0, "m", "ground_effect: baro error near the "
                                                         "ground at take-off (PX4 #26655)")
    ground_effect_height: float = param(1.0, "m", "ground_effect: full error below this "
                                                  "height above ground", min=0.0)
    ground_effect_zone: float = param(3.0, "m", "ground_effect: no error above this height "
                                                "above ground", positive=True)
    prop_wash_error: float = param(7.0, "m", "prop_wash: baro error at full thrust "
                                             "(PX4 #26924)")
    full_thrust: float = param(40.0, "N", "prop_wash: full thrust (FlightController "
                                          "thrust_max)", positive=True)
    terrain_box: float = param(3.0, "m", "range_terrain: height of the terrain box")
    range_phase: float = param(5.0, "s", "range_terrain: duration of each phase (box, stuck, "
                                         "low) and of the gaps between them", positive=True)
    range_low: float = param(0.05, "m", "range_terrain: out-of-range-low reading, flagged "
                                        "valid", min=0.0)
    front_drop: float = param(300.0, "Pa", "weather_front: static-pressure fall (3 hPa)")
    front_time: float = param(3600.0, "s", "weather_front: duration of the fall",
                              positive=True)
    stamp_lead: float = param(0.05, "s", "early_late_samples: GNSS and radar stamps ahead "
                                         "(below their sample period: ECOS shows a slow "
                                         "component's sample at most one step early)",
                              min=0.0)
    stamp_lag: float = param(0.02, "s", "early_late_samples: baro, acc, laser stamps behind",
                             min=0.0)


def hypsometric_pressure(p: float, T: float, dh: float) -> float:
    """The pressure ``dh`` higher than ``p`` at temperature ``T`` (ISA's if not > 0)."""
    T = T if T > 0.0 else ISA_T0
    return p * math.exp(-G0 * dh / (R_AIR * T))


def hypsometric_height(p: float, p_new: float, T: float) -> float:
    """The height change from pressure ``p`` to ``p_new`` at temperature ``T``."""
    T = T if T > 0.0 else ISA_T0
    return R_AIR * T / G0 * math.log(p / p_new) if p > 0.0 and p_new > 0.0 else 0.0


def ramp(t: float, start: float, duration: float) -> float:
    """0 before ``start``, rising linearly to 1 over ``duration``, then 1."""
    return min(max((t - start) / duration, 0.0), 1.0)


class _StreamNames(NamedTuple):
    """The attribute names SensorFaults reads and writes for one stream, made once."""

    prefix: str
    raw_values: tuple[tuple[str, str], ...]
    """(output, input) of each sample value: ``("baro_h", "raw_baro_h")``..."""
    validity: str | None
    raw_validity: str | None
    ranging: bool
    """A range sensor (:data:`RANGE_SOURCES`)."""
    count: str
    raw_count: str
    time: str
    raw_time: str
    fault: str
    """The method applying the scenario to a sample: ``_fault_<prefix>``."""

    @classmethod
    def of(cls, prefix: str) -> "_StreamNames":
        validity = VALIDITY.get(prefix)
        return cls(prefix, tuple((name, f"raw_{name}") for name in STREAMS[prefix]),
                   validity, None if validity is None else f"raw_{validity}",
                   prefix in RANGE_SOURCES, f"{prefix}_count", f"raw_{prefix}_count",
                   f"{prefix}_time", f"raw_{prefix}_time", f"_fault_{prefix}")


class SensorFaults(Component):
    """Inputs ``raw_<signal>`` of :data:`PASSED_SIGNALS`, ``h``, ``thrust``; outputs the
    signals of :data:`PASSED_SIGNALS` and ``fault_active``."""

    Params = SensorFaultsParams

    def __init__(self, params: SensorFaultsParams | None = None, **kwargs):
        for prefix, names in STREAMS.items():
            for name in names:
                setattr(self, f"raw_{name}", 0.0 if name != "gps_nsat" else 0)
            if prefix in VALIDITY:
                setattr(self, f"raw_{VALIDITY[prefix]}", prefix == "gps")
            setattr(self, f"raw_{prefix}_count", 0)
            setattr(self, f"raw_{prefix}_time", 0.0)
        self.h = 0.0
        self.thrust = 0.0
        super().__init__(params, **kwargs)

    def configure(self, clock: TickClock) -> None:
        p = self.params
        if p.scenario not in SCENARIOS:
            raise ParameterError("scenario", p.scenario, f"unknown; choose one of {SCENARIOS}")
        if p.acc_bias_min > p.acc_bias_max:
            raise ParameterError("acc_bias_min", p.acc_bias_min,
                                 f"must not exceed acc_bias_max = {p.acc_bias_max}")
        if p.ground_effect_height >= p.ground_effect_zone:
            raise ParameterError("ground_effect_height", p.ground_effect_height,
                                 f"must be below ground_effect_zone = {p.ground_effect_zone}")
        self._streams = tuple(_StreamNames.of(prefix) for prefix in STREAMS)
        self._may_stop = p.scenario in ("silent", "failover")

    def reset(self) -> None:
        p = self.params
        rng = np.random.default_rng(np.random.SeedSequence([p.seed, 0x5F]))
        self.acc_bias = float(rng.uniform(p.acc_bias_min, p.acc_bias_max))
        self._last_count = {prefix: getattr(self, f"raw_{prefix}_count") for prefix in STREAMS}
        for name in PASSED_SIGNALS:
            setattr(self, name, getattr(self, f"raw_{name}"))
        self._probe = 0
        self._left_ground = False
        self._clip_sign = 1.0
        self._held = {"h": 0.0, "thrust": 0.0}
        self.fault_active = False

    # ------------------------------------------------------------------ scenario timing
    def _stopped(self, prefix: str, t: float) -> bool:
        """True if stream ``prefix`` has stopped (outputs hold, count frozen)."""
        p = self.params
        if p.scenario == "silent":
            return t >= p.fault_start
        if p.scenario == "failover":
            order = {"gps": 0, "baro": 1, "radar": 2, "laser": 2}.get(prefix)
            return order is not None and t >= p.fault_start + order * p.failover_interval
        return False

    def _gps_outage(self, t: float) -> bool:
        p = self.params
        return (p.scenario == "gnss_outage_return_off"
                and max(p.fault_start - p.gps_outage, 0.0) <= t < p.fault_start)

    def _range_phase(self, t: float) -> str | None:
        """'box', 'stuck' or 'low' while that phase of ``range_terrain`` lasts."""
        p = self.params
        if p.scenario != "range_terrain" or t < p.fault_start:
            return None
        phase, within = divmod((t - p.fault_start) / p.range_phase, 1.0)
        names = {0: "box", 2: "stuck", 4: "low"}
        return names.get(int(phase)) if within < 1.0 else None

    # ------------------------------------------------------------------ Component
    def update(self) -> None:
        p = self.params
        t = self.clock.now
        height = self._finite_input("h")
        thrust = self._finite_input("thrust")
        if height - p.ground_h > p.ground_effect_zone:
            self._left_ground = True
        self.fault_active = p.scenario != "none" and t >= p.fault_start
        for names in self._streams:
            prefix = names.prefix
            if self._may_stop and self._stopped(prefix, t):
                continue
            if prefix == "gps" and self._gps_outage(t):
                self.gps_fix = False
                self._last_count[prefix] = self.raw_gps_count
                continue
            if names.validity is not None:
                valid = bool(getattr(self, names.raw_validity))
                if names.ranging and self._range_phase(t) in ("stuck", "low"):
                    valid = True
                setattr(self, names.validity, valid)
            count = getattr(self, names.raw_count)
            if count != self._last_count[prefix]:
                self._last_count[prefix] = count
                self._pass_sample(names, t, height, thrust)

    def _finite_input(self, name: str) -> float:
        """Input ``name``, or its last finite value (a non-finite truth is not a fault)."""
        value = float(getattr(self, name))
        if math.isfinite(value):
            self._held[name] = value
        return self._held[name]

    def _pass_sample(self, names: "_StreamNames", t: float, height: float,
                     thrust: float) -> None:
        """Apply the scenario to the new sample of stream ``names.prefix`` and deliver it."""
        sample = {name: getattr(self, raw) for name, raw in names.raw_values}
        sample[names.time] = float(getattr(self, names.raw_time))
        if self.fault_active or self.params.scenario in ("baro_drift", "gnss_step"):
            apply = getattr(self, names.fault)
            apply(sample, t, height, thrust)
            self._wild(names.prefix, sample, t)
        for name, value in sample.items():
            setattr(self, name, value)
        setattr(self, names.count, getattr(self, names.count) + 1)

    # ------------------------------------------------------------------ faults per stream
    def _fault_baro(self, sample: dict, t: float, height: float, thrust: float) -> None:
        p, scenario, dh = self.params, self.params.scenario, 0.0
        if scenario == "baro_step":
            dh = p.baro_step
        elif scenario == "baro_drift":
            dh = (p.warmup_drift * ramp(t, 0.0, p.warmup_time)
                  + p.baro_drift * ramp(t, p.fault_start, p.baro_drift_time))
        elif scenario == "all_fail":
            dh = p.all_fail_baro
        elif scenario == "ground_effect":
            dh = self._ground_effect(height)
        elif scenario == "prop_wash":
            dh = p.prop_wash_error * min(max(thrust / p.full_thrust, 0.0), 1.0)
        elif scenario == "weather_front":
            pressure = sample["baro_p"]
            fallen = pressure - p.front_drop * ramp(t, p.fault_start, p.front_time)
            dh = hypsometric_height(pressure, fallen, sample["baro_T"])
        elif scenario == "early_late_samples":
            sample["baro_time"] -= p.stamp_lag
        if dh:
            sample["baro_h"] += dh
            sample["baro_p"] = hypsometric_pressure(sample["baro_p"], sample["baro_T"], dh)

    def _ground_effect(self, height: float) -> float:
        """The baro error of ``ground_effect`` at true altitude ``height``."""
        p = self.params
        above = height - p.ground_h
        weight = 1.0 - ramp(above, p.ground_effect_height,
                            p.ground_effect_zone - p.ground_effect_height)
        error = p.ground_effect_error if self._left_ground else p.ground_effect_takeoff_error
        return weight * error

    def _fault_gps(self, sample: dict, t: float, height: float, thrust: float) -> None:
        p, scenario = self.params, self.params.scenario
        if scenario == "gnss_step":
            sample["gps_h"] += (p.gps_jump * (t >= p.fault_start - p.gps_jump_lead)
                                + p.gps_step * (t >= p.fault_start))
        elif scenario == "gnss_outage_return_off":
            sample["gps_h"] += p.gps_return_offset
        elif scenario == "all_fail":
            sample["gps_h"] += p.all_fail_gps
        elif scenario == "early_late_samples":
            sample["gps_time"] += p.stamp_lead

    def _fault_acc(self, sample: dict, t: float, height: float, thrust: float) -> None:
        p = self.params
        if p.scenario == "acc_bias":
            sample["acc_z"] += self.acc_bias
            if 0.0 <= t - p.fault_start - p.clip_delay < p.clip_duration:
                sample["acc_z"] = self._clip_sign * p.acc_clip
                self._clip_sign = -self._clip_sign
        elif p.scenario == "early_late_samples":
            sample["acc_time"] -= p.stamp_lag

    def _fault_radar(self, sample: dict, t: float, height: float, thrust: float) -> None:
        self._fault_range("radar", sample, t)

    def _fault_laser(self, sample: dict, t: float, height: float, thrust: float) -> None:
        self._fault_range("laser", sample, t)

    def _fault_range(self, prefix: str, sample: dict, t: float) -> None:
        p, value = self.params, f"{prefix}_h"
        if p.scenario == "early_late_samples":
            shift = p.stamp_lead if prefix == "radar" else -p.stamp_lag
            sample[f"{prefix}_time"] += shift
            return
        phase = self._range_phase(t)
        if phase == "box" and getattr(self, VALIDITY[prefix]):
            sample[value] -= p.terrain_box
        elif phase == "stuck":
            sample[value] = getattr(self, value)
        elif phase == "low":
            sample[value] = p.range_low

    def _wild(self, prefix: str, sample: dict, t: float) -> None:
        """``wild_sample``: the next due probe, if it belongs to this stream."""
        p = self.params
        if p.scenario != "wild_sample" or self._probe >= len(WILD_PROBES):
            return
        name, value = WILD_PROBES[self._probe]
        if name in sample and t >= p.fault_start + self._probe * p.wild_interval:
            sample[name] = value
            self._probe += 1
