"""Recorded co-simulation results: time series by 'component.variable', with units and CSV."""

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from altfusion.atomic import write_text

MAX_WARNINGS = 10_000
"""Warnings kept per instance and run; later ones are counted, not kept."""


class Warnings(list[str]):
    """A component's warnings in a run: the first ``MAX_WARNINGS`` - 1 kept, and from there
    on a last entry counting the ones not kept."""

    def __init__(self) -> None:
        super().__init__()
        self.dropped = 0

    @property
    def total(self) -> int:
        """How many were logged."""
        return len(self) - 1 + self.dropped if self.dropped else len(self)

    def keep(self, new: Sequence[str]) -> None:
        """Keep ``new`` while there is room, count the rest."""
        if not self.dropped:
            room = MAX_WARNINGS - len(self)
            if len(new) <= room:
                self.extend(new)
                return
            self.extend(new[:room - 1])
            new = new[room - 1:]
            self.append("")
        self.dropped += len(new)
        self[-1] = f"... {self.dropped} more warnings not kept"

    def clear(self) -> None:
        super().clear()
        self.dropped = 0


@dataclass
class Results:
    """Time (s) and recorded signals; ``units`` maps each column to its unit ('' if none);
    ``warnings`` holds what each component logged as a warning (ignored samples, outliers,
    stuck sensors), by component."""

    time: np.ndarray
    columns: dict[str, np.ndarray]
    units: dict[str, str] = field(default_factory=dict)
    warnings: dict[str, Warnings] = field(default_factory=dict)

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

    def warnings_to_text(self, path: Path) -> Path:
        """Write every kept warning, one line each after its component's name, atomically;
        return the path."""
        lines = (f"{name}: {warning}" for name, kept in self.warnings.items() for warning in kept)
        return write_text(Path(path), "".join(f"{line}\n" for line in lines))

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
