"""Campaign statistics, computed by streaming the stored runs in index order (so the numbers
do not depend on which worker finished first, and memory does not grow with the number of
runs).

For each error metric (estimate - truth, ``Metric`` of the system), with confidence level
``CONFIDENCE``:

* versus time (like whang2008, Fig. 3): the RMS over runs at each output sample, with the
  chi-square interval of a zero-mean Gaussian error's σ, and the mean error with its t
  interval;
* overall, treating each run as one independent sample (samples within a run are
  correlated), over the rows where the estimate's component is initialized (its ``status``
  bit INITIALIZED, when its status is recorded; every row otherwise): the RMS over runs,
  :data:`altfusion.scores.RMS_DEFINITION` (:func:`altfusion.scores.pooled_rms`, as
  ``altfusion evaluate`` computes it; square root of the t interval of the per-run mean
  squares), mean (t interval of the per-run means), σ about that mean (same construction
  as the RMS), and the largest |error| (where it occurred, and the mean per-run maximum with
  its t interval).

Every recorded signal also gets its mean, σ, minimum and maximum over runs versus time.
"""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from altfusion.estimators.health import Status
from altfusion.montecarlo.source import CampaignError
from altfusion.montecarlo.statistics import (
    Interval,
    mean_bounds,
    mean_interval,
    rms_chi2_bounds,
    root_interval,
)
from altfusion.montecarlo.storage import (
    DamagedRunError,
    failed_runs,
    finished_runs,
    load_run,
    read_manifest,
)
from altfusion.scores import pooled_rms
from altfusion.systems.spec import Metric

CONFIDENCE = 0.95


class _Welford:
    """Running mean and sum of squared deviations of equally shaped arrays."""

    def __init__(self, shape: tuple[int, ...]):
        self.count = 0
        self.mean = np.zeros(shape)
        self.m2 = np.zeros(shape)

    def add(self, values: np.ndarray) -> None:
        self.count += 1
        delta = values - self.mean
        self.mean += delta / self.count
        self.m2 += delta * (values - self.mean)

    def std(self) -> np.ndarray:
        return np.sqrt(self.m2 / (self.count - 1)) if self.count > 1 else np.zeros_like(self.m2)


@dataclass
class TimeProfile:
    """Statistics over runs at each output time; bounds are None with fewer than 2 runs."""

    rms: np.ndarray
    rms_low: np.ndarray
    rms_high: np.ndarray
    mean: np.ndarray
    mean_low: np.ndarray | None
    mean_high: np.ndarray | None


@dataclass
class MetricStatistics:
    metric: Metric
    unit: str
    rms: float
    rms_ci: Interval | None
    mean: float
    mean_ci: Interval | None
    std: float
    std_ci: Interval | None
    max_abs: float
    max_abs_run: int
    max_abs_time: float
    run_max_mean: float
    run_max_ci: Interval | None
    run_rms: np.ndarray
    """RMS error of each run (in the order of ``CampaignStatistics.runs``)."""
    profile: TimeProfile


@dataclass
class SignalEnvelope:
    name: str
    unit: str
    mean: np.ndarray
    std: np.ndarray
    minimum: np.ndarray
    maximum: np.ndarray


@dataclass
class CampaignStatistics:
    manifest: dict
    runs: list[int]
    """Indices of the runs aggregated."""
    failed: dict[int, str]
    time: np.ndarray
    metrics: list[MetricStatistics]
    signals: list[SignalEnvelope]
    seeds: list[dict[str, int]] = field(default_factory=list)
    confidence: float = CONFIDENCE
    skipped: dict[int, str] = field(default_factory=dict)
    """Stored runs left out because their file is damaged, with what is wrong."""

    @property
    def expected_runs(self) -> int:
        return int(self.manifest["runs"])


class _MetricAccumulator:
    def __init__(self, metric: Metric, samples: int):
        self.metric = metric
        self.unit = ""
        self.per_time = _Welford((samples,))
        self.sum_squares = np.zeros(samples)
        self.run_mean: list[float] = []
        self.run_mean_square: list[float] = []
        self.run_max: list[float] = []
        self.worst = (-1.0, -1, 0.0)

    def add(self, index: int, time: np.ndarray, error: np.ndarray,
            initialized: np.ndarray) -> None:
        """One run's error at every output time; its scalars over the ``initialized`` rows."""
        self.per_time.add(error)
        self.sum_squares += error**2
        counted, at = error[initialized], time[initialized]
        if not counted.size:
            counted, at = np.array([np.nan]), time[:1]
        self.run_mean.append(float(counted.mean()))
        self.run_mean_square.append(float(np.mean(counted**2)))
        where = int(np.argmax(np.abs(counted)))
        self.run_max.append(float(abs(counted[where])))
        if self.run_max[-1] > self.worst[0]:
            self.worst = (self.run_max[-1], index, float(at[where]))

    def result(self, confidence: float) -> MetricStatistics:
        n = len(self.run_mean)
        means, mean_squares = np.array(self.run_mean), np.array(self.run_mean_square)
        mean = float(means.mean())
        variances = mean_squares - 2 * mean * means + mean**2
        per_time_ms = self.sum_squares / n
        rms_low, rms_high = rms_chi2_bounds(per_time_ms, n, confidence)
        bounds = mean_bounds(self.per_time.mean, self.per_time.std(), n, confidence)
        profile = TimeProfile(np.sqrt(per_time_ms), rms_low, rms_high, self.per_time.mean.copy(),
                              *(bounds if bounds is not None else (None, None)))
        return MetricStatistics(
            self.metric, self.unit,
            pooled_rms(mean_squares), root_interval(mean_squares, confidence),
            mean, mean_interval(means, confidence),
            float(np.sqrt(max(variances.mean(), 0.0))), root_interval(variances, confidence),
            self.worst[0], self.worst[1], self.worst[2],
            float(np.mean(self.run_max)),
            mean_interval(np.array(self.run_max), confidence, nonnegative=True),
            np.sqrt(mean_squares), profile,
        )


def _signal(results, name: str, path: Path) -> np.ndarray:
    if name not in results.columns:
        raise CampaignError(f"{path}: signal '{name}' was not recorded")
    return results[name]


def initialized_rows(results, metric: Metric) -> np.ndarray:
    """Rows where the estimate's component has the status bit INITIALIZED (every row when
    its ``status`` is not recorded)."""
    status = results.columns.get(f"{metric.estimate.partition('.')[0]}.status")
    if status is None:
        return np.ones(results.time.size, dtype=bool)
    return (status.astype(np.int64) & int(Status.INITIALIZED)) != 0


def aggregate(out: Path, confidence: float = CONFIDENCE) -> CampaignStatistics:
    """Statistics of the finished runs of the campaign in ``out``."""
    out = Path(out)
    manifest = read_manifest(out)
    stored = [index for index in finished_runs(out) if index < manifest["runs"]]
    metrics = [Metric(**m) for m in manifest["metrics"]]
    accumulators: list[_MetricAccumulator] = []
    envelopes: dict[str, tuple[_Welford, np.ndarray, np.ndarray, str]] = {}
    seeds, runs, skipped = [], [], {}
    time = np.empty(0)
    for index in stored:
        try:
            record = load_run(out, index)
        except DamagedRunError as error:
            skipped[index] = str(error)
            continue
        if not runs:
            time = record.results.time
            accumulators = [_MetricAccumulator(metric, time.size) for metric in metrics]
        runs.append(index)
        results = record.results
        if not np.array_equal(results.time, time):
            raise CampaignError(f"run {index} has other output times than run {runs[0]}")
        seeds.append(record.seeds)
        for accumulator in accumulators:
            metric = accumulator.metric
            error = _signal(results, metric.estimate, out) - _signal(results, metric.truth, out)
            accumulator.unit = results.units.get(metric.estimate, "")
            accumulator.add(index, time, error, initialized_rows(results, metric))
        for name, values in results.columns.items():
            if name not in envelopes:
                envelopes[name] = (_Welford(values.shape), values.copy(), values.copy(),
                                   results.units.get(name, ""))
            welford, low, high, _unit = envelopes[name]
            welford.add(values)
            np.minimum(low, values, out=low)
            np.maximum(high, values, out=high)
    if not runs:
        damaged = f" ({len(skipped)} damaged run files skipped)" if skipped else ""
        raise CampaignError(f"{out} holds no finished runs{damaged}")
    signals = [SignalEnvelope(name, unit, w.mean, w.std(), low, high)
               for name, (w, low, high, unit) in envelopes.items()]
    failed = {i: m for i, m in failed_runs(out).items() if i < manifest["runs"]}
    return CampaignStatistics(manifest, runs, failed, time,
                              [a.result(confidence) for a in accumulators], signals, seeds,
                              confidence, skipped)
