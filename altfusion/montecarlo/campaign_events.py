"""The health events (:mod:`altfusion.health_events`) of a campaign's stored runs: written to
``<campaign>/<name>.events.csv`` (one row per event, with its run) and said in a line per
estimator: in how many runs it isolated, re-admitted, fell back, reset its height or lost
its validity, and at what median time. ``altfusion evaluate`` says them for each scenario,
``altfusion mc`` and ``report`` for a campaign whose runs record an estimator's ``status``."""

import statistics
from dataclasses import dataclass
from pathlib import Path

from altfusion.health_events import (
    FALLBACK,
    HEIGHT_RESET,
    INVALID,
    ISOLATED,
    READMITTED,
    HealthEvent,
    estimators_in,
    health_events,
    write_events,
)
from altfusion.montecarlo.storage import finished_runs, load_run

NOTABLE = (ISOLATED, FALLBACK, READMITTED, HEIGHT_RESET, INVALID)
"""The events a campaign's summary counts (rejections and start-ups are in the CSV)."""
NONE_NOTABLE = "no isolation, fallback, height reset or loss of validity in any run"


def records_health(folder: Path) -> bool:
    """True if the runs of the campaign in ``folder`` record an estimator's health outputs
    (its ``status``; read off the first finished run): else they have no events to say."""
    runs = finished_runs(folder)
    return bool(runs) and bool(estimators_in(load_run(folder, runs[0]).results))


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


def summary_rows(by_run: dict[int, list[HealthEvent]]) -> list[tuple[str, str]]:
    """(estimator, its notable events: ``isolated baro 20/20 runs (median 132.5 s)``, each
    kind of event and source once, counted in runs (first time in each)) for each estimator
    with one."""
    firsts: dict[str, dict[tuple[str, str], list[float]]] = {}
    for events in by_run.values():
        seen: set[tuple[str, str, str]] = set()
        for event in events:
            key = (event.estimator, event.what, event.source)
            if event.what in NOTABLE and key not in seen:
                seen.add(key)
                firsts.setdefault(event.estimator, {}).setdefault(
                    (event.what, event.source), []).append(event.time)
    rows = []
    for estimator, kinds in firsts.items():
        said = [f"{what} {source.replace('+', ', ')}".strip() + f" {len(times)}/{len(by_run)} "
                f"runs (median {statistics.median(times):.1f} s)"
                for (what, source), times in sorted(
                    kinds.items(), key=lambda item: statistics.median(item[1]))]
        rows.append((estimator, "; ".join(said)))
    return rows


@dataclass(frozen=True)
class CampaignHealth:
    """What the estimators did over a campaign's runs."""

    events: Path
    """The CSV of every event of every run (:func:`write_campaign_events`)."""
    rows: list[tuple[str, str]]
    """Each estimator's notable events in words (:func:`summary_rows`)."""
    runs: int
    """Runs read."""

    def said(self, name: str) -> str:
        """:attr:`rows` a line per estimator, headed by ``name``."""
        lines = [f"  {estimator}: {said}" for estimator, said in self.rows] \
            or [f"  {NONE_NOTABLE}"]
        return "\n".join([f"{name}: health events of {self.runs} runs"] + lines)


def campaign_health(folder: Path, name: str) -> CampaignHealth:
    """The health events of the campaign in ``folder``, written to ``<name>.events.csv``
    there and summed up."""
    by_run = campaign_events(folder)
    return CampaignHealth(write_campaign_events(folder, name, by_run), summary_rows(by_run),
                          len(by_run))
