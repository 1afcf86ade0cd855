"""``altfusion compare``: the same seeded runs through several estimators, side by side.

The system's component named ``estimator`` runs each named FMU in turn (see
:mod:`altfusion.montecarlo.swap`); every other component keeps its name and therefore its
derived seeds, so every estimator sees identical noise realizations. Each estimator's
campaign lives in ``OUT/<estimator>/`` (resumable and reportable on its own);
``OUT/compare.html`` and ``OUT/compare.json`` put them side by side.
"""

import json
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from altfusion.atomic import write_text
from altfusion.cosim.ssp import read_ssp
from altfusion.montecarlo import plots
from altfusion.montecarlo.aggregation import CampaignStatistics
from altfusion.montecarlo.execution import (
    CampaignOutcome,
    CampaignSettings,
    Execution,
    run_campaign,
)
from altfusion.montecarlo.report import STYLE, Report, esc, image, table, write_report
from altfusion.montecarlo.source import CampaignError, SystemSource
from altfusion.montecarlo.swap import find_fmu
from altfusion.montecarlo.tables import HEADER, format_table, metric_row, statistics_json

COMPONENT = "estimator"
"""The component whose FMU is swapped."""


def folder_name(estimator: str) -> str:
    """The sub-folder of an estimator's campaign: its FMU name, file-system safe."""
    return re.sub(r"[^A-Za-z0-9_.-]", "_", Path(estimator).stem)


@dataclass
class Contender:
    name: str
    source: SystemSource

    @property
    def folder(self) -> str:
        return folder_name(self.name)


def contenders(ssp: Path, estimators: list[str]) -> list[Contender]:
    """One swapped source per estimator FMU name (or .fmu path)."""
    if len(estimators) < 1:
        raise CampaignError("--estimators names no FMU")
    if len(set(estimators)) != len(estimators):
        raise CampaignError(f"--estimators names an FMU twice: {','.join(estimators)}")
    loaded = read_ssp(ssp)
    names = [c.name for c in loaded.spec.components]
    if COMPONENT not in names:
        raise CampaignError(f"{Path(ssp).name} has no component named '{COMPONENT}' to swap "
                            f"(components: {', '.join(names)})")
    found = [Contender(name, SystemSource.from_path(ssp, find_fmu(COMPONENT, name, ssp,
                                                                  loaded.fmu_paths)))
             for name in estimators]
    folders = [c.folder for c in found]
    if len(set(folders)) != len(folders):
        raise CampaignError(f"estimators {', '.join(estimators)} map to the same folder name")
    return found


def run_comparison(ssp: Path, estimators: list[str], out: Path, settings: CampaignSettings,
                   execution: Execution | None = None, resume: bool = False,
                   ) -> list[tuple[Contender, CampaignOutcome]]:
    """Run every estimator's campaign in turn; stop at the first interrupted one."""
    execution = execution or Execution()
    outcomes = []
    for contender in contenders(ssp, estimators):
        if execution.progress:
            print(f"{contender.name}:", file=sys.stderr, flush=True)
        outcome = run_campaign(contender.source, Path(out) / contender.folder, settings,
                               execution, resume)
        outcomes.append((contender, outcome))
        if outcome.stopped:
            break
    return outcomes


def comparison_rows(results: list[tuple[str, CampaignStatistics]]) -> list[tuple[str, ...]]:
    """One row per (metric, estimator), metrics grouped."""
    rows = []
    metric_names = [m.metric.name for m in results[0][1].metrics]
    for metric_name in metric_names:
        for name, statistics in results:
            for metric in statistics.metrics:
                if metric.metric.name == metric_name:
                    row = metric_row(metric)
                    rows.append((row[0], name, f"{len(statistics.runs)}", *row[1:]))
    return rows


COMPARE_HEADER = (HEADER[0], "estimator", "runs", *HEADER[1:])


def format_comparison(results: list[tuple[str, CampaignStatistics]]) -> str:
    text = format_table(COMPARE_HEADER, comparison_rows(results))
    run_sets = {tuple(s.runs) for _, s in results}
    if len(run_sets) > 1:
        text += "\nnote: the estimators were evaluated on different runs (failed runs differ)"
    confidence = results[0][1].confidence
    return text + f"\n[brackets]: {100 * confidence:g} % confidence intervals"


def write_comparison(out: Path, estimators: list[str]) -> tuple[Path, list[tuple[str, Report]]]:
    """Per-estimator reports, then ``compare.html`` (side-by-side table, overlaid RMS versus
    time) and ``compare.json`` in ``out``; returns the HTML path and each estimator's
    report."""
    out = Path(out)
    reports = [(name, write_report(out / folder_name(name))) for name in estimators]
    results = [(name, report.statistics) for name, report in reports]
    first = results[0][1]
    series = [(f"{name}: {m.metric.name}", m) for name, s in results for m in s.metrics]
    pngs = []
    if series:
        pngs.append(plots.plot_rms_versus_time(first, out / "compare_rms_vs_time.png", series))
    write_text(out / "compare.json", json.dumps(
        {name: statistics_json(s) for name, s in results}, indent=2) + "\n")
    links = "".join(f'<li><a href="{esc(folder_name(n))}/report.html">{esc(n)}</a>'
                    f"</li>" for n, _ in results)
    system = first.manifest["system"]
    body = (f"<h1>Estimator comparison: {esc(system['name'])}</h1>"
            f"<p>{esc(system['description'])}</p>"
            f"<p>Component '{COMPONENT}' runs each estimator FMU on the same seeded runs "
            f"(master seed {first.manifest['master_seed']}): identical noise realizations."
            f"</p>" + table(COMPARE_HEADER, comparison_rows(results))
            + f'<p class="note">{100 * first.confidence:g} % confidence intervals.</p>'
            + "".join(image(p) for p in pngs) + f"<h2>Reports</h2><ul>{links}</ul>")
    page = out / "compare.html"
    write_text(page, f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>"
               f"{esc(system['name'])} comparison</title><style>{STYLE}</style></head>"
               f"<body>\n{body}\n</body></html>\n")
    return page, reports
