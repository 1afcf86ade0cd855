"""Flight-log replay through fmpy: LogReplay.fmu (with its bundled logs) feeding every
estimator FMU, on the real Auterion flight and the PX4 SITL sample."""

import math
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog
from ulog_mutation import shift_stamp, unknown_message_id, without_topic

from altfusion.cli import main
from altfusion.cosim import CosimError, read_ssp
from altfusion.cosim.results import Results
from altfusion.cosim.runner import Simulation
from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.health_events import events_csv, health_events
from altfusion.replay.compare import (
    compare_all,
    format_table,
    new_sample_rows,
    settle_time,
)
from altfusion.replay.run import declared_inputs, plan_replay, run_replay
from altfusion.signals import LOG_OUTPUTS
from altfusion.systems.replay import LOGS, REPLAY

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
LOG_DIR = ROOT / "tests" / "data" / "flightlogs"
ESTIMATORS = tuple(ESTIMATOR_CLASSES)
TOPICS = {"baro": "vehicle_air_data", "gps": "vehicle_gps_position", "acc": "sensor_combined",
          "laser": "distance_sensor", "ekf": "vehicle_local_position"}


@pytest.fixture(scope="module", params=sorted(LOGS))
def replayed(request, ssp_files):
    """(catalog system name, its results)."""
    loaded = read_ssp(ssp_files[request.param])
    with Simulation(loaded.spec, loaded.fmu_paths) as simulation:
        return request.param, simulation.run()


def test_every_estimator_runs_to_the_end_of_the_log_with_finite_outputs(replayed):
    name, results = replayed
    assert results.time[-1] == LOGS[name].stop_time
    for estimator in ESTIMATORS:
        for output in ("h_est", "vz_est", "h_std"):
            values = results[f"{estimator}.{output}"]
            assert np.all(np.isfinite(values)), f"{estimator}.{output}"
    replay_columns = [c for c in results.columns if c.startswith(f"{REPLAY}.")]
    assert all(np.all(np.isfinite(results[c])) for c in replay_columns)


def test_replay_counts_equal_the_samples_in_the_log(replayed):
    """Each stream delivers every sample of its topic once: the number of distinct time stamps
    in the file as pyulog reads it (neither log has duplicates or samples past its end; the
    unit tests cover duplicate removal)."""
    name, results = replayed
    ulog = ULog(str(LOG_DIR / LOGS[name].file), list(TOPICS.values()))
    topics = {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    for prefix, topic in TOPICS.items():
        expected = len(np.unique(topics[topic]["timestamp"])) if topic in topics else 0
        assert results[f"{REPLAY}.{prefix}_count"][-1] == expected, prefix
    assert results[f"{REPLAY}.radar_count"][-1] == 0


def test_catalog_replay_systems_connect_exactly_the_inputs_each_fmu_declares(ssp_files, fmus):
    for name in LOGS:
        spec = read_ssp(ssp_files[name]).spec
        for estimator in ESTIMATORS:
            connected = {c.end.split(".", 1)[1] for c in spec.connections
                         if c.end.startswith(f"{estimator}.")}
            provided = set(declared_inputs(fmus[estimator])) & set(LOG_OUTPUTS)
            assert connected == provided, (name, estimator)


LOG_NOISE = {"replay_auterion": (0.83, 0.59), "replay_px4_sitl": (0.70, 0.073)}
"""Each log's sensor noise as measured by the agreement test below (σ_G, σ_B, m): the bounds
come from the log itself, these figures pin what they are."""

UNHELD = {"replay_auterion": ("XuSHAEKF",)}
"""Estimators the agreement test does not hold to its bounds on a log, and why: on the
Auterion flight XuSHAEKF integrates the accelerometer as its input, and that log's vertical
acceleration is sampled at ~9 Hz with a vibration scatter of 8.7 m/s² (aliased rotor
vibration), far from the MEMS accelerometer its model assumes. Through the log's 2.2 s
air-data gap that input alone moves the height by metres, and the filter then rejects height
samples (measured: std 2.8 m, max 25.8 m, 45 rejections). It must still run to the end with
finite outputs (the tests above). On the SITL log (a simulated 250 Hz accelerometer) it is
held like every other estimator."""


def test_every_estimator_agrees_with_px4_ekf2_within_the_logs_sensor_noise(replayed):
    """Each log, from 5 s after the first GPS fix (the offset-learning time, see
    altfusion.replay.compare.SETTLE_TIME) to the end, at each valid EKF2 sample: d = h_est -
    ekf_h. The bounds come from the log's own sensors, measured here (:data:`LOG_NOISE`):

    * σ_G, GPS height noise: the receiver's epv, its largest value (Auterion 0.83 m, SITL
      0.70 m);
    * σ_B, baro noise: sample-to-sample scatter of baro_alt_meter, std(Δh)/√2 (Auterion
      0.59 m, SITL 0.073 m; an upper bound: Δh also holds the motion between samples).

    The estimators fuse GPS as their absolute reference (BaselineKF and Whang learn the
    Auterion baro's 155 m offset in their bias states, Hajiyev's adaptive gain goes to ~1);
    EKF2's height reference is the baro, anchored to GPS when its origin was set. So:

    1. datum: mean(d) equals the log's own GPS-EKF2 datum difference mean(gps_h - ekf_h)
       (Auterion -1.87 m, SITL +0.11 m) to within σ_G: the estimators follow GPS, and GPS
       errors over the tens of seconds compared are correlated, so no better than 1 σ_G is
       claimed;
    2. common datum (mean removed): std(d) <= √(σ_G² + σ_B²) (Auterion 1.02 m, SITL 0.70 m),
       the scatter of two estimates each within sensor noise of the truth, one GPS-like, one
       baro-like;
    3. no excursion beyond 4 √(σ_G² + σ_B²) in the common datum;
    4. no GPS height sample rejected: clean flights (``gps_rejected``; YangFusionKF's gate on
       the GPS vertical speed rejects one marginal Auterion sample, test ratio 1.13 at 41.8 s:
       its speed variance is overconfident on that log).

    Issue 16 asks this of AltitudeEKF on both logs; every estimator but :data:`UNHELD` is held
    to it.
    """
    name, results = replayed
    start = settle_time(results)
    gps = new_sample_rows(results, "gps", "gps_fix")
    gps = gps[results.time[gps] >= start]
    sigma_g = float(np.max(results[f"{REPLAY}.gps_epv"][gps]))
    baro = new_sample_rows(results, "baro")
    sigma_b = float(np.std(np.diff(results[f"{REPLAY}.baro_h"][baro])) / math.sqrt(2))
    assert (sigma_g, sigma_b) == pytest.approx(LOG_NOISE[name], abs=0.01)
    datum = float(np.mean(results[f"{REPLAY}.gps_h"][gps] - results[f"{REPLAY}.ekf_h"][gps]))
    bound = math.hypot(sigma_g, sigma_b)
    ekf = new_sample_rows(results, "ekf", "ekf_valid")
    ekf = ekf[results.time[ekf] >= start]
    held = [e for e in ESTIMATORS if e not in UNHELD.get(name, ())]
    assert "AltitudeEKF" in held
    for report in compare_all(results, held, start)[1:]:
        d = results[f"{report.name}.h_est"][ekf] - results[f"{REPLAY}.ekf_h"][ekf]
        assert len(d) == report.vs_ekf.n > 150  # Auterion 286 EKF2 samples, SITL 170
        assert abs(d.mean() - datum) <= sigma_g, report.name
        assert d.std() <= bound, report.name
        assert np.max(np.abs(d - d.mean())) <= 4 * bound, report.name
        assert results[f"{report.name}.gps_rejected"][-1] == 0, report.name


@pytest.mark.parametrize("replayed", ["replay_auterion"], indirect=True)
def test_altitude_ekf_ground_height_scatters_no_more_than_ekf2s(replayed):
    """Issue 16: on the Auterion flight (the one log with a rangefinder) AltitudeEKF's
    rangefinder-implied ground height (h_est - laser_h at each valid lidar sample after the
    settle time) scatters no more than EKF2's own (ekf_h - laser_h) + 0.1 m: its height is at
    least as smooth against the lidar as the autopilot's."""
    _, results = replayed
    reports = {r.name: r for r in compare_all(results, ["AltitudeEKF"], settle_time(results))}
    ekf2, ours = reports.pop(next(n for n in reports if n != "AltitudeEKF")), reports[
        "AltitudeEKF"]
    assert ours.ground.n == ekf2.ground.n > 100
    assert ours.ground.std <= ekf2.ground.std + 0.1


def test_altitude_ekf_told_nothing_holds_the_auterion_flight_within_its_sensor_noise(
        fmus, tmp_path):
    """AltitudeEKF's defaults (every noise not stated: measured from the data), as a user
    dropping it onto a log knows nothing: on the Auterion flight, whose 8.6 Hz accelerometer
    scatters 6-10 m/s² against the typical 0.35 m/s² the noise starts from, the height in a
    common datum with EKF2 scatters within the log's sensor-noise bound √(σ_G² + σ_B²) =
    1.02 m of the agreement test above (measured 0.31 m; 2.02 m while the accelerometer's
    scatter counted only from its 100th sample, 11.6 s in, the height 8 m off before it),
    and no height sample is rejected (42 were)."""
    plan = plan_replay(LOG_DIR / LOGS["replay_auterion"].file, ["AltitudeEKF"], fmus,
                       paper_tuning=True)
    run = run_replay(plan, fmus, tmp_path)
    report = run.reports[1]
    assert report.name == "AltitudeEKF" and report.vs_ekf.n > 150
    assert report.vs_ekf.std <= math.hypot(*LOG_NOISE["replay_auterion"])
    assert report.rejected == 0


def test_altitude_ekf_told_nothing_keeps_the_sitl_receiver_through_the_landing(fmus, tmp_path):
    """AltitudeEKF's defaults on the PX4 SITL log, whose simulated receiver is near exact at
    rest (±0.01 m): told nothing, the typical receiver's 3 m is read as mostly a slow error,
    which now sizes the GNSS's gate and bias test. From touchdown on the receiver's speed
    reads 0 while the simulated accelerometer shows no landing; with the gate sized by the
    heights' centimetre scatter every GNSS height of the last 5 s was rejected (100) and the
    height ended 1.64 m below EKF2 (std 0.58 m in a common datum); now none is, std 0.17 m,
    ending 0.24 m above it: within the log's sensor-noise bound and its GNSS's σ_G (0.70 m)
    at the end. (The GNSS speed is still rejected through the take-off, where it lags the
    accelerometer by about 0.2 s.)"""
    plan = plan_replay(LOG_DIR / LOGS["replay_px4_sitl"].file, ["AltitudeEKF"], fmus,
                       paper_tuning=True)
    run = run_replay(plan, fmus, tmp_path)
    report, results = run.reports[1], run.results
    assert report.name == "AltitudeEKF" and report.vs_ekf.n > 150
    sigma_g = LOG_NOISE["replay_px4_sitl"][0]
    assert report.vs_ekf.std <= math.hypot(*LOG_NOISE["replay_px4_sitl"])
    assert results["AltitudeEKF.gps_rejected"][-1] == 0
    ekf = new_sample_rows(results, "ekf", "ekf_valid")
    end = results["AltitudeEKF.h_est"][ekf[-1]] - results[f"{REPLAY}.ekf_h"][ekf[-1]]
    assert abs(end) <= sigma_g


def test_altfusion_replay_prints_the_comparison_and_writes_csv_and_plot(fmus, tmp_path, capsys):
    log = LOG_DIR / LOGS["replay_px4_sitl"].file
    assert main(["replay", str(log), "--models", str(MODELS), "--out", str(tmp_path),
                 "--estimators", "BaselineKF,WhangGAEstimator",
                 "--set", "BaselineKF.R_gps=1.0"]) == 0
    out = capsys.readouterr().out
    assert "samples delivered: baro 623 of 623, gps 583 of 583, acc 7783 of 7783" in out
    assert "distance_sensor: missing topic" in out
    table = [line for line in out.splitlines() if line.startswith(("BaselineKF", "Whang"))]
    assert len(table) == 2
    stem = "replay_pyulog_sample_px4_events"
    assert (tmp_path / f"{stem}.png").stat().st_size > 10_000
    header = (tmp_path / f"{stem}.csv").read_text().splitlines()[0]
    assert "BaselineKF.h_est [m]" in header and "replay.ekf_h [m]" in header
    summary = (tmp_path / f"{stem}_summary.md").read_text()          # beside the plot
    assert [line.split(" | ")[0] for line in summary.splitlines()[2:]] == [
        "| PX4 EKF2 (reference)", "| BaselineKF", "| WhangGAEstimator"]
    assert (tmp_path / f"{stem}_summary.csv").read_text().startswith("estimate,vs EKF2")


def test_altfusion_replay_refuses_a_missing_log_or_an_unknown_estimator(fmus, tmp_path, capsys):
    assert main(["replay", str(tmp_path / "absent.ulg"), "--models", str(MODELS)]) == 2
    assert "no such file" in capsys.readouterr().err
    log = LOG_DIR / LOGS["replay_px4_sitl"].file
    assert main(["replay", str(log), "--models", str(MODELS), "--estimators", "NoSuchKF"]) == 2
    assert "no FMU for NoSuchKF" in capsys.readouterr().err
    assert main(["replay", str(log), "--models", str(tmp_path)]) == 2   # run elsewhere
    assert f"error: no FMU in {tmp_path} (build them" in capsys.readouterr().err


def test_a_log_file_that_is_not_there_fails_initialization_naming_log_file(fmus):
    from altfusion.cosim import simulate
    from altfusion.systems.spec import ComponentSpec, SystemSpec

    system = SystemSpec("bad_log", "LogReplay of a missing file",
                        (ComponentSpec(REPLAY, "LogReplay", 0.01,
                                       {"log_file": "flightlogs/absent.ulg"}),), (), 1.0)
    with pytest.raises(CosimError, match=r"'log_file' = 'flightlogs/absent.ulg': .*no such"):
        simulate(system, fmus)


def replay_cli(log: Path, out: Path, capsys, estimators: str = "BaselineKF,YangFusionKF"):
    """``altfusion replay`` of ``log`` with two estimators: (status, stdout, stderr)."""
    status = main(["replay", str(log), "--models", str(MODELS), "--out", str(out),
                   "--estimators", estimators])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize("shift_s", [3000, 100_000])
def test_a_corrupted_gps_stamp_is_dropped_and_the_replay_keeps_the_logs_span(
        fmus, tmp_path, capsys, shift_s):
    """One GPS stamp moved by +3000 s (the replay took 26 s) or +100000 s (it hung)."""
    log = tmp_path / "shifted.ulg"
    shift_stamp(LOG_DIR / LOGS["replay_px4_sitl"].file, log, "vehicle_gps_position", 100,
                shift_s * 1_000_000)
    status, out, err = replay_cli(log, tmp_path, capsys)
    assert status == 0, err
    assert f"replayed to {LOGS['replay_px4_sitl'].stop_time:g} s" in out
    assert "vehicle_gps_position: bad time stamp: 1 sample(s)" in out


def test_the_readers_warnings_are_in_the_log_report_not_on_standard_output(
        fmus, tmp_path, capsys):
    """pyulog reports a damaged log with print(): two GPS samples bound to a message id no
    topic declares printed "Warning: no subscription found..." (once per id) among the
    replay's output (inside an FMU: on the host's standard output); it is a line of the log
    report, and the replay goes on without those samples."""
    log = tmp_path / "unknown_id.ulg"
    unknown_message_id(LOG_DIR / LOGS["replay_px4_sitl"].file, log, "vehicle_gps_position",
                       100, 60000)
    unknown_message_id(log, log, "vehicle_gps_position", 200, 60000)
    status, out, err = replay_cli(log, tmp_path, capsys)
    assert status == 0, err
    assert not [line for line in out.splitlines() if line.startswith("Warning")]
    assert ("  log: file: damaged: pyulog: Warning: no subscription found for message id 60000."
            " Continuing, but file is most likely corrupt\n") in out
    assert "samples delivered: baro 623 of 623, gps 581 of 581" in out


def test_a_log_without_baro_gives_the_table_and_the_plot(fmus, tmp_path, capsys):
    log = tmp_path / "nobaro.ulg"
    without_topic(LOG_DIR / LOGS["replay_px4_sitl"].file, log, "vehicle_air_data")
    status, out, err = replay_cli(log, tmp_path, capsys)
    assert status == 0, err
    rows = [line for line in out.splitlines() if line.startswith(("BaselineKF", "YangFusion"))]
    assert len(rows) == 2 and all(row.endswith("100%  no") for row in rows)
    assert (tmp_path / "replay_nobaro.png").stat().st_size > 10_000


def test_random_byte_flips_end_in_a_replay_or_a_one_line_error(fmus, tmp_path, capsys):
    """Three seeded sets of 20 flipped bytes: a degraded replay bounded by the log's span or
    status 2 with one line, never a MemoryError or a traceback."""
    original = (LOG_DIR / LOGS["replay_px4_sitl"].file).read_bytes()
    rng = np.random.default_rng(17)
    for attempt in range(3):
        data = bytearray(original)
        for index in rng.integers(16, len(data), 20):
            data[index] ^= int(rng.integers(1, 256))
        log = tmp_path / f"flipped{attempt}.ulg"
        log.write_bytes(bytes(data))
        status, out, err = replay_cli(log, tmp_path, capsys, "BaselineKF")
        assert status in (0, 2), err
        if status == 2:
            assert len(err.strip().splitlines()) == 1 and err.startswith("error: ")
        else:
            replayed = float(out.split(" replayed to ")[1].split(" s ")[0])
            assert replayed <= LOGS["replay_px4_sitl"].stop_time


def replayed_columns(baro_h: float, estimates: dict[str, np.ndarray]) -> Results:
    """20 rows at 1 s, GPS (500 m), baro (``baro_h``) and EKF2 samples up to t = 9 s, and the
    ``estimates`` (component name -> h_est)."""
    time = np.arange(0.0, 20.0, 1.0)
    count = np.minimum(np.arange(20), 9).astype(float)      # samples up to t = 9 s
    columns = {f"{REPLAY}.gps_count": count, f"{REPLAY}.gps_fix": np.ones(20),
               f"{REPLAY}.gps_h": np.full(20, 500.0), f"{REPLAY}.gps_epv": np.ones(20),
               f"{REPLAY}.baro_count": count, f"{REPLAY}.baro_h": np.full(20, baro_h),
               f"{REPLAY}.ekf_count": count, f"{REPLAY}.ekf_valid": np.ones(20),
               f"{REPLAY}.ekf_h": np.full(20, 500.0),
               **{f"{name}.h_est": h for name, h in estimates.items()}}
    return Results(time, columns)


def test_the_table_flags_a_divergent_estimate_and_gives_the_valid_fraction():
    """An estimate 100 m (> DIVERGENCE_BOUND) from GPS and baro is flagged; rows more than
    AIDING_TIMEOUT after the last height sample are not valid."""
    results = replayed_columns(510.0, {"good": np.full(20, 500.5),
                                       "bad": np.linspace(500.0, 600.0, 20)})
    reports = compare_all(results, ["good", "bad"], start=0.0)
    good, bad = reports[1], reports[2]
    assert good.diverged == "" and bad.diverged.startswith("|h - sensors|")
    # samples arrive at rows 1..9 (t = 1..9 s): valid from row 1 while t - 9 s <= 5 s, 14 of 20
    assert good.valid_fraction == pytest.approx(14 / 20)
    assert "70%" in format_table(reports)


def test_an_estimate_in_the_baros_datum_is_not_flagged_diverged():
    """AltitudeEKF with ``height_ref`` baro gives its height in the baro's datum: on the
    Auterion log 155 m from the GPS altitude (> DIVERGENCE_BOUND), 0.2 m from the baro. Such
    an estimate follows a height sensor and has not diverged; 100 m from the baro and the GPS
    it has."""
    results = replayed_columns(655.0, {"baro_datum": np.full(20, 655.2),
                                       "bad": np.full(20, 755.0)})
    reports = compare_all(results, ["baro_datum", "bad"], start=0.0)
    assert reports[1].diverged == "" and reports[2].diverged.startswith("|h - sensors| 100 m")


def test_altfusion_replay_says_the_health_events_and_writes_them(fmus, tmp_path, capsys):
    """The replay prints each estimator's health events in words and writes them all to
    ``<system>.events.csv``, derived from the recorded outputs as for any host's results."""
    log = LOG_DIR / LOGS["replay_px4_sitl"].file
    assert main(["replay", str(log), "--models", str(MODELS), "--out", str(tmp_path),
                 "--estimators", "BaselineKF,AltitudeEKF"]) == 0
    out = capsys.readouterr().out
    stem = "replay_pyulog_sample_px4_events"
    events = tmp_path / f"{stem}.events.csv"
    assert f"health events (all in {events}):" in out
    results = Results.from_csv(tmp_path / f"{stem}.csv")
    assert events.read_text() == events_csv(health_events(results))
    said = out.split("health events")[1]
    assert "  BaselineKF\n" in said and "  AltitudeEKF\n" in said and " initialized" in said
    # The simulated receiver reads a vertical speed of exactly 0.0 on the ground: a GNSS
    # holding still, not a stuck one (before: gps_vz isolated at 9.7 s, 257 rejections).
    assert "isolated" not in said and "rejected" not in said
    assert results["AltitudeEKF.gps_vz_rejected"].max() == 0
