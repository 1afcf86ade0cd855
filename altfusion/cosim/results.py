"""Recorded co-simulation results: time series by 'component.variable', with units and CSV."""

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from altfusion.atomic import write_text


@dataclass
class Results:
    """Time (s) and recorded signals; ``units`` maps each column to its unit ('' if none);
    ``warnings`` holds what each component logged as a warning (ignored samples, outliers)."""

    time: np.ndarray
    columns: dict[str, np.ndarray]
    units: dict[str, str] = field(default_factory=dict)
    warnings: dict[str, list[str]] = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def header(self, name: str) -> str:
        unit = self.units.get(name, "")
        return f"{name} [{unit}]" if unit else name

    def to_csv(self, path: Path) -> Path:
        """Write 'time [s]' and every column, units in the header, atomically (see
        :mod:`altfusion.atomic`); return the path."""
        names = list(self.columns)
        data = np.column_stack([self.time] + [self.columns[n] for n in names])
        text = io.StringIO(newline="")
        writer = csv.writer(text)
        writer.writerow(["time [s]"] + [self.header(n) for n in names])
        for row in data:
            writer.writerow([repr(float(v)) for v in row])
        return write_text(Path(path), text.getvalue())

    @classmethod
    def from_csv(cls, path: Path) -> "Results":
        with open(path, newline="") as handle:
            header = next(csv.reader(handle))
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        columns, units = {}, {}
        for index, title in enumerate(header[1:], start=1):
            name, _, unit = title.partition(" [")
            columns[name] = data[:, index]
            units[name] = unit.rstrip("]")
        return cls(data[:, 0], columns, units)
