"""``altfusion report DIR``: PNG plots, ``summary.json``, ``rms_vs_time.csv``, the estimators'
health events (``<system>.events.csv``, where the runs record their ``status``) and one
self-contained ``report.html`` (plots embedded as data URIs) for a campaign folder."""

import base64
import html
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.atomic import write_text
from altfusion.montecarlo import plots
from altfusion.montecarlo.aggregation import CampaignStatistics, aggregate
from altfusion.montecarlo.campaign_events import (
    NONE_NOTABLE,
    CampaignHealth,
    campaign_health,
    records_health,
)
from altfusion.montecarlo.tables import HEADER, confidence_note, metric_row, statistics_json
from altfusion.systems.faults import FAULTS

WORST_RUNS = 5
STYLE = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}
table{border-collapse:collapse;margin:0.5em 0 1.5em}td,th{border:1px solid #bbb;
padding:3px 8px;text-align:left;vertical-align:top;font-size:90%}th{background:#eee}
img{max-width:100%}code{background:#f4f4f4}.note{color:#555;font-size:90%}"""


@dataclass
class Report:
    html: Path
    pngs: list[Path]
    summary: Path
    statistics: CampaignStatistics
    health: CampaignHealth | None = None
    """What the estimators did over the runs, every event in a CSV (None: the runs record no
    estimator's status)."""


def esc(value: object) -> str:
    return html.escape(str(value))


def table(header: tuple[str, ...] | list[str] | None, rows: list) -> str:
    """An HTML table; without ``header``, rows only (a list of name-value pairs)."""
    head = "" if header is None else \
        "<tr>" + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr>"
    body = "".join("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in row) + "</tr>"
                   for row in rows)
    return f"<table>{head}{body}</table>"


def image(path: Path) -> str:
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    return f'<p><img alt="{esc(Path(path).name)}" src="data:image/png;base64,{data}"></p>'


def write_profiles_csv(statistics: CampaignStatistics, path: Path) -> Path:
    """time and, per metric, RMS with its bounds and the mean error, one row per output time."""
    columns, header = [statistics.time], ["time [s]"]
    for metric in statistics.metrics:
        p, name, unit = metric.profile, metric.metric.name, metric.unit
        columns += [p.rms, p.rms_low, p.rms_high, p.mean]
        header += [f"{name} RMS [{unit}]", f"{name} RMS low [{unit}]",
                   f"{name} RMS high [{unit}]", f"{name} mean [{unit}]"]
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=",".join(header),
               comments="", fmt="%.10g")
    return path


def write_plots(statistics: CampaignStatistics, folder: Path) -> list[Path]:
    pngs = []
    if statistics.metrics:
        pngs.append(plots.plot_rms_versus_time(statistics, folder / "rms_vs_time.png"))
        pngs.append(plots.plot_mean_error_versus_time(statistics,
                                                      folder / "mean_error_vs_time.png"))
        pngs.append(plots.plot_run_rms_histograms(statistics, folder / "run_rms_histogram.png"))
    if statistics.signals:
        pngs.append(plots.plot_signal_envelopes(statistics, folder / "signals.png"))
    return pngs


def write_report(out: Path) -> Report:
    """Aggregate the campaign in ``out`` and write its plots, summary and HTML report there."""
    out = Path(out)
    statistics = aggregate(out)
    pngs = write_plots(statistics, out)
    summary = out / "summary.json"
    write_text(summary, json.dumps(statistics_json(statistics), indent=2) + "\n")
    if statistics.metrics:
        write_profiles_csv(statistics, out / "rms_vs_time.csv")
    health = campaign_health(out, statistics.manifest["system"]["name"]) \
        if records_health(out) else None
    page = out / "report.html"
    write_text(page, render(statistics, pngs, out, health))
    return Report(page, pngs, summary, statistics, health)


def render(statistics: CampaignStatistics, pngs: list[Path], out: Path,
           health: CampaignHealth | None = None) -> str:
    """The report page of the campaign in ``out`` (``health``: what the estimators did over
    the runs, None where no status is recorded)."""
    manifest = statistics.manifest
    system = manifest["system"]
    parts = [f"<h1>Monte Carlo campaign: {esc(system['name'])}</h1>",
             f"<p>{esc(system['description'])}</p>", campaign_section(statistics),
             "<h2>Error metrics</h2>"]
    if statistics.metrics:
        parts.append(table(HEADER, [metric_row(m) for m in statistics.metrics]))
    parts.append(f'<p class="note">{esc(confidence_note(statistics))}. RMS and σ: square '
                 f"root of the t interval of the per-run mean squares; versus time: chi-square "
                 f"interval of a zero-mean Gaussian error's σ at each output time (log axis: "
                 f"a 0.4 m band stays visible beside a 500 m one).</p>")
    parts += [image(path) for path in pngs]
    parts += [worst_runs_section(statistics, out), health_section(health),
              failures_section(statistics),
              system_section(manifest), versions_section(manifest)]
    body = "\n".join(part for part in parts if part)
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>"
            f"{esc(system['name'])} Monte Carlo</title><style>{STYLE}</style></head>"
            f"<body>\n{body}\n</body></html>\n")


def campaign_section(statistics: CampaignStatistics) -> str:
    m = statistics.manifest
    rows = [("runs", f"{len(statistics.runs)} finished of {m['runs']}"),
            ("master seed", m["master_seed"]), ("stop time", f"{m['stop_time']:g} s"),
            ("SSP", m["ssp"]), ("SSP SHA-256", m["ssp_sha256"]),
            ("parameter overrides", ", ".join(f"{k} = {v!r}" for k, v in
                                              m["parameters"].items()) or "none"),
            ("seeded components", ", ".join(m["seeded_components"]) or "none"),
            ("started", m["created"])]
    if m.get("swap"):
        swap, effect = m["swap"], m["swap_effect"]
        rows.append(("component swap", f"{swap['component']} runs {swap['fmu']}"
                     f" ({swap['path'] or 'from the SSP'})"))
        rows += [(f"dropped {kind}", ", ".join(items))
                 for kind, items in (("connections", effect["dropped_connections"]),
                                     ("parameters", effect["dropped_parameters"]),
                                     ("recordings", effect["dropped_recordings"])) if items]
    return "<h2>Campaign</h2>" + table(None, rows)


def rerun_command(manifest: dict, out: Path, index: int) -> str:
    """The command that re-runs run ``index`` of the campaign in ``out`` alone (its settings
    come from the campaign's manifest; a fault applied with ``--fault`` is named again)."""
    name = manifest["system"]["name"]
    fault = name.rpartition("+")[2] if "+" in name else ""
    option = f" --fault {fault}" if fault in FAULTS else ""
    return f"altfusion mc {manifest['ssp']} --out {out}{option} --run {index}"


def worst_runs_section(statistics: CampaignStatistics, out: Path) -> str:
    if not statistics.metrics:
        return ""
    rows = []
    for metric in statistics.metrics:
        for k in np.argsort(-metric.run_rms, kind="stable")[:WORST_RUNS]:
            index = statistics.runs[k]
            seeds = ", ".join(f"{n} = {v}" for n, v in statistics.seeds[k].items())
            rows.append((metric.metric.name, index, f"{metric.run_rms[k]:.4g}", seeds,
                         rerun_command(statistics.manifest, out, index)))
    return ("<h2>Largest per-run RMS errors</h2>"
            + table(("metric", "run", "RMS", "seeds", "re-run alone"), rows))


def health_section(health: CampaignHealth | None) -> str:
    """What each estimator did over the runs (:mod:`.campaign_events`), with where every
    event of every run is."""
    if health is None:
        return ""
    body = table(("estimator", "in how many runs, first time's median"), health.rows) \
        if health.rows else f"<p>{esc(NONE_NOTABLE)}.</p>"
    return (f"<h2>Health events over the runs</h2>{body}"
            f'<p class="note">Read off each run\'s recorded health outputs (docs: estimator '
            f"health); every event of every run, rejections included, in "
            f"<code>{esc(health.events.name)}</code>; a run's in words: "
            f"<code>altfusion mc ... --run I</code>.</p>")


def failures_section(statistics: CampaignStatistics) -> str:
    if not statistics.failed:
        return ""
    rows = [(index, message) for index, message in sorted(statistics.failed.items())]
    return "<h2>Failed runs</h2>" + table(("run", "error"), rows)


def system_section(manifest: dict) -> str:
    system = manifest["system"]
    seeded = set(manifest["seeded_components"])
    rows = []
    for c in system["components"]:
        parameters = dict(c["parameters"])
        for key, value in manifest["parameters"].items():
            name, _, parameter = key.partition(".")
            if name == c["name"]:
                parameters[parameter] = value
        text = ", ".join(f"{k} = {v!r}" for k, v in sorted(parameters.items())) or "defaults"
        if c["name"] in seeded:
            text += "; seed derived per run"
        rows.append((c["name"], c["fmu"], f"{c['step_size']:g} s", text))
    connections = [(c["start"], c["end"]) for c in system["connections"]]
    metrics = [(m["name"], m["estimate"], m["truth"]) for m in system["metrics"]]
    return ("<h2>System</h2>"
            f"<p>base step {system['base_step']:g} s, output interval "
            f"{system['output_interval'] or system['base_step']:g} s, "
            f"start {system['start_time']:g} s</p>"
            + table(("component", "FMU", "step", "parameters"), rows)
            + "<h3>Connections</h3>" + table(("output", "input"), connections)
            + "<h3>Error metrics (estimate - truth)</h3>"
            + table(("metric", "estimate", "truth"), metrics)
            + "<h3>Recorded signals</h3><p>"
            + esc(", ".join(system["record"]) or "all outputs") + "</p>")


def versions_section(manifest: dict) -> str:
    rows = list(manifest["versions"].items())
    later = [s for s in manifest.get("sessions", [])[1:] if s["versions"] != manifest["versions"]]
    note = "".join(f'<p class="note">resumed {esc(s["started"])} with other versions: '
                   f'{esc(s["versions"])}</p>' for s in later)
    return "<h2>Package versions</h2>" + table(("package", "version"), rows) + note
