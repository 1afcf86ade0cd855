"""Campaign statistics as table rows, plain text and JSON."""

from typing import Any

from altfusion.montecarlo.aggregation import CampaignStatistics, MetricStatistics
from altfusion.montecarlo.statistics import FEW_RUNS, Interval
from altfusion.scores import RMS_DEFINITION

HEADER = ("error metric", "unit", "RMS", "mean", "σ", "mean per-run max |e|", "max |e|")


def number(value: float) -> str:
    return f"{value:.4g}"


def with_interval(value: float, interval: Interval | None) -> str:
    """'1.23 [1.1, 1.4]', or '1.23 [n/a]' when there is no interval (a single run)."""
    if interval is None:
        return f"{number(value)} [n/a]"
    return f"{number(value)} [{number(interval.low)}, {number(interval.high)}]"


def metric_row(statistics: MetricStatistics) -> tuple[str, ...]:
    s = statistics
    return (s.metric.name, s.unit, with_interval(s.rms, s.rms_ci),
            with_interval(s.mean, s.mean_ci), with_interval(s.std, s.std_ci),
            with_interval(s.run_max_mean, s.run_max_ci),
            f"{number(s.max_abs)} (run {s.max_abs_run}, t = {s.max_abs_time:g} s)")


def confidence_note(statistics: CampaignStatistics) -> str:
    runs, expected = len(statistics.runs), statistics.expected_runs
    note = f"{runs} run{'s' if runs != 1 else ''}"
    if runs != expected:
        note += f" of {expected} ({len(statistics.failed)} failed, "
        note += f"{expected - runs - len(statistics.failed)} not run)"
    warning = (f"; WARNING: fewer than {FEW_RUNS} runs: the intervals are very wide and the "
               f"lower ends of RMS, σ and max |e| are clipped at 0" if runs < FEW_RUNS else "")
    return (f"{note}; [brackets]: {100 * statistics.confidence:g} % confidence intervals, "
            f"each run one independent sample{warning}; {RMS_DEFINITION}")


def format_table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
             for row in [header, *rows]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def format_statistics(statistics: CampaignStatistics) -> str:
    """The metrics table with intervals, as plain text."""
    rows = [metric_row(m) for m in statistics.metrics]
    if not rows:
        return f"no error metrics defined ({confidence_note(statistics)})"
    return format_table(HEADER, rows) + "\n" + confidence_note(statistics)


def _interval_json(interval: Interval | None) -> list[float] | None:
    return None if interval is None else [interval.low, interval.high]


def statistics_json(statistics: CampaignStatistics) -> dict[str, Any]:
    """Scalar statistics and the per-run RMS errors, JSON-ready."""
    metrics = []
    for s in statistics.metrics:
        metrics.append({
            "name": s.metric.name, "estimate": s.metric.estimate, "truth": s.metric.truth,
            "unit": s.unit, "rms": s.rms, "rms_ci": _interval_json(s.rms_ci),
            "mean": s.mean, "mean_ci": _interval_json(s.mean_ci),
            "std": s.std, "std_ci": _interval_json(s.std_ci),
            "max_abs": s.max_abs, "max_abs_run": s.max_abs_run,
            "max_abs_time": s.max_abs_time,
            "run_max_mean": s.run_max_mean, "run_max_ci": _interval_json(s.run_max_ci),
        })
    per_run = [{"run": index, "seeds": seeds,
                "rms": {s.metric.name: float(s.run_rms[k]) for s in statistics.metrics}}
               for k, (index, seeds) in enumerate(zip(statistics.runs, statistics.seeds,
                                                      strict=True))]
    return {"system": statistics.manifest["system"]["name"],
            "runs": statistics.runs, "expected_runs": statistics.expected_runs,
            "failed": {str(k): v for k, v in statistics.failed.items()},
            "confidence": statistics.confidence, "metrics": metrics, "per_run": per_run}
