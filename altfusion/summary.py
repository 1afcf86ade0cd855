"""Text summaries of a run: error metrics, the range of each recorded signal, the warnings."""

from collections.abc import Collection
from pathlib import Path

import numpy as np

from altfusion.cosim.results import Results
from altfusion.health_events import status_names
from altfusion.systems.spec import Metric


def metric_rows(results: Results, metrics: tuple[Metric, ...]) -> list[tuple[str, float, ...]]:
    """(name, RMS, mean, max |error|) of estimate - truth for each metric."""
    rows = []
    for metric in metrics:
        error = results[metric.estimate] - results[metric.truth]
        rows.append((metric.name, float(np.sqrt(np.mean(error**2))), float(np.mean(error)),
                     float(np.max(np.abs(error)))))
    return rows


def format_summary(results: Results, metrics: tuple[Metric, ...]) -> str:
    """A short plain-text table of the metrics and the recorded signals."""
    lines = []
    rows = metric_rows(results, metrics)
    if rows:
        lines.append(f"{'error metric':<34}{'RMS':>12}{'mean':>12}{'max |e|':>12}")
        for name, rms, mean, worst in rows:
            lines.append(f"{name:<34}{rms:12.4g}{mean:12.4g}{worst:12.4g}")
        lines.append("")
    lines.append(f"{'signal':<34}{'final':>12}{'min':>12}{'max':>12}")
    for name, values in results.columns.items():
        label = results.header(name)
        if name.endswith(".status") and np.all(np.isfinite(values)):
            lines.append(f"{label:<34}{status_words(values)}")
        else:
            lines.append(f"{label:<34}{values[-1]:12.5g}{values.min():12.5g}"
                         f"{values.max():12.5g}")
    return "\n".join(lines)


def status_words(values: np.ndarray) -> str:
    """An estimator's ``status`` column decoded by bit name: the final bits, then those set
    at some time but not at the end (``docs/estimator_health.md``)."""
    bits = values.astype(np.int64)
    final = status_names(int(bits[-1]))
    seen = [name for name in status_names(int(np.bitwise_or.reduce(bits)))
            if name not in final]
    return (f"  final {' '.join(final) or 'none'}"
            + (f"; also seen {' '.join(seen)}" if seen else ""))


def write_warnings(results: Results, path: Path, leave_out: Collection[str] = (),
                   ) -> tuple[Path, str] | None:
    """Write every warning of ``results`` to ``path`` (atomically) and return it with what
    each component logged as a warning (an estimator's notes: ignored, refused and stuck
    samples, inputs outside their plausible range): how many, and the first; the components
    in ``leave_out`` (reported otherwise) are not summed up. None (nothing written) when the
    others logged none."""
    shown = {name: kept for name, kept in results.warnings.items() if name not in leave_out}
    if not shown:
        return None
    written = results.warnings_to_text(path)
    lines = [f"  {name}: {kept.total}, first: {kept[0]}" for name, kept in shown.items()]
    return written, "\n".join([f"warnings (all in {written}):", *lines])
