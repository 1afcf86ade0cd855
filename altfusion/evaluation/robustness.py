"""The robustness of the estimators ``altfusion evaluate`` evaluates: each told nothing, or
every noise misstated x0.2 and x5 (:mod:`altfusion.evaluation.told`), in every scenario: its
coverage (whether its ``h_std`` stays honest when it was told wrong) and its RMS over its RMS
told the true noise only (what the wrong statement costs; when ``noise`` was evaluated)."""

import math
from dataclasses import dataclass

from altfusion.evaluation.run import Cell, Cells, estimator_cell
from altfusion.evaluation.told import MISSTATED, NOISE, NOTHING, Told


@dataclass(frozen=True)
class Robustness:
    """One estimator in one scenario told per one variant: n/a (why), or its RMS (m), its
    coverage and the ratio of its RMS to its told-noise RMS (nan: no runs, no finite value
    or no told-noise cell to compare with)."""

    not_applicable: str = ""
    rms: float = math.nan
    coverage: float = math.nan
    ratio: float = math.nan

    def text(self) -> str:
        """'x1.23, 96 %' (ratio, coverage), or with the RMS '0.52 m, 96 %' when there is
        no told-noise RMS; n/a, or - without a finite value."""
        if self.not_applicable:
            return "n/a"
        if not math.isfinite(self.rms):
            return "-"
        error = f"x{self.ratio:.3g}" if math.isfinite(self.ratio) else f"{self.rms:.3g} m"
        coverage = f"{100 * self.coverage:.0f} %" if math.isfinite(self.coverage) else "-"
        return f"{error}, {coverage}"


def robustness_variants(results: dict[Told, Cells]) -> list[Told]:
    """The evaluated variants the robustness table shows: told nothing and misstated."""
    return [told for told in results if told.mode in (NOTHING, MISSTATED)]


def robustness_measure(results: dict[Told, Cells]) -> str:
    """What a robustness cell's first number is, in words."""
    if Told(NOISE) in results:
        return "its RMS over its RMS told the noise only (x1: the wrong statement costs nothing)"
    return "its RMS in m (`noise` not evaluated)"


def cell_robustness(cell: Cell, reference: Cell | None) -> Robustness:
    """A cell's robustness against its told-noise cell ``reference`` (None: not evaluated)."""
    if cell.not_applicable:
        return Robustness(cell.not_applicable)
    coverage = cell.summary("coverage") if cell.runs else None
    rms = cell.rms
    base = reference.rms if reference is not None else math.nan
    ratio = rms / base if math.isfinite(base) and base > 0 else math.nan
    return Robustness(rms=rms, coverage=math.nan if coverage is None else coverage.mean,
                      ratio=ratio)


def robustness(results: dict[Told, Cells], estimators: list[str],
               ) -> list[tuple[str, Told, dict[str, Robustness]]]:
    """One row per estimator and robustness variant: scenario name -> its robustness."""
    reference = results.get(Told(NOISE))
    rows = []
    for estimator in estimators:
        for told in robustness_variants(results):
            row = {}
            for name, column in results[told].items():
                noise = None if reference is None else estimator_cell(reference[name],
                                                                      estimator)
                row[name] = cell_robustness(estimator_cell(column, estimator), noise)
            rows.append((estimator, told, row))
    return rows
