"""Robustness of every estimator FMU, driven through fmpy with synthetic sensor streams:
GPS outage, non-finite inputs, a 100 m GPS outlier, bad parameters, state save/restore."""

import math

import numpy as np
import pytest
from state_restore import assert_restores_identically

from altfusion.cosim.instances import CosimError, FmuInstance, fmu_info
from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.bao import BaoDriftEstimator
from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.hajiyev import HajiyevAdaptiveEstimator
from altfusion.estimators.health import SourceBit, Status, source_bit
from altfusion.estimators.whang import WhangGAEstimator
from altfusion.estimators.xu import XuSHAEKF
from altfusion.estimators.yang import YangFusionKF

ESTIMATORS = ("BaselineKF", "HajiyevAdaptiveEstimator", "WhangGAEstimator",
              "BaoDriftEstimator", "YangFusionKF", "XuSHAEKF", "AltitudeEKF")
STEP = 0.2
TRUTH = 1000.0
GPS_EVERY = 5


class Harness:
    """One estimator FMU instance fed, at a static TRUTH, with every stream it declares: every
    0.2 s a baro sample (20 m off, σ 3 m, with temperature and pressure), an accelerometer
    sample (σ 0.05 m/s²), a radio-altimeter sample (σ 10 m) and a laser frame (out of range:
    invalid, reading 0); every 1 s a GPS sample (σ 10 m, vertical speed σ 0.2 m/s, VDOP 1,
    8 satellites); and a gusty wind speed."""

    def __init__(self, fmu, parameters=None, seed=0):
        self.info = fmu_info(fmu)
        self.instance = FmuInstance("estimator", self.info)
        self.instance.initialize(parameters or {}, STEP, 0.0, 1e6)
        self.instance.exit_initialization()
        self.rng = np.random.default_rng(seed)
        self.n = 0
        self.counts = dict.fromkeys(("baro", "gps", "acc", "radar", "laser"), 0)
        self.inputs = {n for n, v in self.info.variables.items() if v.causality == "input"}
        self.bad = math.nan

    def set(self, name, value):
        var = self.info.variables[name]
        self.instance.set(var.type, [var.value_reference], [value])

    def get(self, name):
        var = self.info.variables[name]
        return self.instance.get(var.type, [var.value_reference])[0]

    def samples(self, gps: bool, gps_value: float | None) -> tuple[dict, float]:
        """This step's samples by stream, and the wind speed. All noise is drawn at every
        step, whatever is delivered, so twin harnesses stay in step."""
        noise = self.rng.standard_normal(7)
        t = (self.n + 1) * STEP
        samples = {
            "baro": {"baro_h": TRUTH + 20.0 + 3.0 * noise[0], "baro_T": 281.65 + 0.5 * noise[1],
                     "baro_p": 89875.0 + 30.0 * noise[0], "baro_time": t},
            "acc": {"acc_z": 0.05 * noise[2], "acc_time": t},
            "radar": {"radar_h": TRUTH + 10.0 * noise[3], "radar_valid": True, "radar_time": t},
            "laser": {"laser_h": 0.0, "laser_valid": False, "laser_time": t},
        }
        if gps and self.n % GPS_EVERY == GPS_EVERY - 1:
            samples["gps"] = {
                "gps_h": TRUTH + 10.0 * noise[4] if gps_value is None else gps_value,
                "gps_vz": 0.2 * noise[5], "gps_vdop": 1.0, "gps_nsat": 8, "gps_time": t}
        return samples, 3.0 + noise[6]

    def step(self, gps=True, fix=True, bad=(), skip=(), gps_value=None, override=None):
        """One 0.2 s step. Streams (or ``wind_speed``) in ``bad`` deliver non-finite values in
        every Real variable; streams in ``skip`` deliver nothing; ``override`` replaces sample
        values by name (``{"baro_h": 1100.0}``)."""
        samples, wind = self.samples(gps, gps_value)
        for values in samples.values():
            values.update({k: v for k, v in (override or {}).items() if k in values})
        for prefix, values in samples.items():
            if prefix in skip or f"{prefix}_count" not in self.inputs:
                continue
            self.counts[prefix] += 1
            for name, value in values.items():
                if name in self.inputs:
                    bad_real = prefix in bad and self.info.variables[name].type == "Real"
                    self.set(name, self.bad if bad_real else value)
            self.set(f"{prefix}_count", self.counts[prefix])
        if "wind_speed" in self.inputs and "wind_speed" not in skip:
            self.set("wind_speed", self.bad if "wind_speed" in bad else wind)
        self.set("gps_fix", fix)
        self.instance.do_step(self.n * STEP, STEP)
        self.n += 1
        return {name: self.get(name) for name in ("h_est", "vz_est", "h_std")}

    def health(self) -> dict:
        """The health outputs: h_valid, status and every ``<source>_test_ratio`` and
        ``<source>_rejected``."""
        return {name: self.get(name) for name in self.info.variables
                if name in ("h_valid", "status") or name.endswith(("_test_ratio", "_rejected"))}

    def free(self):
        self.instance.free()


# A good GPS (σ 10 m) makes a 100 m outlier a 10-sigma event. Whang's paper tuning lets the
# bias wander 20 m per air-data step (Q_b = 400 m²), which makes any GPS jump plausible, so
# the outlier test gives it a bias random walk that matches this steady scene. Bao, Yang and
# Xu are told this scene's GPS accuracy (and the baro noise where their h_std includes it);
# Bao corrects the wind; Xu expects a baro constant error of tens of metres, AltitudeEKF
# (every noise of this scene) a baro offset of σ 30 m.
TUNING = {"BaselineKF": {"R_gps": 100.0}, "HajiyevAdaptiveEstimator": {},
          "WhangGAEstimator": {"R_gps": 100.0, "Q_b": 0.04},
          "BaoDriftEstimator": {"user_range_error": 10.0, "R_gps": 100.0, "R_baro": 9.0,
                                "use_wind": True},
          "YangFusionKF": {"R_gps": 100.0},
          "XuSHAEKF": {"R_gps": 100.0, "R_baro": 9.0, "baro_bias_std": 30.0},
          "AltitudeEKF": {"gps_noise": 10.0, "baro_noise": 3.0, "acc_noise": 0.05,
                          "radar_noise": 10.0, "P0_offset": 900.0}}


@pytest.fixture(params=ESTIMATORS)
def harness(request, fmus):
    h = Harness(fmus[request.param], TUNING[request.param])
    yield h
    h.free()


def test_gps_outage_of_60_s_keeps_estimates_finite_grows_h_std_and_recovers(harness):
    before = [harness.step() for _ in range(300)]
    during = [harness.step(gps=False, fix=False) for _ in range(300)]  # 60 s without GPS
    assert all(math.isfinite(v) for out in during for v in out.values())
    # honest: the filter's own uncertainty grows while the absolute reference is missing
    assert during[-1]["h_std"] > 1.05 * during[0]["h_std"]
    after = [harness.step() for _ in range(300)][-1]
    # recovered: within 3σ of its own std, never required closer than one GPS σ (10 m), and
    # the std back within 10 % of its level before the outage (a Kalman filter's P returns to
    # the same steady state; 60 s of GPS again are many of its time constants)
    assert abs(after["h_est"] - TRUTH) < max(3.0 * after["h_std"], 10.0)
    assert after["h_std"] <= 1.1 * max(out["h_std"] for out in before[-150:])


NON_FINITE_CASES = [
    (name, streams) for name in ESTIMATORS for streams in (
        ("baro",), ("gps",), ("baro", "gps"),
        *{"BaoDriftEstimator": [("wind_speed",)], "YangFusionKF": [("acc",), ("radar",)],
          "XuSHAEKF": [("acc",)], "AltitudeEKF": [("acc",), ("radar",)]}.get(name, []))
]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
@pytest.mark.parametrize(("name", "streams"), NON_FINITE_CASES)
def test_non_finite_inputs_are_logged_ignored_and_never_propagate(fmus, name, streams, bad):
    """A non-finite sample (every Real of the stream, or the wind speed) must act exactly as no
    sample: a twin that receives nothing at that step ends bit-identical."""
    harness = Harness(fmus[name], TUNING[name], seed=9)
    twin = Harness(fmus[name], TUNING[name], seed=9)
    harness.bad = bad
    try:
        for _ in range(104):  # the next step carries a GPS sample
            harness.step()
            twin.step()
        harness.instance.warnings.clear()
        harness.step(bad=streams)
        twin.step(skip=streams)
        for _ in range(20):
            after, expected = harness.step(), twin.step()
        assert all(math.isfinite(v) for v in after.values())
        assert after == expected
        warnings = " ".join(harness.instance.warnings)
        assert all(f"{s}: non-finite sample ignored" in warnings for s in streams)
    finally:
        harness.free()
        twin.free()


@pytest.mark.parametrize("name", ESTIMATORS)
def test_a_100_m_gps_outlier_is_rejected_or_bounded_and_logged(fmus, name):
    """The estimate after a 100 m GPS outlier stays within 5 m of a twin's that received no
    GPS sample instead (equal if the outlier is rejected; the baro noise, which some
    estimators pass straight through, cancels out). 5 m is half the scene's GPS σ: an outlier
    that gets through moves the estimate less than half an ordinary sample's error."""
    harness = Harness(fmus[name], TUNING[name])
    twin = Harness(fmus[name], TUNING[name])
    try:
        for _ in range(300):
            harness.step()
            twin.step()
        harness.instance.warnings.clear()
        for _ in range(5):  # samples 300..304: the GPS at 304
            outlier = harness.step(gps_value=TRUTH + 100.0)
            expected = twin.step(skip=("gps",))
        assert any("rejected" in w for w in harness.instance.warnings)
        assert abs(outlier["h_est"] - expected["h_est"]) < 5.0
    finally:
        harness.free()
        twin.free()


@pytest.mark.parametrize("name", ESTIMATORS)
def test_invalid_parameters_are_rejected_at_initialization_by_name(fmus, name):
    # AltitudeEKF: the contract name, σ, where 0 means "not stated" (measured)
    parameter, bound = ("gps_noise", ">= 0") if name == "AltitudeEKF" else ("R_gps", "> 0")
    instance = FmuInstance("estimator", fmu_info(fmus[name]))
    try:
        instance.initialize({parameter: -1.0}, STEP, 0.0, 10.0)
        with pytest.raises(CosimError, match=rf"'{parameter}' = -1\.0: must be {bound}"):
            instance.exit_initialization()
    finally:
        instance.free()


@pytest.mark.parametrize("name", ESTIMATORS)
def test_state_save_and_restore_continue_bit_identically(fmus, name):
    harness = Harness(fmus[name], TUNING[name], seed=4)
    try:
        for _ in range(100):
            harness.step()
        rng_state = harness.rng.bit_generator.state
        n, counts = harness.n, dict(harness.counts)

        def continuation():
            harness.rng.bit_generator.state = rng_state
            harness.n, harness.counts = n, dict(counts)
            return [harness.step() for _ in range(100)]

        assert_restores_identically(harness.instance, continuation)
    finally:
        harness.free()


CORES = {"BaselineKF": BaselineKF, "HajiyevAdaptiveEstimator": HajiyevAdaptiveEstimator,
         "WhangGAEstimator": WhangGAEstimator, "BaoDriftEstimator": BaoDriftEstimator,
         "YangFusionKF": YangFusionKF, "XuSHAEKF": XuSHAEKF, "AltitudeEKF": AltitudeEKF}
"""The core class of each estimator FMU (which inputs it declares)."""

WILD_SAMPLES = [
    (name, value_name, value, counter) for name in ESTIMATORS for value_name, value, counter in (
        ("baro_h", 1100.0, None), ("baro_h", 1e308, "baro_rejected"),
        ("gps_time", 1e308, "gps_rejected"), ("acc_z", 1000.0, "acc_rejected"),
        ("gps_vz", 100.0, "gps_vz_rejected"), ("radar_h", 1100.0, "radar_rejected"))
    if value_name in CORES[name].declared_inputs()
    and (name, value_name, value) != ("WhangGAEstimator", "baro_h", 1100.0)
]
"""Every estimator's inputs; WhangGAEstimator's baro is ungated by design (FAILED_BARO), so
a plausible wild baro sample moves it by its alpha-beta gain (24 m for 80 m here)."""


@pytest.mark.parametrize(("name", "value_name", "value", "counter"), WILD_SAMPLES)
def test_a_wild_sample_is_refused_or_bounded_and_counted(fmus, name, value_name, value,
                                                         counter):
    """One absurd sample (issue 15: baro 1100 m or 1e308, acc_z 1000 m/s², gps_vz 100 m/s,
    gps_time 1e308) against a twin that receives the normal sample: over the next 10 s the
    estimates differ by at most 3 of the twin's h_std (a refused sample is one sample of
    information less, which the filter's own uncertainty covers; before the gates YangFusionKF
    ended 1970 m off after acc_z = 1000, and Whang and Xu crashed on 1e308). A value beyond
    its plausibility bound or gate is counted (``counter``); baro 1100 m is only 80 m from
    this scene's baro, inside the 5σ gates of the estimators that assume a 20 m baro."""
    harness = Harness(fmus[name], TUNING[name], seed=9)
    twin = Harness(fmus[name], TUNING[name], seed=9)
    try:
        for _ in range(104):  # the next step carries a GPS sample
            harness.step()
            twin.step()
        harness.step(override={value_name: value})
        twin.step()
        if counter is not None:
            assert harness.get(counter) == 1
        for _ in range(50):
            out, expected = harness.step(), twin.step()
            assert all(math.isfinite(v) for v in out.values())
            assert abs(out["h_est"] - expected["h_est"]) <= 3.0 * expected["h_std"]
    finally:
        harness.free()
        twin.free()


def test_h_valid_needs_initialization_and_a_height_sample_within_the_aiding_timeout(harness):
    """h_valid and the INITIALIZED / DEAD_RECKONING bits (docs/estimator_health.md): false
    before any sample, true while the heights are fused, false once no height sample came for
    more than aiding_timeout = 5 s (26 steps of 0.2 s = 5.2 s), true again after one."""
    assert not harness.get("h_valid") and harness.get("status") == 0
    for _ in range(50):
        harness.step()
    assert harness.get("h_valid")
    assert harness.get("status") & (Status.INITIALIZED | Status.DEAD_RECKONING) == 1
    silent = ("baro", "gps", "radar", "laser")
    for _ in range(24):
        harness.step(skip=silent)
    assert harness.get("h_valid")
    for _ in range(2):
        harness.step(skip=silent)
    assert not harness.get("h_valid")
    assert harness.get("status") & Status.DEAD_RECKONING
    for _ in range(5):
        harness.step()
    assert harness.get("h_valid")


FAILED_BARO = [name for name in ESTIMATORS if name != "WhangGAEstimator"]
"""WhangGAEstimator does not gate its baro: its paper scenario steps the baro height by up to
~100 m between samples (the weather), which its bias random walk is built to follow; with this
scene's tuning (Q_b = 0.04 m² per step) it follows a failed baro (docs/estimator_health.md)."""


@pytest.mark.parametrize("name", FAILED_BARO)
def test_a_failed_baro_is_isolated_while_the_gps_agrees(fmus, name):
    """Issue 15's failed barometer: +200 m from t = 100 s, GPS (σ 10 m) healthy. The baro is
    isolated within reset_timeout + one GPS period (2.5 + 1 s; asserted within 10 s, the fault
    suite's isolation time: an estimator with a baro-offset state re-admits it later with
    its new offset, estimators/base.py) and the error stays within 3x the nominal error
    bound of this scene, 3·(3 h_std) with the nominal h_std, for the last 60 s of 100 s
    after the fault (before: Hajiyev, Bao and Xu followed the baro, 200 m off)."""
    harness = Harness(fmus[name], TUNING[name], seed=3)
    try:
        nominal = [harness.step() for _ in range(500)][-1]
        step = {"override": {"baro_h": TRUTH + 220.0}}
        isolated = False
        for _ in range(50):
            harness.step(**step)
            isolated |= bool(harness.get("status") & source_bit("baro", SourceBit.ISOLATED))
        assert isolated
        errors = []
        for _ in range(500):
            errors.append(abs(harness.step(**step)["h_est"] - TRUTH))
        assert max(errors[200:]) <= 9.0 * nominal["h_std"]
        assert harness.get("h_valid")
    finally:
        harness.free()
