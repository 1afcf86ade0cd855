"""A result file from any host, read as rows of time and columns named 'component.variable'.

Layouts (the first column is always the time):

* ``altfusion``: our runner's CSV, and libcosim's and ECOS's as ``altfusion.interop`` writes
  them: ``time [s]``, then ``component.variable [unit]``;
* ``OMSimulator``: ``time``, then ``<system>.<component>.<variable>`` (the SSP's system
  name, e.g. ``yang2020.gnss.gps_count``; a model prefix such as ``model.root.`` is taken
  off the same way). OMSimulator writes a row after each step and another after it has
  exchanged the outputs, at the same time: the first row of each time is kept, so an input
  column shows the value the input had during the step that ended then, as in the other
  layouts.
"""

import csv
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.errors import UsageError

TIME_HEADERS = {"time [s]": "altfusion", "time": "OMSimulator"}


@dataclass(frozen=True)
class ResultTable:
    """Rows of a result: strictly increasing ``time`` (s) and columns by
    'component.variable'; ``layout`` names the host layout it was read in."""

    time: np.ndarray
    columns: dict[str, np.ndarray]
    layout: str


def column_name(header: str, components: set[str]) -> str | None:
    """'component.variable' of a column header, or None if it names no component of the
    system: a unit suffix ' [..]' and leading system/model prefixes are taken off."""
    name = header.strip().split(" [", 1)[0]
    parts = name.split(".")
    for start in range(len(parts) - 1):
        if parts[start] in components:
            return ".".join(parts[start:])
    return None


def first_row_per_time(time: np.ndarray) -> np.ndarray:
    """Indices of the first row of each distinct time (times must not decrease)."""
    return np.flatnonzero(np.r_[True, np.diff(time) > 0])


def read_result(path: Path, components: set[str]) -> ResultTable:
    """The result file ``path`` as a :class:`ResultTable` of the columns that name one of
    ``components``; a UsageError naming the file when it is missing or not in a known
    layout."""
    path = Path(path)
    if not path.is_file():
        raise UsageError(f"{path}: no such file")
    try:
        with open(path, newline="") as handle:
            header = next(csv.reader(handle), [])
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise UsageError(f"{path}: not a result table ({error})") from None
    layout = TIME_HEADERS.get(header[0].strip()) if header else None
    if layout is None:
        raise UsageError(f"{path}: unknown column layout (first column {header[:1]!r}; "
                         f"expected {' or '.join(repr(h) for h in TIME_HEADERS)})")
    try:
        with warnings.catch_warnings():             # no rows: said below, in one line
            warnings.simplefilter("ignore", UserWarning)
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as error:
        raise UsageError(f"{path}: not a result table ({error})") from None
    if data.shape[0] == 0 or data.shape[1] != len(header):
        raise UsageError(f"{path}: {data.shape[0]} rows of {data.shape[1]} values under "
                         f"{len(header)} column headers")
    time = data[:, 0]
    if np.any(np.diff(time) < 0):
        raise UsageError(f"{path}: the time column decreases")
    rows = first_row_per_time(time)
    columns = {}
    for index, title in enumerate(header[1:], start=1):
        name = column_name(title, components)
        if name is not None and name not in columns:
            columns[name] = data[rows, index]
    if not columns:
        raise UsageError(f"{path}: unknown column layout: no column names a component of the "
                         f"system ({', '.join(sorted(components))})")
    return ResultTable(time[rows], columns, layout)
