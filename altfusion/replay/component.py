"""LogReplay: a flight log's sensor streams delivered with their original time stamps.

Each stream (``baro``, ``gps``, ``acc``, ``laser``, ``radar``, ``ekf``; see
:mod:`altfusion.replay.extract` for what each value is) follows the contract's multi-rate
convention. A step over (t_a, t_b] delivers every sample whose replay time falls in it:

* ``<prefix>_count`` increases by the number of samples delivered, so a step that holds
  several samples (a 250 Hz accelerometer under a 100 Hz step) counts them all;
* the outputs hold the last of them, and ``<prefix>_time`` is that sample's own replay time,
  not the step's end;
* a consumer stepped more slowly than the samples arrive sees the count jump by more than one
  and fuses the latest sample (the estimators note this).

Replay time is log time minus ``time_offset``, log time being seconds after the log's first
sample. The first step also delivers samples exactly at the start time; samples before it are
skipped and noted. The log's report (missing topics, gaps, duplicates, conversions) is noted
when the component is reset, so a host logs it as warnings with the first step.
"""

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from altfusion.component import Component
from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.replay.extract import FlightLog
from altfusion.replay.streams import SampleStream
from altfusion.replay.ulog import LogReadError, read_ulog
from altfusion.signals import LOG_OUTPUTS, LOG_STREAMS
from altfusion.timegrid import TickClock, exact

INTEGER_OUTPUTS = ("gps_nsat",)


@dataclass(frozen=True)
class LogReplayParams:
    log_file: str = param(
        "", None, "PX4 ULog file to replay. A relative path is looked up in the FMU's resources "
        "folder (bundled logs: flightlogs/<name>.ulg), then in the working directory. Empty: "
        "nothing is replayed")
    time_offset: float = param(
        0.0, "s", "Log time replayed at simulation time 0: a sample taken at log time tau (s "
        "after the log's first sample) is delivered at tau - time_offset", min=0.0)


def resolve_log_file(log_file: str, resources: str | None) -> str:
    """``log_file``, made absolute if it is relative and exists under ``resources``."""
    path = Path(log_file)
    if log_file and not path.is_absolute() and resources:
        candidate = Path(resources) / path
        if candidate.is_file():
            return str(candidate)
    return log_file


def delivery_ticks(time_s: np.ndarray, clock: TickClock, time_offset: float) -> np.ndarray:
    """The tick k whose step (t_k-1, t_k] delivers each sample (0: before the start).

    Exact: sample times are whole microseconds, the step and offsets decimals, so k =
    ceil((tau - time_offset - t_start) / step) is computed in integers. A sample exactly at the
    start time goes to the first step."""
    step = exact(clock.step_size)
    origin = exact(time_offset) + exact(clock.time(0))
    scale = 10**6 * origin.denominator * step.numerator
    ticks = []
    for micros in np.round(np.asarray(time_s) * 1e6).astype(np.int64).tolist():
        numerator = (micros * origin.denominator - origin.numerator * 10**6) * step.denominator
        if numerator < 0:
            ticks.append(0)
        else:
            ticks.append(max(1, -((-numerator) // scale)))
    return np.asarray(ticks, dtype=np.int64)


class LogReplay(Component):
    """Replays a PX4 ULog's air data, GNSS, vertical acceleration, rangefinder and EKF2 height
    with the original time stamps, each stream with its own count and time stamp."""

    Params = LogReplayParams

    def __init__(self, params: Any = None, **kwargs: Any):
        for name in LOG_OUTPUTS:
            setattr(self, name, self._initial(name))
        super().__init__(params, **kwargs)

    @staticmethod
    def _initial(name: str) -> Any:
        if name.endswith("_count") or name in INTEGER_OUTPUTS:
            return 0
        if name.endswith("_valid") or name == "gps_fix":
            return False
        return 0.0

    def configure(self, clock: TickClock) -> None:
        """Read the log and schedule each sample on the step grid."""
        self.log = self._read(resolve_log_file(self.params.log_file, self.resources))
        self._streams: dict[str, SampleStream] = {}
        self._ticks: dict[str, np.ndarray] = {}
        self.skipped: dict[str, int] = {}
        for prefix, stream in self.log.streams.items():
            if prefix not in LOG_STREAMS or not len(stream):
                continue
            ticks = delivery_ticks(stream.time, clock, self.params.time_offset)
            self._streams[prefix] = stream
            self._ticks[prefix] = ticks
            self.skipped[prefix] = int(np.sum(ticks == 0))

    @staticmethod
    def _read(log_file: str) -> FlightLog:
        if not log_file:
            return FlightLog(0, 0.0, {})
        try:
            return read_ulog(Path(log_file))
        except LogReadError as error:
            raise ParameterError("log_file", log_file, str(error)) from None

    @property
    def duration(self) -> float:
        """Replay time of the log's last time stamp, s."""
        return self.log.duration - self.params.time_offset

    def expected_counts(self, stop_time: float) -> dict[str, int]:
        """How many samples of each stream a run to ``stop_time`` delivers."""
        elapsed = exact(stop_time) - exact(self.clock.time(0))
        last_tick = math.floor(elapsed / exact(self.clock.step_size))
        return {prefix: int(np.sum((ticks >= 1) & (ticks <= last_tick)))
                for prefix, ticks in self._ticks.items()}

    def reset(self) -> None:
        for name in LOG_OUTPUTS:
            setattr(self, name, self._initial(name))
        if not self.params.log_file:
            self.note("log_file is empty: nothing is replayed")
        for line in self.log.report():
            self.note(f"log: {line}")
        for prefix, count in self.skipped.items():
            if count:
                self.note(f"{prefix}: {count} sample(s) before the replay start skipped")

    def update(self) -> None:
        tick = self.clock.ticks
        for prefix, stream in self._streams.items():
            ticks = self._ticks[prefix]
            delivered = int(np.searchsorted(ticks, tick, side="right"))
            count = delivered - self.skipped[prefix]
            if count == getattr(self, f"{prefix}_count"):
                continue
            self._hold(prefix, stream, delivered - 1, count)

    def _hold(self, prefix: str, stream: SampleStream, index: int, count: int) -> None:
        values, valid = LOG_STREAMS[prefix]
        for name in values:
            value = stream.values[name][index]
            setattr(self, name, int(value) if name in INTEGER_OUTPUTS else float(value))
        if valid:
            setattr(self, valid, bool(stream.valid[index]))
        setattr(self, f"{prefix}_count", count)
        setattr(self, f"{prefix}_time", float(stream.time[index]) - self.params.time_offset)
