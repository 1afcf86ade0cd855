"""The outputs of ``altfusion evaluate``: the text table (printed), ``evaluation.md`` (the
matrices and the table in markdown), ``evaluation.html`` (self-contained: a heat map estimator
x scenario coloured by RMS over the column's best, and one plot per cell as an embedded PNG)
and ``evaluation_summary.json``."""

import base64
import io
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from altfusion.atomic import write_text  # noqa: E402
from altfusion.evaluation.metrics import Summary  # noqa: E402
from altfusion.evaluation.run import METRICS, Cell  # noqa: E402
from altfusion.evaluation.scenarios import Scenario  # noqa: E402
from altfusion.montecarlo.report import STYLE, esc  # noqa: E402
from altfusion.scores import COVERAGE_SIGMAS  # noqa: E402

NA = "n/a"
COLUMNS = ("scenario", "estimator", "runs", "RMS [m]", "max |e| [m]", "coverage",
           "valid", "isolate [s]", "recover [s]")
FORMATS = {"rms": {"unit": ""}, "max_abs": {"unit": ""}, "coverage": {"percent": True},
           "valid_fraction": {"percent": True}, "time_to_isolate": {"unit": ""},
           "time_to_recover": {"unit": ""}}


def _format(summary: Summary | None, metric: str) -> str:
    return "-" if summary is None else summary.format(**FORMATS[metric])


def cell_row(cell: Cell) -> tuple[str, ...]:
    """The table row of a cell: its metrics as 'mean ± spread', or n/a with the reason."""
    if cell.not_applicable:
        return (cell.scenario, cell.estimator, NA, f"{NA}: {cell.not_applicable}", "", "",
                "", "", "")
    if not cell.runs:
        return (cell.scenario, cell.estimator, "0", "no finished run", "", "", "", "", "")
    return (cell.scenario, cell.estimator, str(len(cell.runs)),
            *(_format(cell.summary(m), m) for m in METRICS))


def rows(cells: dict[str, list[Cell]]) -> list[tuple[str, ...]]:
    return [cell_row(cell) for scenario_cells in cells.values() for cell in scenario_cells]


def format_text(cells: dict[str, list[Cell]]) -> str:
    """The table as aligned text (n/a rows carry their reason in the RMS column)."""
    table = [COLUMNS, *rows(cells)]
    widths = [max(len(r[i]) for r in table if r[2] != NA or i < 3)
              for i in range(len(COLUMNS))]
    lines = []
    for row in table:
        if row[2] == NA:
            lines.append("  ".join(c.ljust(w) for c, w in zip(row[:3], widths, strict=False))
                         + "  " + row[3])
        else:
            lines.append("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True))
                         .rstrip())
    return "\n".join(lines) + f"\n{LEGEND}"


LEGEND = (f"mean ± standard deviation over runs; coverage: |e| <= {COVERAGE_SIGMAS:g} h_std "
          f"outside the fault transient; valid: h_valid true; isolate: fault start to the "
          f"faulty source's ISOLATED bit; recover: fault start to the error back within 3x "
          f"the nominal RMS (or h_valid false); (k/N): k of N runs; never: no run; "
          f"-: no fault")


def best_rms(cells: list[Cell]) -> float:
    """The column's best (smallest) mean RMS (nan if no estimator ran)."""
    values = [c.rms for c in cells if math.isfinite(c.rms)]
    return min(values) if values else math.nan


def ratio_matrix(cells: dict[str, list[Cell]], estimators: list[str]) -> np.ndarray:
    """RMS over the column's best: estimators (rows) x scenarios (columns), nan for n/a."""
    matrix = np.full((len(estimators), len(cells)), np.nan)
    for j, column in enumerate(cells.values()):
        best = best_rms(column)
        for cell in column:
            if math.isfinite(cell.rms) and best > 0:
                matrix[estimators.index(cell.estimator), j] = cell.rms / best
    return matrix


def _markdown_table(header: list[str], body: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |"
              for row in body]
    return "\n".join(lines)


def matrix_markdown(cells: dict[str, list[Cell]], estimators: list[str], metric: str) -> str:
    """Estimators (rows) x scenarios (columns) of ``metric``: the mean RMS in m with its
    ratio to the column's best, or the mean coverage in %; n/a where not applicable."""
    body = []
    for estimator in estimators:
        row = [estimator]
        for column in cells.values():
            cell = next(c for c in column if c.estimator == estimator)
            summary = cell.summary(metric) if cell.runs else None
            if cell.not_applicable:
                row.append(NA)
            elif summary is None or not summary.finite:
                row.append("-")
            elif metric == "rms":
                best = best_rms(column)
                row.append(f"{summary.mean:.3g} (x{summary.mean / best:.3g})" if best > 0
                           else f"{summary.mean:.3g}")
            else:
                row.append(f"{100 * summary.mean:.0f} %")
        body.append(row)
    return _markdown_table(["estimator", *cells], body)


def format_markdown(cells: dict[str, list[Cell]], estimators: list[str],
                    scenarios: list[Scenario], settings: dict) -> str:
    """``evaluation.md``: the RMS and coverage matrices, the scenarios, the full table."""
    described = "\n".join(f"* `{s.name}`: {s.description}" + (f" {s.note}" if s.note else "")
                          for s in scenarios)
    not_applicable = sorted({(c.estimator, c.not_applicable) for column in cells.values()
                             for c in column if c.not_applicable})
    reasons = "\n".join(f"* {e}: {r}" for e, r in dict.fromkeys(not_applicable))
    return (
        f"RMS error [m] of each estimator in each scenario (mean over {settings['runs']} "
        f"runs; in brackets: over the column's best):\n\n"
        + matrix_markdown(cells, estimators, "rms")
        + f"\n\nCoverage (|e| <= {COVERAGE_SIGMAS:g} h_std outside the fault transient; an "
          f"honest h_std gives about 95 %, the fault suite asks for 85 % to 99.5 %):\n\n"
        + matrix_markdown(cells, estimators, "coverage")
        + "\n\nScenarios:\n\n" + described
        + ("\n\nNot applicable (never run on defaults):\n\n" + reasons if reasons else "")
        + "\n\nEvery metric (mean ± standard deviation over runs):\n\n"
        + _markdown_table(list(COLUMNS), [list(r) for r in rows(cells)])
        + f"\n\n{LEGEND}.\n")


def _png(fig) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=72)
    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def heat_map(cells: dict[str, list[Cell]], estimators: list[str]) -> str:
    """The heat map as a base64 PNG: colour = RMS over the column's best (log scale), grey
    for n/a, the mean RMS written in each cell."""
    matrix = ratio_matrix(cells, estimators)
    fig, ax = plt.subplots(figsize=(1.0 + 0.9 * len(cells), 0.8 + 0.45 * len(estimators)))
    shown = np.ma.masked_invalid(np.log10(np.maximum(matrix, 1.0)))
    colours = plt.get_cmap("RdYlGn_r").copy()
    colours.set_bad("#cccccc")
    image = ax.imshow(shown, cmap=colours, vmin=0.0, vmax=max(1.0, float(np.nanmax(
        np.log10(np.maximum(matrix, 1.0)), initial=1.0))), aspect="auto")
    for j, column in enumerate(cells.values()):
        for cell in column:
            i = estimators.index(cell.estimator)
            text = NA if cell.not_applicable else (f"{cell.rms:.3g}" if math.isfinite(cell.rms)
                                                   else "-")
            ax.text(j, i, text, ha="center", va="center", fontsize=7)
    ax.set_xticks(range(len(cells)), list(cells), rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(len(estimators)), estimators, fontsize=8)
    bar = fig.colorbar(image, ax=ax)
    bar.set_label("log10(RMS / column's best)", fontsize=8)
    ax.set_title("RMS error [m]; colour: RMS over the best in the scenario", fontsize=9)
    fig.tight_layout()
    return _png(fig)


def cell_plot(cell: Cell, scenario: Scenario) -> str:
    """Error of every run versus time (thin), the RMS over runs (bold) and ± 2 mean h_std
    (dashed); the fault start and transient marked."""
    fig, ax = plt.subplots(figsize=(4.2, 2.4))
    for error in cell.errors:
        ax.plot(cell.time, error, color="tab:blue", linewidth=0.4, alpha=0.35)
    ax.plot(cell.time, np.sqrt(np.mean(cell.errors**2, axis=0)), color="black",
            linewidth=1.0, label="RMS")
    band = COVERAGE_SIGMAS * np.mean(cell.h_std, axis=0)
    ax.plot(cell.time, band, "r--", linewidth=0.8, label=f"±{COVERAGE_SIGMAS:g} h_std")
    ax.plot(cell.time, -band, "r--", linewidth=0.8)
    if scenario.fault is not None:
        ax.axvspan(scenario.fault.start, scenario.fault.start + scenario.fault.transient,
                   color="orange", alpha=0.15, linewidth=0)
        ax.axvline(scenario.fault.start, color="orange", linewidth=0.8)
    finite = cell.errors[np.isfinite(cell.errors)]
    if finite.size:
        limit = 1.2 * max(float(np.percentile(np.abs(finite), 99.5)), 1e-3)
        ax.set_ylim(-limit, limit)
    ax.set_title(f"{cell.estimator} - {cell.scenario}", fontsize=8)
    ax.set_xlabel("time [s]", fontsize=7)
    ax.set_ylabel("error [m]", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=6, loc="upper right")
    fig.tight_layout()
    return _png(fig)


def _image(data: str, alt: str) -> str:
    return f'<img alt="{esc(alt)}" src="data:image/png;base64,{data}">'


def write_html(path: Path, cells: dict[str, list[Cell]], estimators: list[str],
               scenarios: list[Scenario], settings: dict) -> Path:
    """``evaluation.html``: heat map, the table, then per scenario a plot per cell."""
    header = "".join(f"<th>{esc(h)}</th>" for h in COLUMNS)
    body = "".join("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in row) + "</tr>"
                   for row in rows(cells))
    sections = []
    for scenario in scenarios:
        plots = []
        for cell in cells[scenario.name]:
            if cell.not_applicable:
                plots.append(f'<div class="na">{esc(cell.estimator)}: {NA} '
                             f'({esc(cell.not_applicable)})</div>')
            elif cell.errors is not None:
                plots.append(_image(cell_plot(cell, scenario),
                                    f"{cell.estimator} in {scenario.name}"))
        note = f" {esc(scenario.note)}" if scenario.note else ""
        sections.append(f"<h3 id=\"{esc(scenario.name)}\">{esc(scenario.name)}</h3>"
                        f"<p>{esc(scenario.description)}{note}</p>{''.join(plots)}")
    page = (
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>altfusion evaluation"
        f"</title><style>{STYLE}.na{{display:inline-block;width:300px;color:#777;"
        f"font-size:85%;vertical-align:top;margin:1em}}</style></head><body>\n"
        f"<h1>Estimator evaluation</h1><p>{settings['runs']} runs per scenario (master seed "
        f"{settings['master_seed']}, backend {esc(settings['backend'])}); every estimator of "
        f"a scenario reads the same sensor outputs in each run.</p>"
        f"{_image(heat_map(cells, estimators), 'heat map')}"
        f"<table><tr>{header}</tr>{body}</table><p class=\"note\">{esc(LEGEND)}</p>"
        f"<h2>Error versus time, per cell</h2>{''.join(sections)}\n</body></html>\n")
    return write_text(path, page)


def summary_json(cells: dict[str, list[Cell]]) -> str:
    """Every cell's summaries (mean, std, finite runs, runs) or its n/a reason, as JSON."""
    data: dict = {}
    for scenario, column in cells.items():
        for cell in column:
            entry: dict = {"not_applicable": cell.not_applicable} if cell.not_applicable else {
                metric: (None if (s := cell.summary(metric)) is None else
                         {"mean": _finite(s.mean), "std": _finite(s.std), "finite": s.finite,
                          "runs": s.runs}) for metric in METRICS}
            data.setdefault(scenario, {})[cell.estimator] = entry
    return json.dumps(data, indent=2) + "\n"


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None
