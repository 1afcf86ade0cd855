"""The LogReplay core: the multi-rate delivery of logged samples, bad parameters, bundled
paths, and the catalog's per-log constants."""

from pathlib import Path

import numpy as np
import pytest

from altfusion.errors import ParameterError
from altfusion.replay import component
from altfusion.replay.calibration import launch_calibration
from altfusion.replay.component import LogReplay, LogReplayParams, resolve_log_file
from altfusion.replay.extract import FlightLog
from altfusion.replay.streams import SampleStream
from altfusion.replay.ulog import read_ulog
from altfusion.systems.replay import LOGS

LOGS_DIR = Path(__file__).parent / "data" / "flightlogs"


@pytest.fixture
def synthetic(monkeypatch):
    """LogReplay reading a made-up log: baro at irregular times, two accelerometer samples in
    one 0.01 s step, one sample exactly at t = 0."""
    baro = SampleStream("baro", "vehicle_air_data", np.array([0.0, 0.013, 0.0135, 0.05]),
                        {"baro_h": np.array([1.0, 2.0, 3.0, 4.0]), "baro_p": np.zeros(4),
                         "baro_T": np.full(4, 290.0)})
    log = FlightLog(0, 0.05, {"baro": baro})
    monkeypatch.setattr(component, "read_ulog", lambda path: log)

    def make(**params) -> LogReplay:
        return LogReplay(LogReplayParams(log_file="synthetic.ulg", **params), step_size=0.01)
    return make


def step_to(replay: LogReplay, ticks: int) -> None:
    while replay.clock.ticks < ticks:
        replay.do_step(replay.time, replay.dt)


def test_several_samples_in_one_step_count_each_and_hold_the_last_with_its_own_time(synthetic):
    replay = synthetic()
    step_to(replay, 1)  # [0, 0.01]: the sample at exactly t = 0
    assert (replay.baro_count, replay.baro_h, replay.baro_time) == (1, 1.0, 0.0)
    step_to(replay, 2)  # (0.01, 0.02]: two samples
    assert (replay.baro_count, replay.baro_h, replay.baro_time) == (3, 3.0, 0.0135)
    step_to(replay, 4)  # (0.03, 0.04]: none, the last is held
    assert (replay.baro_count, replay.baro_h, replay.baro_time) == (3, 3.0, 0.0135)
    step_to(replay, 5)  # the sample at 0.05 falls in (0.04, 0.05]
    assert (replay.baro_count, replay.baro_h) == (4, 4.0)


def test_a_time_offset_skips_earlier_samples_notes_them_and_shifts_the_times(synthetic):
    replay = synthetic(time_offset=0.01)
    assert any("baro: 1 sample(s) before the replay start skipped" in n
               for n in replay.take_notes())
    step_to(replay, 1)  # replay times 0.003 and 0.0035
    assert (replay.baro_count, replay.baro_h) == (2, 3.0)
    assert replay.baro_time == pytest.approx(0.0035)
    assert replay.expected_counts(0.04) == {"baro": 3}


def test_a_missing_or_unreadable_log_file_is_rejected_naming_the_parameter(tmp_path):
    with pytest.raises(ParameterError, match="'log_file'.*no such file"):
        LogReplay(LogReplayParams(log_file=str(tmp_path / "absent.ulg")))
    junk = tmp_path / "junk.ulg"
    junk.write_bytes(b"this is not a ULog file")
    with pytest.raises(ParameterError, match="'log_file'.*not a readable ULog"):
        LogReplay(LogReplayParams(log_file=str(junk)))


def test_an_empty_log_file_replays_nothing_and_says_so():
    replay = LogReplay()
    assert any("nothing is replayed" in n for n in replay.take_notes())
    step_to(replay, 3)
    assert replay.baro_count == replay.gps_count == 0


def test_a_relative_log_file_is_resolved_in_the_resources_folder_when_it_is_there():
    relative = "flightlogs/auterion_esc_status_log.ulg"
    resolved = resolve_log_file(relative, str(LOGS_DIR.parent))
    assert Path(resolved) == LOGS_DIR / "auterion_esc_status_log.ulg"
    assert resolve_log_file(relative, "/nonexistent") == relative
    replay = LogReplay(LogReplayParams(log_file=relative), resources=str(LOGS_DIR.parent))
    assert replay.log.streams["baro"].time.size > 0


@pytest.mark.parametrize("name", sorted(LOGS))
def test_catalog_constants_are_those_of_the_bundled_logs(name):
    """Stop time = the log's duration rounded up to the 0.01 s step; Whang's H0 and T0 are
    launch_calibration of the log."""
    entry = LOGS[name]
    log = read_ulog(LOGS_DIR / entry.file)
    assert entry.stop_time == pytest.approx(np.ceil(log.duration * 100) / 100)
    calibration = launch_calibration(log)
    assert calibration == pytest.approx(entry.calibration, abs=0.005)
