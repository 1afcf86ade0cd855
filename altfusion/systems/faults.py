"""The fault suite (``docs/faults.md``) as data, a fault inserted into any system, and the
generic flight every estimator is tested on side by side.

* :data:`FAULTS`: the 14 scenarios of the suite, in the spec's order, each a
  :class:`FaultScenario` timed for :func:`fault_flight` (its ``start``; preludes such as the
  GNSS outage before ``gnss_outage_return_off``'s return lie before it).
* :func:`with_fault`: a system with a ``fault`` component (the SensorFaults FMU,
  :mod:`altfusion.sensors.faults`) between its sensors and every consumer of their outputs.
* :func:`fault_flight`: a 300 s flight closed on the TRUE altitude (the estimators do not
  change it): take-off from the ground at 5 s to a 15 m hover (the laser in range), a climb
  at 60 s to a 120 m cruise, a descent at 200 s to the ground (landed at 264 s); the five
  sensors with yang2020's noise levels (the laser with its own 5 mm), the fast ones at 20 Hz;
  every estimator beside the others at 20 Hz, each given its sensors' true noise
  (:data:`TRUE_NOISE`).
"""

from dataclasses import dataclass, field, replace
from typing import Any

from altfusion.estimators.baseline import BaselineKFParams
from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.estimators.whang import WhangParams
from altfusion.estimators.yang import YangParams
from altfusion.sensors.faults import PASSED_SIGNALS, STREAMS
from altfusion.systems.error_models import FLAT_TERRAIN
from altfusion.systems.plant import plant_components, plant_connections
from altfusion.systems.sensors import SEED_003_SENSORS, sensor_components, sensor_connections
from altfusion.systems.spec import ComponentSpec, Connection, Metric, SystemSpec
from altfusion.systems.wiring import estimator_connections

FAULT_COMPONENT = "fault"
FAULT_FMU = "SensorFaults"


@dataclass(frozen=True)
class FaultScenario:
    """One scenario of the fault suite.

    ``start``: time the fault the estimator must cope with begins, s (SensorFaults'
    ``fault_start``); ``needs``: sensor sources the system must have; ``faulty``: sources an
    estimator is expected to isolate (time to isolate counts from ``start``); ``transient``:
    time after ``start`` excluded from the coverage and recovery windows, s (the faults'
    duration plus 10 s to isolate and 30 s to recover); ``truth``: truth inputs the fault
    needs (``h`` from ``plant.h``, ``thrust`` from ``controller.thrust``); ``parameters``:
    SensorFaults parameters other than the defaults, fitting the scenario into the 300 s of
    :func:`fault_flight`."""

    name: str
    description: str
    origin: str
    start: float
    needs: tuple[str, ...] = ()
    faulty: tuple[str, ...] = ()
    transient: float = 0.0
    truth: tuple[str, ...] = ()
    parameters: dict[str, Any] = field(default_factory=dict)


ISOLATE_AND_RECOVER = 40.0
"""10 s to isolate a faulty source plus 30 s for the error to return (docs/faults.md)."""

FAULTS: dict[str, FaultScenario] = {f.name: f for f in (
    FaultScenario("baro_step", "baro height +200 m from 130 s, and stays (failed sensor)",
                  "PX4 EKF2 test_EKF_height_fusion (baro jump: baro dropped, GNSS takes over "
                  "within 10 s)", 130.0, ("baro",), ("baro",), ISOLATE_AND_RECOVER),
    FaultScenario("baro_drift", "baro drifts +5 m over 100 s from 130 s, on a warm-up drift "
                  "of 9 m over the first 10 min",
                  "PX4 gpsRef test (estimate within 1 m of GNSS over 100 s); ArduPilot issue "
                  "#2022", 130.0, ("baro",), (), 100.0),
    FaultScenario("gnss_step", "GNSS height +6 m from 80 s, +100 m more from 140 s; both stay",
                  "PX4 test (reset to GNSS within 10 s when GNSS is the reference); PX4 issue "
                  "#21820 (6 m jump, crash)", 140.0, ("gps",), ("gps",), ISOLATE_AND_RECOVER),
    FaultScenario("gnss_outage_return_off", "no GNSS fix from 50 s to 150 s (the spec's "
                  "10 min shortened to the flight), then 50 m off",
                  "PX4 gpsRefDeadReckoningStopRestartInconsistent (not re-admitted, baro bias "
                  "frozen)", 150.0, ("gps",), ("gps",), ISOLATE_AND_RECOVER,
                  parameters={"gps_outage": 100.0}),
    FaultScenario("failover", "GNSS stops at 130 s, baro at 170 s, range sensors at 210 s",
                  "PX4 baroRefFailOver / gpsRefFailOver (reference hands over within 10 s "
                  "each time)", 130.0, ("gps", "baro"), (), 80.0 + ISOLATE_AND_RECOVER),
    FaultScenario("all_fail", "GNSS +10 m and baro +5 m together from 130 s",
                  "PX4 *AllHgtFailReset (exactly one height reset, within 0.2 m)", 130.0,
                  ("gps", "baro"), (), ISOLATE_AND_RECOVER),
    FaultScenario("silent", "every sensor stops at 130 s",
                  "h_valid false within the aiding timeout (PX4: 5 s)", 130.0, (), (),
                  ISOLATE_AND_RECOVER),
    FaultScenario("wild_sample", "from 20 s, every 5 s, one absurd sample in each input in "
                  "turn (height 1100 m, 1e308, acc_z 1000 m/s², gps_vz 100 m/s, a GNSS stamp "
                  "of 1e308 s)", "gating; our own probes", 20.0, (), (), 45.0 + 30.0),
    FaultScenario("acc_bias", "accelerometer bias of 0.1-0.4 m/s² (seeded draw) from the "
                  "start; readings clipping at ±16 g for 1 s at 150 s",
                  "PX4 test_EKF_accelerometer (bias learnt to ±0.03 m/s² in 60 s; "
                  "bad_acc_vertical)", 0.0, ("acc",), (), 60.0),
    FaultScenario("ground_effect", "baro error +2 m near the ground at take-off, -4 m at "
                  "landing (full within 1 m, none above 3 m)",
                  "PX4 EKF2_GND_EFF_DZ; PX4 PR #26655 (15 of 20 logs positive); ArduPilot "
                  "GNDEFF_ALT", 0.0, ("baro",), (), 0.0, ("h",)),
    FaultScenario("prop_wash", "baro error proportional to thrust (7 m at full thrust)",
                  "PX4 PR #26924 (r = 0.91)", 0.0, ("baro",), (), 0.0, ("thrust",)),
    FaultScenario("range_terrain", "range sensors over a 3 m box (20-25 s), stuck (30-35 s), "
                  "reading 0.05 m flagged valid (40-45 s), in the 15 m hover",
                  "PX4 issues #9583, #27110; ArduPilot #13379", 20.0, ("laser",), (),
                  25.0 + 30.0),
    FaultScenario("weather_front", "sea-level pressure falls 3 hPa within an hour (about "
                  "25 m of baro height; 2 m over the flight)",
                  "bao2017 (drift), hajiyev (changing p0/T0)", 0.0, ("baro",), (), 0.0),
    FaultScenario("early_late_samples", "GNSS and radar samples stamped 0.05 s ahead of the "
                  "consumer's clock, baro, accelerometer and laser 0.02 s behind",
                  "ECOS behaviour on our systems", 0.0, (), (), 0.0),
)}
"""The fault suite in docs/faults.md order, timed for :func:`fault_flight`."""

TRUTH_SOURCES = {"h": "plant.h", "thrust": "controller.thrust"}
"""Where :func:`with_fault` takes the truth inputs of SensorFaults from."""


def _producers(spec: SystemSpec) -> dict[str, str]:
    """Passed signal -> the 'component.variable' output feeding it in ``spec``."""
    producers: dict[str, str] = {}
    for connection in spec.connections:
        variable = connection.start.partition(".")[2]
        if variable in PASSED_SIGNALS:
            known = producers.setdefault(variable, connection.start)
            if known != connection.start:
                raise ValueError(f"system {spec.name}: both {known} and {connection.start} "
                                 f"feed '{variable}'; cannot insert one fault component")
    return producers


def fault_parameters(fault: str) -> dict[str, Any]:
    """The SensorFaults parameters of scenario ``fault`` (``"none"``: no fault, every stream
    passed through unchanged, for a nominal run of a system that has the component)."""
    if fault == "none":
        return {"scenario": "none"}
    scenario = FAULTS[fault]
    return {"scenario": fault, "fault_start": scenario.start, **scenario.parameters}


def run_parameters(fault: str) -> dict[str, Any]:
    """The parameter overrides {'fault.<name>': value} that switch a system built by
    :func:`with_fault` (with any scenario) to scenario ``fault`` for one run, so that one
    instantiated simulation flies every scenario."""
    return {f"{FAULT_COMPONENT}.{name}": value for name, value in fault_parameters(fault).items()}


def with_fault(spec: SystemSpec, fault: str) -> SystemSpec:
    """``spec`` with fault scenario ``fault`` applied by a SensorFaults component named
    ``fault`` between the sensor outputs and every input they drove, named
    ``"<spec.name>+<fault>"``; ValueError for an unknown fault, one that needs a sensor or a
    truth signal the system lacks, or a system that has a fault already."""
    if fault not in FAULTS:
        raise ValueError(f"unknown fault {fault!r}; known: {', '.join(FAULTS)}")
    scenario = FAULTS[fault]
    names = {c.name for c in spec.components}
    if FAULT_COMPONENT in names:
        raise ValueError(f"system {spec.name} has a '{FAULT_COMPONENT}' component already")
    producers = _producers(spec)
    present = {prefix for prefix in STREAMS if f"{prefix}_count" in producers}
    missing = [source for source in scenario.needs if source not in present]
    if missing:
        raise ValueError(f"fault {fault} needs the {' and '.join(missing)} sensor(s) "
                         f"feeding a consumer, which system {spec.name} lacks (sensor streams "
                         f"it connects: {', '.join(sorted(present)) or 'none'})")
    truth = {name: source for name, source in TRUTH_SOURCES.items()
             if source.partition(".")[0] in names}
    lacking = [TRUTH_SOURCES[name] for name in scenario.truth if name not in truth]
    if lacking:
        raise ValueError(f"fault {fault} needs {', '.join(lacking)}, which system {spec.name} "
                         f"lacks")
    connections = []
    for connection in spec.connections:
        variable = connection.start.partition(".")[2]
        if variable in producers:
            connection = replace(connection, start=f"{FAULT_COMPONENT}.{variable}")
        connections.append(connection)
    connections += [Connection(source, f"{FAULT_COMPONENT}.raw_{variable}")
                    for variable, source in producers.items()]
    connections += [Connection(source, f"{FAULT_COMPONENT}.{name}")
                    for name, source in truth.items()]
    component = ComponentSpec(FAULT_COMPONENT, FAULT_FMU, spec.base_step,
                              fault_parameters(fault))
    return replace(spec, name=f"{spec.name}+{fault}",
                   description=f"{spec.description}; fault {fault}: {scenario.description}",
                   components=(*spec.components, component), connections=tuple(connections),
                   record=(*spec.record, f"{FAULT_COMPONENT}.fault_active"))


# ---------------------------------------------------------------------- the flight
STOP_TIME = 300.0
BASE_STEP = 0.05
OUTPUT_INTERVAL = 0.1
SENSOR_STEPS = {"gnss": 0.1, "radar": 0.2}
FAST_SENSORS = ("air_data", "accelerometer", "laser")
SENSORS = {**SEED_003_SENSORS, **{name: {**SEED_003_SENSORS.get(name, {}),
                                         "sample_period": BASE_STEP} for name in FAST_SENSORS}}
"""yang2020's sensors (Section 4.2), the baro, accelerometer and laser sampled at 20 Hz
instead of 100 Hz: the suite runs 15 flights of 15 FMUs, and the base step sets its time
(the runner's and the FMUs' cost is per step: about 1 ms per base step here)."""

BARO_VARIANCE = SEED_003_SENSORS["air_data"]["height_noise_std"] ** 2
GPS_VARIANCE = SEED_003_SENSORS["gnss"]["user_range_error"] ** 2
BARO_BIAS_PSD = BaselineKFParams().bias_psd
"""The baro-bias random walk the estimators are told on this flight, m²/s: BaselineKF's
default (its baro does not drift, its atmosphere has no weather; the faults' drifts, 5 m in
100 s and 9 m in 10 min, stay within it). whang2008's weather (Whang's default Q_b, 2000 m²/s)
and hajiyev's drift (Hajiyev's default drift_psd, 1 m²/s) are not this flight's."""
TRUE_NOISE: dict[str, dict[str, Any]] = {
    "BaselineKF": {"R_baro": BARO_VARIANCE, "R_gps": GPS_VARIANCE},
    "HajiyevAdaptiveEstimator": {"R_baro": BARO_VARIANCE, "R_gps": GPS_VARIANCE,
                                 "drift_psd": BARO_BIAS_PSD},
    "WhangGAEstimator": {"R_baro": BARO_VARIANCE, "R_gps": GPS_VARIANCE,
                         "Q_b": BARO_BIAS_PSD * WhangParams().adm_period},
    "BaoDriftEstimator": {"R_baro": BARO_VARIANCE, "R_gps": GPS_VARIANCE,
                          "user_range_error": SEED_003_SENSORS["gnss"]["user_range_error"],
                          "R_worst": 4.0 * GPS_VARIANCE},
    "YangFusionKF": {"gps_bias_psd": YangParams().baro_bias_psd},
    "XuSHAEKF": {"R_baro": BARO_VARIANCE, "R_gps": GPS_VARIANCE,
                 "acc_noise_std": SEED_003_SENSORS["accelerometer"]["noise_std"]},
    "AltitudeEKF": {"baro_noise": BARO_VARIANCE**0.5, "gps_noise": GPS_VARIANCE**0.5,
                    "gps_vz_noise": SEED_003_SENSORS["gnss"]["velocity_noise_std"],
                    "acc_noise": SEED_003_SENSORS["accelerometer"]["noise_std"],
                    "radar_noise": SEED_003_SENSORS["radar"]["noise_std"],
                    "laser_noise": 0.005, **FLAT_TERRAIN, "height_ref": "range"},
}
"""The fault suite's settings of each estimator: its noise parameters set to the flight's
sensors and the flight's error models (``altfusion evaluate --told noise`` tells only the
former, :func:`altfusion.evaluation.told.split_noise`). The noises are yang2020's (Section 4.2:
baro 20 m, GPS 30 m, accelerometer 0.01 m/s²; YangFusionKF's defaults are these already;
the laser keeps its 5 mm, XuSHAEKF's default; AltitudeEKF takes all of them by their
contract names). BaoDriftEstimator's worst accepted GNSS
variance R_worst (eq. 14) is (2σ)² of the GPS. The flight is over flat terrain at 0 m
(``range_terrain``'s box is a fault): YangFusionKF's ``terrain_h`` is that 0 m, and AltitudeEKF
is told the same (``error_models.FLAT_TERRAIN``, as in the paper scenarios), so its radio
altimeter measures the height, not a terrain it would have to learn against the 30 m GNSS
(nominal RMS 1.24 m without, 0.57 m with it). Over that known terrain the radio altimeter,
in range for the whole flight, is the one absolute height without a bias of its own, so
AltitudeEKF takes it as its height reference (``height_ref`` range, PX4's EKF2_HGT_REF
range): the baro and the GNSS each get an offset state, and a GNSS off by 10 m within its
30 m noise (``all_fail``) is taken up by its offset instead of entering the height with its
weight against the radar (0.54 m RMS after it against 1.00 m with the GNSS as reference).
YangFusionKF gets its GPS-offset state for the same reason (``gps_bias_psd``, at the rate of
its baro offset's walk: 0.46 m RMS after ``all_fail`` against 0.82 m without).
The baro-bias walks of WhangGAEstimator (Q_b; default whang2008's weather, a lapse rate
redrawn every 10 s, 400 m² per air-data step) and HajiyevAdaptiveEstimator (``drift_psd``;
default hajiyev's 1 m/s drift, 1 m²/s) are the flight's, :data:`BARO_BIAS_PSD` (Whang's per
air-data step: 0.01 m²). Under the paper's 2000 m²/s Whang's bias moves 70 m (1σ) within the
bias test's 2.5 s: a 100 m GNSS or 200 m baro step is absorbed within 0.5 s, no fault (106 m
RMS after gnss_step). Under hajiyev's 1 m²/s Hajiyev's reference for the GPS-minus-baro
residual is uncertain by 10.5 m after the 100 s outage of ``gnss_outage_return_off``, so a GNSS
back 50 m off is at most 3.9 standard deviations over the bias test's 2.5 s and not isolated
(47 m RMS after it); with the flight's walk it is isolated 3 s after it returns."""

ESTIMATOR_RECORD = ("h_est", "vz_est", "h_std", "h_valid", "status", "n_height_resets")


def estimator_record(fmu: str) -> tuple[str, ...]:
    """What :func:`fault_flight` records of estimator ``fmu``: estimate, health, test
    ratios."""
    core = ESTIMATOR_CLASSES[fmu]
    ratios = tuple(f"{source}_test_ratio" for source in core.sources())
    return tuple(f"{fmu}.{name}" for name in (*ESTIMATOR_RECORD, *ratios))


def fault_flight(estimators: tuple[str, ...] = tuple(ESTIMATOR_CLASSES)) -> SystemSpec:
    """The fault suite's generic flight (module docstring) with ``estimators`` (FMU model
    names) side by side, each a component named after its FMU."""
    unknown = [name for name in estimators if name not in ESTIMATOR_CLASSES]
    if unknown:
        raise ValueError(f"unknown estimators {unknown}; known: {list(ESTIMATOR_CLASSES)}")
    components = (
        plant_components("fault_flight", step=BASE_STEP)
        + sensor_components(step=BASE_STEP, parameters=SENSORS, steps=SENSOR_STEPS)
        + tuple(ComponentSpec(name, name, BASE_STEP, dict(TRUE_NOISE.get(name, {})))
                for name in estimators))
    connections = (plant_connections() + sensor_connections()
                   + sum((estimator_connections(ESTIMATOR_CLASSES[name], name)
                          for name in estimators), ()))
    return SystemSpec(
        name="fault_flight",
        description="The fault suite's flight, closed on the true altitude: take-off to a "
                    "15 m hover, climb to a 120 m cruise, descent and landing in 300 s; "
                    "baro 20 m at 20 Hz, GPS 30 m / 0.2 m/s at 10 Hz, radio altimeter 10 m at "
                    "5 Hz, accelerometer 0.01 m/s² at 20 Hz (yang2020's noise), laser 5 mm "
                    "at 20 Hz; estimators at 20 Hz: " + ", ".join(estimators),
        components=components, connections=connections, stop_time=STOP_TIME,
        base_step=BASE_STEP, output_interval=OUTPUT_INTERVAL,
        record=("plant.h", "plant.vz", "controller.thrust",
                *(signal for name in estimators for signal in estimator_record(name))),
        metrics=tuple(Metric(f"{name} error", f"{name}.h_est", "plant.h")
                      for name in estimators),
    )
