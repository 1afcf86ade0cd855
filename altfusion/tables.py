"""Breakpoint tables written as text, e.g. ``"0 0; 10 15; 100 15"`` (time, value pairs).

Used for user-supplied profiles and schedules passed through FMI String parameters.
"""

import numpy as np

from altfusion.errors import ParameterError


def parse_table(text: str, name: str, columns: int = 2) -> np.ndarray:
    """Parse ';'-separated rows of whitespace- or ','-separated numbers into an array.

    The first column must be strictly increasing. Raises ParameterError naming ``name``.
    """
    rows = []
    for row in text.replace("\n", ";").split(";"):
        if not row.strip():
            continue
        try:
            values = [float(v) for v in row.replace(",", " ").split()]
        except ValueError:
            raise ParameterError(name, text, f"row {row.strip()!r} is not numeric") from None
        if len(values) != columns:
            raise ParameterError(name, text, f"each row needs {columns} numbers")
        rows.append(values)
    if not rows:
        raise ParameterError(name, text, "the table is empty")
    table = np.array(rows, dtype=float)
    if not np.all(np.isfinite(table)):
        raise ParameterError(name, text, "values must be finite")
    if np.any(np.diff(table[:, 0]) <= 0):
        raise ParameterError(name, text, "the first column must be strictly increasing")
    return table
