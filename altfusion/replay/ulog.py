"""Reading a PX4 ULog file with ``pyulog`` into a :class:`~altfusion.replay.extract.FlightLog`.

Only the topics the replay needs are kept, as ``field -> numpy array``. Of a topic logged in
several instances (``multi_id``) the first is used and the others are reported. Times are
relative to the log's first time stamp (or an earlier sample time, see ``extract_streams``).
"""

import contextlib
import io
from collections import Counter
from pathlib import Path

import numpy as np

from altfusion.replay.extract import TOPICS, FlightLog, extract_streams
from altfusion.replay.streams import LogProblem


class LogReadError(ValueError):
    """The file cannot be read as a ULog at all (missing, not a ULog, truncated header)."""


def read_topics(path: Path) -> tuple[dict[str, dict[str, np.ndarray]], int, int,
                                     list[LogProblem]]:
    """``(topic -> field -> array, first time stamp µs, last time stamp µs, problems)``."""
    try:
        from pyulog import ULog
    except ImportError as error:
        raise LogReadError(f"reading {path} needs the Python package pyulog, which the "
                           f"host's Python lacks (pip install pyulog): {error}") from None

    path = Path(path)
    if not path.is_file():
        raise LogReadError(f"{path}: " + ("a folder, not a ULog file" if path.is_dir() else
                                          "not a regular file" if path.exists() else
                                          "no such file"))
    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed):   # pyulog reports damage with print()
            ulog = ULog(str(path))
    except Exception as error:  # pyulog raises bare exceptions on corrupt files
        raise LogReadError(f"{path}: not a readable ULog file ({type(error).__name__}: "
                           f"{error})") from None
    topics: dict[str, dict[str, np.ndarray]] = {}
    problems = reader_warnings(printed.getvalue())
    for data in sorted(ulog.data_list, key=lambda d: d.multi_id):
        if data.name not in TOPICS:
            continue
        if data.name in topics:
            problems.append(LogProblem(data.name, "skipped", f"instance {data.multi_id} "
                                                             f"ignored; instance 0 used"))
            continue
        topics[data.name] = {name: np.asarray(values) for name, values in data.data.items()}
    for message in ulog.logged_messages:
        if message.log_level <= 3:  # emergency, alert, critical, error
            problems.append(LogProblem("logged message", "error", message.message))
    return topics, int(ulog.start_timestamp), int(ulog.last_timestamp), problems


SHOWN_WARNINGS = 3
"""Distinct reader warnings reported one by one; the others are counted."""


def reader_warnings(printed: str) -> list[LogProblem]:
    """What pyulog printed while reading (it reports a damaged file with ``print``: "no
    subscription found for message id 11...", "File corruption detected..."), as log
    problems instead of lines on the host's standard output: the first
    :data:`SHOWN_WARNINGS` distinct ones with their counts, then how many more."""
    counts = Counter(line.strip() for line in printed.splitlines() if line.strip())
    problems = [LogProblem("file", "damaged", f"pyulog: {line}"
                           + (f" ({count} times)" if count > 1 else ""))
                for line, count in list(counts.items())[:SHOWN_WARNINGS]]
    others = sum(list(counts.values())[SHOWN_WARNINGS:])
    if others:
        problems.append(LogProblem("file", "damaged", f"pyulog: {others} more warning(s)"))
    return problems


SECONDS_PER_BYTE = 1e-3
"""Longest replay per byte of log: 14 times the bundled logs' largest span per byte (the
Auterion log: 44 s in 0.62 MB; the SITL sample: 31 s in 1.56 MB), so the recorded results (one
row per 0.01 s base step, ~60 columns of 8 bytes) stay within about 50 bytes of memory per byte
of log whatever a corrupted file claims."""


def read_ulog(path: Path) -> FlightLog:
    """The replay streams of a ULog file; raises :class:`LogReadError` only if the file cannot
    be parsed at all. Everything else (missing topics, gaps, duplicates...) is in the report."""
    topics, first_us, _last_us, problems = read_topics(path)
    log = extract_streams(topics, first_us, source=str(path))
    log.problems[:0] = problems
    size = Path(path).stat().st_size
    if log.duration > SECONDS_PER_BYTE * size:
        raise LogReadError(f"{path}: sensor data span {log.duration:.4g} s, more than "
                           f"{SECONDS_PER_BYTE:g} s per byte of a {size}-byte file could "
                           f"hold; the time stamps are corrupt")
    return log
