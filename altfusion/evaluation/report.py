"""The outputs of ``altfusion evaluate``: the text table (printed), ``evaluation.md`` (the
matrices and the table in markdown), ``evaluation.html`` (self-contained: heat maps estimator
x scenario of the RMS, coloured by its ratio to the column's best, and of the coverage, each
cell linked to its plot; the table; one plot per cell as an embedded PNG) and
``evaluation_summary.json``.

Of several ``--told`` variants (:mod:`altfusion.evaluation.told`): the matrices and heat maps
show told ``noise`` and told ``models`` side by side (those evaluated), a robustness table
(:mod:`altfusion.evaluation.robustness`) shows told ``nothing`` and ``misstated``; the full
table and the plots are of the primary variant (:func:`primary`: ``models`` when evaluated),
the summary has every variant."""

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
from altfusion.evaluation.metrics import (  # noqa: E402
    RECOVERY_WINDOW,
    STARTUP_TIME,
    Summary,
    trailing_rms,
)
from altfusion.evaluation.robustness import (  # noqa: E402
    Robustness,
    robustness,
    robustness_measure,
)
from altfusion.evaluation.run import METRICS, Cell, Cells, estimator_cell  # noqa: E402
from altfusion.evaluation.scenarios import PAPER_SCENARIOS, Scenario  # noqa: E402
from altfusion.evaluation.told import DEFAULT_TOLD, MODELS, NOISE, Told  # noqa: E402
from altfusion.montecarlo.report import STYLE, esc  # noqa: E402
from altfusion.scores import COVERAGE_SIGMAS, HONEST_COVERAGE, RMS_DEFINITION  # noqa: E402

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


LEGEND = (f"{RMS_DEFINITION}, ± the standard deviation of the per-run RMS; the other "
          f"metrics: mean ± standard deviation over runs; (n=k): over k runs, (n=k of N): "
          f"only k of the N runs gave a value; start-up: the first {STARTUP_TIME:g} s after "
          f"the estimator's first fused sample; max |e|: after the start-up; coverage: "
          f"|e| <= {COVERAGE_SIGMAS:g} h_std outside the fault transient; valid: h_valid "
          f"true; isolate: fault start to the faulty source's ISOLATED bit; recover: fault "
          f"start (or the end of the start-up, if later) to the error back within 3x the "
          f"nominal RMS (or h_valid false); never: no run; -: no fault")


def best_rms(cells: list[Cell]) -> float:
    """The column's best (smallest) mean RMS (nan if no estimator ran)."""
    values = [c.rms for c in cells if math.isfinite(c.rms)]
    return min(values) if values else math.nan


def _markdown_table(header: list[str], body: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |"
              for row in body]
    return "\n".join(lines)


def matrix_value(cell: Cell, metric: str, best: float | None = None) -> str:
    """A matrix's text of a cell: the mean RMS in m (with its ratio to the column's
    ``best``, if given) or the mean coverage in %; n/a where not applicable, - without a
    finite value."""
    summary = cell.summary(metric) if cell.runs else None
    if cell.not_applicable:
        return NA
    if summary is None or not summary.finite:
        return "-"
    if metric != "rms":
        return f"{100 * summary.mean:.0f} %"
    if best is not None and best > 0:
        return f"{summary.mean:.3g} (x{summary.mean / best:.3g})"
    return f"{summary.mean:.3g}"


def matrix_markdown(variants: list[Cells], estimators: list[str], metric: str) -> str:
    """Estimators (rows) x scenarios (columns) of ``metric`` in one or more ``variants`` of
    the evaluation: of one, the mean RMS in m with its ratio to the column's best, or the
    mean coverage in %; of several, their values side by side ('a / b')."""
    body = []
    for estimator in estimators:
        row = [estimator]
        for name, column in variants[0].items():
            if len(variants) == 1:
                row.append(matrix_value(estimator_cell(column, estimator), metric,
                                        best_rms(column) if metric == "rms" else None))
            else:
                row.append(" / ".join(matrix_value(estimator_cell(cells[name], estimator),
                                                   metric) for cells in variants))
        body.append(row)
    return _markdown_table(["estimator", *variants[0]], body)


def side_by_side(results: dict[Told, Cells]) -> list[Told]:
    """The variants the RMS and coverage matrices show side by side: told the noise and told
    the models, those evaluated (of neither, the first variant)."""
    return [told for told in results if told.mode in (NOISE, MODELS)] or list(results)[:1]


def primary(results: dict[Told, Cells]) -> Told:
    """The variant of the full table and the per-cell plots: ``models`` when evaluated."""
    return side_by_side(results)[-1]


def told_markdown(results: dict[Told, Cells]) -> str:
    """The variants evaluated and what each told (nothing for the default alone)."""
    if list(results) == [DEFAULT_TOLD]:
        return ""
    return "What the estimators were told:\n\n" + "\n".join(
        f"* {told.label}: {told.description}" for told in results) + "\n\n"


def robustness_markdown(results: dict[Told, Cells], estimators: list[str]) -> str:
    """The robustness table (estimator and variant x scenarios), if nothing or misstated was
    evaluated."""
    rows = robustness(results, estimators)
    if not rows:
        return ""
    return (f"\n\nRobustness: each estimator told nothing or every noise misstated, in each "
            f"scenario: {robustness_measure(results)}, and its coverage. The paper's "
            f"estimator is evaluated as an observer told so (the system's own flies on the "
            f"paper's parameters):\n\n"
            + _markdown_table(["estimator", "told", *results[rows[0][1]]],
                              [[estimator, told.label, *(r.text() for r in row.values())]
                               for estimator, told, row in rows]))


def format_markdown(results: dict[Told, Cells], estimators: list[str],
                    scenarios: list[Scenario], settings: dict) -> str:
    """``evaluation.md``: the RMS and coverage matrices (told the noise and the models side
    by side, as evaluated), the robustness table, the scenarios, the full table of the
    primary variant."""
    shown = side_by_side(results)
    main = primary(results)
    cells = results[main]
    told = "" if len(results) == 1 else f", told {' / '.join(t.label for t in shown)}"
    ratio = "; in brackets: over the column's best" if len(shown) == 1 else ""
    described = "\n".join(f"* `{s.name}`: {s.description}" + (f" {s.note}" if s.note else "")
                          for s in scenarios)
    not_applicable = sorted({(c.estimator, c.not_applicable) for column in cells.values()
                             for c in column if c.not_applicable})
    reasons = "\n".join(f"* {e}: {r}" for e, r in dict.fromkeys(not_applicable))
    variants = [results[t] for t in shown]
    return (
        told_markdown(results)
        + f"RMS error [m] of each estimator in each scenario{told} (mean over "
          f"{settings['runs']} runs{ratio}):\n\n"
        + matrix_markdown(variants, estimators, "rms")
        + f"\n\nCoverage{told} (|e| <= {COVERAGE_SIGMAS:g} h_std outside the fault transient; "
          f"an honest h_std gives about 95 %, the fault suite asks for 85 % to 99.5 %):\n\n"
        + matrix_markdown(variants, estimators, "coverage")
        + robustness_markdown(results, estimators)
        + "\n\nScenarios:\n\n" + described
        + ("\n\nNot applicable (never run on defaults):\n\n" + reasons if reasons else "")
        + f"\n\nEvery metric{'' if len(results) == 1 else f', told {main.label}'} (mean ± "
          f"standard deviation over runs):\n\n"
        + _markdown_table(list(COLUMNS), [list(r) for r in rows(cells)])
        + f"\n\n{LEGEND}.\n")


PLOT_DPI = 100
"""Per-cell plots are drawn at 100 dpi and shown at their pixel size: 9 pt text is 12.5 px."""
PLOT_SIZE = (5.3, 4.0)
"""Inches of a per-cell plot, legend under the axes: two side by side fill the page."""
RATIO_STEPS = (1.0, 1.5, 3.0, 10.0, 30.0, 100.0)
"""Colour steps of the RMS heat map, as ratios to the column's best (x1 ... x100 and over)."""
COVERAGE_STEPS = ((0.0, "below 50 %", "#d73027"), (0.5, "50-85 %", "#fc8d59"),
                  (HONEST_COVERAGE[0], "85-99.5 % (honest)", "#91cf60"),
                  (HONEST_COVERAGE[1], "above 99.5 % (h_std too large)", "#9ecae1"))
"""Colour of a coverage: (lower bound, label, colour); 85-99.5 % is the fault suite's honest
h_std."""


def _png(fig) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=PLOT_DPI)
    plt.close(fig)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


def cell_id(scenario: str, estimator: str) -> str:
    """The HTML id of a cell's plot."""
    return f"cell-{scenario}-{estimator}"


def ratio_colour(ratio: float) -> str:
    """The heat map's colour of an RMS ``ratio`` to the column's best: green at x1 through
    yellow (x3-x10) to red at x100 and over, on a log scale."""
    position = min(max(math.log10(max(ratio, 1.0)) / 2.0, 0.0), 1.0)
    return matplotlib.colors.to_hex(plt.get_cmap("RdYlGn_r")(0.1 + 0.8 * position))


def coverage_colour(coverage: float) -> str:
    return next(colour for low, _, colour in reversed(COVERAGE_STEPS) if coverage >= low)


def best_coverage(cells: list[Cell]) -> float:
    """The column's coverage nearest the 95.4 % of an honest Gaussian h_std (nan if none)."""
    values = [s.mean for c in cells if c.runs and (s := c.summary("coverage")) is not None
              and math.isfinite(s.mean)]
    honest = math.erf(COVERAGE_SIGMAS / math.sqrt(2.0))
    return min(values, key=lambda v: abs(v - honest)) if values else math.nan


def _heat_cell(cell: Cell, metric: str, best: float, linked: bool) -> str:
    summary = cell.summary(metric) if cell.runs else None
    if cell.not_applicable:
        return f'<td class="off" title="{esc(cell.not_applicable)}">{NA}</td>'
    if summary is None or not math.isfinite(summary.mean):
        return '<td class="off">-</td>'
    value = summary.mean
    if metric == "rms":
        text, colour = f"{value:.3g}", ratio_colour(value / best if best > 0 else 1.0)
        tip = f"x{value / best:.3g} the best" if best > 0 else ""
    else:
        text, colour, tip = f"{100 * value:.0f} %", coverage_colour(value), ""
    marked = value == best
    text += " ★" if marked else ""
    link = f'<a href="#{esc(cell_id(cell.scenario, cell.estimator))}">{text}</a>' if linked \
        else text
    title = f"{cell.estimator} in {cell.scenario}: {summary.format(**FORMATS[metric])}" + \
        (f", {tip}" if tip else "")
    return (f'<td class="{"best" if marked else ""}" style="background:{colour}" '
            f'title="{esc(title)}">{link}</td>')


def heat_table(variants: dict[str, Cells], estimators: list[str], metric: str,
               linked: str) -> str:
    """A heat map as an HTML table, estimators (rows) x scenarios (columns): the mean RMS
    (coloured by its ratio to the column's best) or coverage (coloured by honesty), the
    column's best marked ★, each column a link to its section. Of several ``variants``
    (label -> cells), adjacent columns per scenario, one per variant. The cells of the
    variant ``linked`` link to their plots."""
    names = list(variants[linked])
    several = len(variants) > 1
    span = f' colspan="{len(variants)}"' if several else ""
    head = "".join(f'<th{span}><a href="#{esc(name)}">{esc(name)}</a></th>' for name in names)
    labels = "<tr>" + "".join(f"<th>{esc(label)}</th>" for _ in names
                              for label in variants) + "</tr>" if several else ""
    best = {(label, name): best_rms(column) if metric == "rms" else best_coverage(column)
            for label, cells in variants.items() for name, column in cells.items()}
    body = []
    for estimator in estimators:
        row = "".join(_heat_cell(estimator_cell(cells[name], estimator), metric,
                                 best[label, name], label == linked)
                      for name in names for label, cells in variants.items())
        body.append(f"<tr><th>{esc(estimator)}</th>{row}</tr>")
    corner = '<th rowspan="2"></th>' if several else "<th></th>"
    return f'<table class="heat"><tr>{corner}{head}</tr>{labels}{"".join(body)}</table>'


def ratio_legend() -> str:
    """The RMS heat map's colour key, in ratios to the column's best."""
    steps = "".join(f'<span style="background:{ratio_colour(r)}">x{r:g}'
                    f'{" and over" if r == RATIO_STEPS[-1] else ""}</span>'
                    for r in RATIO_STEPS)
    return f'<p class="key">colour: RMS over the column\'s best {steps} ★ the best</p>'


def coverage_legend() -> str:
    steps = "".join(f'<span style="background:{colour}">{esc(label)}</span>'
                    for _, label, colour in COVERAGE_STEPS)
    return (f'<p class="key">colour: coverage {steps} ★ nearest the 95.4 % of an honest '
            f'Gaussian h_std</p>')


def trailing_errors(cell: Cell) -> np.ndarray:
    """Each run's error as its RMS over the trailing :data:`RECOVERY_WINDOW` s (the quantity
    the recovery is judged on): positive, so it reads on a log axis, and smooth enough to
    read where a noisy error would fill the plot."""
    return np.vstack([trailing_rms(cell.time, error, RECOVERY_WINDOW) for error in cell.errors])


def scenario_scale(cells: list[Cell]) -> tuple[float, float]:
    """One log y-scale (low, high) for every plot of a scenario: from half the smallest 1st
    percentile to twice the largest 99.5th percentile of the cells' trailing RMS after the
    start-up (a 0.4 m error and a 500 m one on the same axis)."""
    lows, highs = [], []
    for cell in cells:
        if cell.errors is None:
            continue
        after = trailing_errors(cell)[:, cell.time >= cell.startup_end]
        finite = after[np.isfinite(after) & (after > 0)]
        if finite.size:
            lows.append(float(np.percentile(finite, 1.0)))
            highs.append(float(np.percentile(finite, 99.5)))
    if not highs:
        return 1e-3, 1.0
    return max(0.5 * min(lows), 1e-4), 2.0 * max(highs)


Margins = dict[str, float]
"""A figure's subplot margins (left, right, bottom, top) as fractions of its size."""


def cell_figure(cell: Cell, scenario: Scenario, scale: tuple[float, float],
                margins: Margins | None = None):
    """Every run's error as its trailing RMS (thin), the RMS over runs (bold) and 2x the
    mean h_std (dashed) versus time, on the scenario's log ``scale``; the start-up, fault
    start and transient marked; every mark in the legend, under the plot. Laid out tight,
    or with the ``margins`` of another cell of the scenario (the same axes, scale and
    legend: the same layout, without the cost of finding it, which draws the figure)."""
    fig, ax = plt.subplots(figsize=PLOT_SIZE)
    runs = cell.errors.shape[0]
    trailing = trailing_errors(cell)
    for k, error in enumerate(trailing):
        ax.plot(cell.time, error, color="tab:blue", linewidth=0.6, alpha=0.5,
                label=f"each run (n={runs})" if k == 0 else None)
    ax.plot(cell.time, np.sqrt(np.mean(trailing**2, axis=0)), color="black", linewidth=1.2,
            label="RMS over runs")
    ax.plot(cell.time, COVERAGE_SIGMAS * np.mean(cell.h_std, axis=0), "r--", linewidth=1.0,
            label=f"{COVERAGE_SIGMAS:g} h_std (mean over runs)")
    ax.axvspan(cell.time[0], min(cell.startup_end, cell.time[-1]), color="0.85", linewidth=0,
               label="start-up (no max |e|, recover)")
    if scenario.fault is not None:
        ax.axvspan(scenario.fault.start, scenario.fault.start + scenario.fault.transient,
                   color="orange", alpha=0.2, linewidth=0, label="fault transient (no coverage)")
        ax.axvline(scenario.fault.start, color="darkorange", linewidth=1.0,
                   label=f"fault start {scenario.fault.start:g} s")
    ax.set_yscale("log")
    ax.set_ylim(*scale)
    ax.set_xlim(cell.time[0], cell.time[-1])
    ax.set_title(f"{cell.estimator} in {cell.scenario}", fontsize=10)
    ax.set_xlabel("time [s]", fontsize=9)
    ax.set_ylabel(f"|error| [m], RMS over {RECOVERY_WINDOW:g} s", fontsize=9)
    ax.tick_params(labelsize=8)
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.22), ncols=2,
              frameon=False)
    if margins is None:
        fig.tight_layout()
    else:
        fig.subplots_adjust(**margins)
    return fig


def figure_margins(fig) -> Margins:
    """The subplot margins of ``fig`` (:func:`cell_figure`'s ``margins``)."""
    return {side: getattr(fig.subplotpars, side) for side in ("left", "right", "bottom", "top")}


def _image(data: str, alt: str) -> str:
    return f'<img alt="{esc(alt)}" src="data:image/png;base64,{data}">'


def _scenario_section(scenario: Scenario, cells: list[Cell]) -> str:
    scale = scenario_scale(cells)
    margins: Margins | None = None
    plots = []
    for cell in cells:
        anchor = esc(cell_id(cell.scenario, cell.estimator))
        if cell.not_applicable:
            plots.append(f'<div class="na" id="{anchor}">{esc(cell.estimator)}: {NA} '
                         f'({esc(cell.not_applicable)})</div>')
        elif cell.errors is not None:
            row = dict(zip(COLUMNS, cell_row(cell), strict=True))
            caption = "; ".join(f"{k} {v}" for k, v in row.items() if k not in (
                "scenario", "estimator", "runs"))
            alt = f"{cell.estimator} in {scenario.name}"
            fig = cell_figure(cell, scenario, scale, margins)
            margins = margins or figure_margins(fig)
            plots.append(f'<figure id="{anchor}">{_image(_png(fig), alt)}'
                         f"<figcaption>{esc(caption)}</figcaption></figure>")
    note = f" {esc(scenario.note)}" if scenario.note else ""
    return (f"<h3 id=\"{esc(scenario.name)}\">{esc(scenario.name)}</h3>"
            f"<p>{esc(scenario.description)}{note}</p>{''.join(plots)}")


def scenario_groups(names: list[str]) -> list[tuple[str, list[str]]]:
    """The paper scenarios and the fault suite among ``names``, each (title, names): shown
    one above the other (a single table of 22 columns would not fit the page)."""
    groups = [("paper scenarios", [n for n in names if n in PAPER_SCENARIOS]),
              ("fault suite", [n for n in names if n not in PAPER_SCENARIOS])]
    return [(title, group) for title, group in groups if group]


def _heat_maps(variants: dict[str, Cells], estimators: list[str], metric: str,
               linked: str) -> str:
    """The heat maps of the paper scenarios and of the fault suite."""
    return "".join(f'<h3>{title}</h3><div class="wide">' + heat_table(
        {label: {n: column[n] for n in names} for label, column in variants.items()},
        estimators, metric, linked) + "</div>"
        for title, names in scenario_groups(list(variants[linked])))


def _robustness_cell(robust: Robustness) -> str:
    if robust.not_applicable:
        return f'<td class="off" title="{esc(robust.not_applicable)}">{NA}</td>'
    if not math.isfinite(robust.coverage):
        return f"<td>{esc(robust.text())}</td>"
    return f'<td style="background:{coverage_colour(robust.coverage)}">{esc(robust.text())}</td>'


def robustness_html(results: dict[Told, Cells], estimators: list[str]) -> str:
    """The robustness tables of the paper scenarios and of the fault suite, each cell
    coloured by its coverage's honesty ('' if neither nothing nor misstated was
    evaluated)."""
    rows = robustness(results, estimators)
    if not rows:
        return ""
    tables = []
    for title, names in scenario_groups(list(rows[0][2])):
        head = "".join(f"<th>{esc(name)}</th>" for name in names)
        body = "".join(f"<tr><th>{esc(estimator)}</th><th>{esc(told.label)}</th>"
                       + "".join(_robustness_cell(row[n]) for n in names) + "</tr>"
                       for estimator, told, row in rows)
        tables.append(f'<h3>{title}</h3><div class="wide"><table class="heat"><tr><th></th>'
                      f"<th>told</th>{head}</tr>{body}</table></div>")
    return (f"<h2>Robustness</h2><p class=\"note\">Each estimator told nothing or every noise "
            f"misstated: {esc(robustness_measure(results))}, and its coverage (coloured as "
            f"above). The paper's estimator is evaluated as an observer told so.</p>"
            + "".join(tables))


PAGE_STYLE = ("body{max-width:1240px}.heat td,.heat th{font-size:13px;padding:4px 5px;"
              "text-align:center;white-space:nowrap}.heat td{min-width:56px}"
              ".heat tr:first-child th{writing-mode:vertical-rl;transform:rotate(180deg);"
              "text-align:left;vertical-align:bottom}.heat tr>th:first-child{text-align:left}"
              ".heat td a{color:#000;text-decoration:none}.heat td.best{font-weight:bold;"
              "outline:2px solid #000;outline-offset:-2px}.heat td.off{background:#ddd;"
              "color:#666}"
              ".key span{display:inline-block;padding:2px 8px;margin:0 2px;font-size:13px}"
              ".wide{overflow-x:auto}figure{display:inline-block;margin:0.4em;"
              "vertical-align:top;width:530px}figcaption{font-size:12px;color:#444}"
              "figure img{width:530px;height:400px}.na{display:inline-block;width:300px;color:#777;"
              "font-size:85%;vertical-align:top;margin:1em}")


def write_html(path: Path, results: dict[Told, Cells], estimators: list[str],
               scenarios: list[Scenario], settings: dict) -> Path:
    """``evaluation.html``: the RMS and coverage heat maps (told the noise and the models
    side by side, as evaluated), the robustness table, the table, then per scenario a plot
    per cell (of the primary variant)."""
    main = primary(results)
    cells = results[main]
    variants = {told.label: results[told] for told in side_by_side(results)}
    told = "" if len(results) == 1 else "".join(
        f"<li>{esc(t.label)}: {esc(t.description)}</li>" for t in results)
    header = "".join(f"<th>{esc(h)}</th>" for h in COLUMNS)
    body = "".join("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in row[:3])
                   + (f'<td colspan="{len(row) - 3}">{esc(row[3])}</td>' if row[2] == NA
                      else "".join(f"<td>{esc(c)}</td>" for c in row[3:])) + "</tr>"
                   for row in rows(cells))
    sections = "".join(_scenario_section(s, cells[s.name]) for s in scenarios)
    page = (
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>altfusion evaluation"
        f"</title><style>{STYLE}{PAGE_STYLE}</style></head><body>\n"
        f"<h1>Estimator evaluation</h1><p>{settings['runs']} runs per scenario (master seed "
        f"{settings['master_seed']}, backend {esc(settings['backend'])}); every estimator of "
        f"a scenario reads the same sensor outputs in each run. A cell links to its plot, a "
        f"scenario to its section.</p>"
        + (f"<p>What the estimators were told (plots and the table: {esc(main.label)}):</p>"
           f"<ul>{told}</ul>" if told else "")
        + f"<h2>RMS error [m]</h2><p class=\"note\">{esc(RMS_DEFINITION)}.</p>"
        f"{ratio_legend()}{_heat_maps(variants, estimators, 'rms', main.label)}"
        f"<h2>Coverage</h2><p class=\"note\">|e| <= {COVERAGE_SIGMAS:g} h_std outside the "
        f"fault transient: an honest h_std gives about 95 %.</p>{coverage_legend()}"
        f"{_heat_maps(variants, estimators, 'coverage', main.label)}"
        f"{robustness_html(results, estimators)}"
        f"<h2>Every metric</h2><table><tr>{header}</tr>{body}</table>"
        f"<p class=\"note\">{esc(LEGEND)}</p>"
        f"<h2>Error versus time, per cell</h2>{sections}\n</body></html>\n")
    return write_text(path, page)


def _summary_entry(cell: Cell) -> dict:
    if cell.not_applicable:
        return {"not_applicable": cell.not_applicable}
    return {metric: (None if (s := cell.summary(metric)) is None else
                     {"mean": _finite(s.mean), "std": _finite(s.std), "finite": s.finite,
                      "runs": s.runs}) for metric in METRICS}


def summary_json(results: dict[Told, Cells]) -> str:
    """Every cell's summaries (mean, std, finite runs, runs) or its n/a reason, by variant
    (:attr:`Told.name`), scenario and estimator, as JSON."""
    data = {told.name: {scenario: {cell.estimator: _summary_entry(cell) for cell in column}
                        for scenario, column in cells.items()}
            for told, cells in results.items()}
    return json.dumps(data, indent=2) + "\n"


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None
