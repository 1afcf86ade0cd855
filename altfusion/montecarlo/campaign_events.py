"""The health events (:mod:`altfusion.health_events`) of a campaign's stored runs: written to
``<campaign>/<name>.events.csv`` (one row per event, with its run) and said in a line per
estimator: in how many runs it isolated, re-admitted, fell back, reset its height or lost
its validity, and at what median time."""

import statistics
from pathlib import Path

from altfusion.health_events import (
    FALLBACK,
    HEIGHT_RESET,
    INVALID,
    ISOLATED,
    READMITTED,
    HealthEvent,
    health_events,
    write_events,
)
from altfusion.montecarlo.storage import finished_runs, load_run

NOTABLE = (ISOLATED, FALLBACK, READMITTED, HEIGHT_RESET, INVALID)
"""The events a campaign's summary counts (rejections and start-ups are in the CSV)."""


def campaign_events(folder: Path) -> dict[int, list[HealthEvent]]:
    """Run index -> its events, for every finished run in ``folder``."""
    return {index: health_events(load_run(folder, index).results)
            for index in finished_runs(folder)}


def write_campaign_events(folder: Path, name: str,
                          by_run: dict[int, list[HealthEvent]]) -> Path:
    """``folder/<name>.events.csv``: every event of every run, the run index first."""
    events = [event for index in sorted(by_run) for event in by_run[index]]
    runs = [index for index in sorted(by_run) for _ in by_run[index]]
    return write_events(events, Path(folder) / f"{name}.events.csv", {"run": runs})


def summary_lines(by_run: dict[int, list[HealthEvent]]) -> list[str]:
    """One line per estimator with a notable event: ``isolated baro 20/20 runs (median
    132.5 s)``, each kind of event and source once, counted in runs (first time in each)."""
    firsts: dict[str, dict[tuple[str, str], list[float]]] = {}
    for events in by_run.values():
        seen: set[tuple[str, str, str]] = set()
        for event in events:
            key = (event.estimator, event.what, event.source)
            if event.what in NOTABLE and key not in seen:
                seen.add(key)
                firsts.setdefault(event.estimator, {}).setdefault(
                    (event.what, event.source), []).append(event.time)
    lines = []
    for estimator, kinds in firsts.items():
        said = [f"{what} {source.replace('+', ', ')}".strip() + f" {len(times)}/{len(by_run)} "
                f"runs (median {statistics.median(times):.1f} s)"
                for (what, source), times in sorted(
                    kinds.items(), key=lambda item: statistics.median(item[1]))]
        lines.append(f"  {estimator}: {'; '.join(said)}")
    return lines


def report_campaign_events(folder: Path, name: str) -> tuple[str, Path]:
    """The events of the campaign in ``folder`` in words (headed by ``name``) and the CSV
    written with all of them."""
    by_run = campaign_events(folder)
    path = write_campaign_events(folder, name, by_run)
    lines = summary_lines(by_run) or ["  no isolation, fallback, height reset or loss of "
                                      "validity in any run"]
    return "\n".join([f"{name}: health events of {len(by_run)} runs"] + lines), path
