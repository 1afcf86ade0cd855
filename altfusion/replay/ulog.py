"""Reading a PX4 ULog file with ``pyulog`` into a :class:`~altfusion.replay.extract.FlightLog`.

Only the topics the replay needs are kept, as ``field -> numpy array``. Of a topic logged in
several instances (``multi_id``) the first is used and the others are reported. Times are
relative to the log's first time stamp (or an earlier sample time, see ``extract_streams``).
"""

from pathlib import Path

import numpy as np

from altfusion.replay.extract import TOPICS, FlightLog, extract_streams
from altfusion.replay.streams import LogProblem


class LogReadError(ValueError):
    """The file cannot be read as a ULog at all (missing, not a ULog, truncated header)."""


def read_topics(path: Path) -> tuple[dict[str, dict[str, np.ndarray]], int, int,
                                     list[LogProblem]]:
    """``(topic -> field -> array, first time stamp µs, last time stamp µs, problems)``."""
    from pyulog import ULog

    path = Path(path)
    if not path.is_file():
        raise LogReadError(f"{path}: no such file")
    try:
        ulog = ULog(str(path))
    except Exception as error:  # pyulog raises bare exceptions on corrupt files
        raise LogReadError(f"{path}: not a readable ULog file ({type(error).__name__}: "
                           f"{error})") from None
    topics: dict[str, dict[str, np.ndarray]] = {}
    problems = []
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


def read_ulog(path: Path) -> FlightLog:
    """The replay streams of a ULog file; raises :class:`LogReadError` only if the file cannot
    be parsed at all. Everything else (missing topics, gaps, duplicates...) is in the report."""
    topics, first_us, last_us, problems = read_topics(path)
    log = extract_streams(topics, first_us, last_us, source=str(path))
    log.problems[:0] = problems
    return log
