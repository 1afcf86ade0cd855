"""The metrics of ``altfusion evaluate`` and its n/a rules, on synthetic series."""

import math
from pathlib import Path

import numpy as np
import pytest

from altfusion.estimators.altitude_ekf import AltitudeEKF
from altfusion.estimators.bao import BaoDriftEstimator
from altfusion.estimators.baseline import BaselineKF
from altfusion.estimators.hajiyev import HajiyevAdaptiveEstimator
from altfusion.estimators.health import SourceBit, Status, source_bit
from altfusion.estimators.whang import WhangGAEstimator
from altfusion.estimators.xu import XuSHAEKF
from altfusion.estimators.yang import YangFusionKF
from altfusion.evaluation.metrics import (
    RECOVERY_WINDOW,
    Fault,
    Series,
    coverage,
    max_abs,
    rms,
    run_metrics,
    summarize,
    time_to_isolate,
    time_to_recover,
    trailing_rms,
    valid_fraction,
)
from altfusion.evaluation.scenarios import (
    NOISE_NAMES,
    PAPER_SCENARIOS,
    EstimatorInfo,
    error_parameters,
    noise_parameters,
    not_applicable,
)
from altfusion.evaluation.told import misstate, split_noise
from altfusion.systems.error_models import FLAT_TERRAIN, SENSOR_ERRORS
from altfusion.systems.faults import BARO_BIAS_PSD, BARO_VARIANCE, GPS_VARIANCE, TRUE_NOISE

DT = 0.1
TIME = np.round(np.arange(0.0, 300.0 + DT / 2, DT), 10)
INITIALIZED = int(Status.INITIALIZED)


def series(error, h_std=1.0, valid=True, status=INITIALIZED) -> Series:
    full = np.broadcast_to
    return Series(TIME, np.asarray(error, dtype=float) * np.ones_like(TIME),
                  full(np.asarray(h_std, dtype=float), TIME.shape).copy(),
                  full(np.asarray(valid, dtype=float), TIME.shape).copy(),
                  full(np.asarray(status), TIME.shape).astype(np.int64))


def estimator(core) -> EstimatorInfo:
    return EstimatorInfo(core.__name__, Path(f"{core.__name__}.fmu"), core,
                         frozenset(core.Params.__dataclass_fields__))


def test_rms_and_max_ignore_the_rows_before_initialization():
    error = np.where(TIME < 10.0, 1e4, 3.0)
    error[TIME == 200.0] = -5.0
    status = np.where(TIME < 10.0, 0, INITIALIZED)
    s = series(error, status=status)
    rows = np.count_nonzero(TIME >= 10.0)
    assert rms(s) == pytest.approx(math.sqrt((9.0 * (rows - 1) + 25.0) / rows))
    assert max_abs(s) == 5.0


def test_coverage_counts_errors_within_two_h_std_outside_the_transient():
    # |e| = 1.5 h_std everywhere except 2.5 h_std in [100, 150): 50 s of 300 s outside.
    error = np.where((TIME >= 100.0) & (TIME < 150.0), 2.5, 1.5)
    s = series(error)
    outside = 1.0 - np.count_nonzero((TIME >= 100.0) & (TIME < 150.0)) / TIME.size
    assert coverage(s) == pytest.approx(outside)
    assert coverage(s, Fault(100.0, (), 50.0)) == 1.0
    assert coverage(s, Fault(100.0, (), 20.0)) < 1.0


def test_valid_fraction():
    assert valid_fraction(series(0.0, valid=TIME < 75.0)) == pytest.approx(
        np.count_nonzero(TIME < 75.0) / TIME.size)


def test_time_to_isolate_is_the_first_isolated_row_after_the_fault_start():
    isolated = source_bit("baro", SourceBit.ISOLATED)
    status = np.where(TIME >= 137.0, INITIALIZED | isolated, INITIALIZED)
    fault = Fault(130.0, ("baro",), 40.0)
    assert time_to_isolate(series(0.0, status=status), fault, ("baro", "gps")) \
        == pytest.approx(7.0)
    assert time_to_isolate(series(0.0), fault, ("baro", "gps")) == math.inf
    assert time_to_isolate(series(0.0, status=status), fault, ("gps",)) is None
    # An isolation before the fault (a false alarm) is not the fault's isolation.
    early = np.where((TIME >= 50.0) & (TIME < 60.0) | (TIME >= 140.0),
                     INITIALIZED | isolated, INITIALIZED)
    assert time_to_isolate(series(0.0, status=early), fault, ("baro",)) == pytest.approx(10.0)


def test_time_to_isolate_two_faulty_sources_waits_for_both():
    baro, gps = (source_bit(s, SourceBit.ISOLATED) for s in ("baro", "gps"))
    status = INITIALIZED | np.where(TIME >= 132.0, baro, 0) | np.where(TIME >= 135.0, gps, 0)
    assert time_to_isolate(series(0.0, status=status), Fault(130.0, ("baro", "gps")),
                           ("baro", "gps")) == pytest.approx(5.0)


def test_trailing_rms_over_the_window():
    error = np.where(TIME >= 100.0, 2.0, 0.0)
    window = trailing_rms(TIME, error, RECOVERY_WINDOW)
    assert window[TIME.searchsorted(99.9)] == 0.0
    assert window[TIME.searchsorted(110.0)] == pytest.approx(2.0)
    # one 2.0 sample among the 20 rows of the 2 s window ending at 100.0
    assert window[TIME.searchsorted(100.0)] == pytest.approx(math.sqrt(4.0 / 20))


def test_time_to_recover_counts_to_the_end_of_the_last_bad_window():
    nominal = 1.0
    # 200 m off from 130 s, back to 0.5 m (within 3x the nominal RMS) from 150 s: the
    # trailing 2 s window is clean from 152 s on.
    error = np.where((TIME >= 130.0) & (TIME < 150.0), 200.0, 0.5)
    fault = Fault(130.0, ("baro",), 40.0)
    recovered = time_to_recover(series(error), fault, nominal)
    assert recovered == pytest.approx(150.0 + RECOVERY_WINDOW - 130.0, abs=DT + 1e-9)
    assert time_to_recover(series(0.5), fault, nominal) == 0.0
    stuck = np.where(TIME >= 130.0, 200.0, 0.5)
    assert time_to_recover(series(stuck), fault, nominal) == math.inf
    # Declared invalid while off: no failure to recover (the fault suite's "or h_valid false").
    assert time_to_recover(series(stuck, valid=TIME < 135.0), fault, nominal) \
        == pytest.approx(5.0, abs=DT + 1e-9)
    assert time_to_recover(series(stuck), fault, math.nan) is None


def test_run_metrics_leave_the_fault_metrics_out_without_a_fault():
    metrics = run_metrics(series(1.0, h_std=1.0))
    assert (metrics.rms, metrics.coverage, metrics.valid_fraction) == (1.0, 1.0, 1.0)
    assert metrics.time_to_isolate is None and metrics.time_to_recover is None


def test_summaries_count_the_runs_with_a_finite_value():
    assert summarize([None, None]) is None
    summary = summarize([2.0, 4.0, math.inf])
    assert (summary.mean, summary.finite, summary.runs) == (3.0, 2, 3)
    assert summary.std == pytest.approx(math.sqrt(2.0))
    assert summary.format(unit="s") == "3 ± 1.41 s (n=2 of 3)"
    assert summarize([math.inf]).format() == "never"
    assert summarize([0.9, 0.95]).format(percent=True) == "92.5 ± 3.5 % (n=2)"


def test_an_estimator_driven_by_the_accelerometer_is_na_without_one():
    reason = not_applicable(estimator(XuSHAEKF), {"baro", "gps"})
    assert reason is not None and "acc" in reason
    assert not_applicable(estimator(XuSHAEKF), {"baro", "gps", "acc"}) is None


def test_a_partially_provided_estimator_runs_on_what_it_reads():
    assert not_applicable(estimator(YangFusionKF), {"baro", "gps"}) is None


def test_an_estimator_without_a_height_sensor_it_reads_is_na():
    reason = not_applicable(estimator(BaselineKF), {"laser", "acc"})
    assert reason is not None and "no height sensor" in reason


def test_a_fault_on_sensors_the_estimator_does_not_read_is_na():
    reason = not_applicable(estimator(BaselineKF), {"baro", "gps", "laser"}, ("laser",))
    assert reason is not None and "laser" in reason
    assert not_applicable(estimator(BaselineKF), {"baro", "gps"}, ("baro",)) is None


def test_true_noise_goes_to_the_parameters_each_estimator_has():
    noise = {"baro_noise": 0.5, "gps_noise": 3.0, "gps_vz_noise": 0.2, "acc_noise": 0.05,
             "laser_noise": 0.0}
    assert noise_parameters(estimator(BaselineKF), noise) == {"R_baro": 0.25, "R_gps": 9.0}
    xu = noise_parameters(estimator(XuSHAEKF), noise)
    assert xu == {"R_baro": 0.25, "R_gps": 9.0, "acc_noise_std": 0.05,
                  "R_laser": pytest.approx(1e-6)}
    yang = noise_parameters(estimator(YangFusionKF), noise)
    assert yang["R_gps_vz"] == pytest.approx(0.04) and yang["R_acc"] == pytest.approx(0.0025)


def test_the_vdop_a_gps_noise_holds_at_goes_with_it():
    """xu2016's GNSS: 3 m at VDOP 1.5. AltitudeEKF, which scales its GNSS noise by
    VDOP/gps_vdop_ref, is told both (it would take 4.5 m at its default reference of 1);
    an estimator without the parameter gets the noise alone; misstated, the noise is
    scaled and its VDOP is not."""
    noise = {"baro_noise": 0.5, "gps_noise": 3.0, "gps_vdop_ref": 1.5}
    told = noise_parameters(estimator(AltitudeEKF), noise)
    assert told == {"baro_noise": 0.5, "gps_noise": 3.0, "gps_vdop_ref": 1.5}
    assert noise_parameters(estimator(BaselineKF), noise) == {"R_baro": 0.25, "R_gps": 9.0}
    assert misstate(told, 5.0) == {"baro_noise": 2.5, "gps_noise": 15.0, "gps_vdop_ref": 1.5}


def test_the_fault_suites_settings_split_into_noises_and_error_models():
    """Told only the noise, an estimator in the fault flight gets the suite's noises, not its
    terrain, height reference or walks (error models, as in a paper scenario)."""
    noise, models = split_noise(TRUE_NOISE["AltitudeEKF"])
    assert set(noise) == {"baro_noise", "gps_noise", "gps_vz_noise", "acc_noise",
                          "radar_noise", "laser_noise"}
    assert models == {**FLAT_TERRAIN, "height_ref": "range"}
    assert split_noise(TRUE_NOISE["HajiyevAdaptiveEstimator"]) == (
        {"R_baro": BARO_VARIANCE, "R_gps": GPS_VARIANCE}, {"drift_psd": BARO_BIAS_PSD})
    assert split_noise(TRUE_NOISE["YangFusionKF"])[0] == {}
    assert split_noise({"gps_noise": 3.0, "gps_vdop_ref": 1.5}) == (
        {"gps_noise": 3.0, "gps_vdop_ref": 1.5}, {})


def test_every_paper_scenario_states_error_models_an_estimator_can_take():
    """The table of stated sensor error models covers every paper scenario, and each name is
    a parameter of some estimator (a misspelt name would silently reach none)."""
    parameters = set().union(*(estimator(core).parameters for core in (
        AltitudeEKF, BaselineKF, XuSHAEKF, YangFusionKF)))
    assert set(PAPER_SCENARIOS) <= set(SENSOR_ERRORS)
    for errors in SENSOR_ERRORS.values():
        assert set(errors) <= parameters


def test_stated_error_models_go_to_every_estimator_with_that_parameter():
    errors = {"baro_bias_psd": 0.5, "terrain_h": 0.0, "P0_offset": 0.01, "baro_noise": 0.7}
    assert error_parameters(estimator(AltitudeEKF), errors) == {
        "baro_bias_psd": 0.5, "terrain_h": 0.0, "P0_offset": 0.01}
    assert error_parameters(estimator(XuSHAEKF), errors) == {"baro_bias_psd": 0.5,
                                                             "terrain_h": 0.0}
    assert "baro_noise" in NOISE_NAMES           # a restated noise goes as the noises go


def test_a_stated_error_model_reaches_the_parameter_of_the_same_quantity_under_another_name():
    """The random walk of baro_h's error is BaselineKF's bias_psd and Hajiyev's drift_psd
    (m²/s each); Bao and Whang, which compute their own height from the pressure, keep
    their walks (docs/montecarlo.md)."""
    errors = {"baro_bias_psd": 0.5, "baro_scale_psd": 1e-6, "terrain_h": 0.0}
    assert error_parameters(estimator(BaselineKF), errors) == {"bias_psd": 0.5}
    assert error_parameters(estimator(HajiyevAdaptiveEstimator), errors) == {"drift_psd": 0.5}
    assert error_parameters(estimator(BaoDriftEstimator), errors) == {}
    assert error_parameters(estimator(WhangGAEstimator), errors) == {}
    assert error_parameters(estimator(BaselineKF), {"terrain_h": 0.0}) == {}
