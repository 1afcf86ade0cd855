"""What the paper reproductions share: running their Monte Carlo campaigns, loading the runs
as arrays, RMS versus time with its confidence band, paired win counts, Markdown tables and
reference CSVs.

A reproduction describes each campaign as a :class:`Campaign` (a catalog system, optionally
with another estimator FMU swapped into its component ``estimator``, and parameter
overrides) and runs them with :func:`run_campaigns`; every campaign is an ordinary campaign
folder (``altfusion mc``'s format: resumable, reportable with ``altfusion report``). All
campaigns of a reproduction use the same master seed, so run i of each sees the same
realization of every component that the systems share by name.

Reference CSVs (the style guide: every paper scenario keeps a small reference result from a
fixed seed that the system tests compare to): a :class:`Reference` names a catalog system,
its columns and the interval between rows; the result is run ``run`` of master seed
``master_seed`` (run 0 of a reproduction's campaign), decimated. Regenerate them after an
intended change of a scenario or a model (then review the diff)::

    python build_fmu.py && python -m altfusion.reproduce.common whang2008 hajiyev
"""

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from altfusion import atomic
from altfusion.atomic import write_text
from altfusion.cosim.results import Results
from altfusion.cosim.runner import simulate
from altfusion.cosim.ssp import read_ssp
from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.montecarlo.execution import (
    CampaignSettings,
    Execution,
    kept_workers,
    run_campaign,
)
from altfusion.montecarlo.seeds import run_seeds, seeded_components
from altfusion.montecarlo.source import CampaignError, SystemSource
from altfusion.montecarlo.statistics import Interval, rms_chi2_bounds, root_interval
from altfusion.montecarlo.storage import finished_runs, has_manifest, read_manifest, read_run
from altfusion.montecarlo.swap import SwapError, find_fmu
from altfusion.reproduce import ReproduceOptions, reproduction

CONFIDENCE = 0.95
INTERRUPTED = 130
REFERENCE_FOLDER = Path("tests") / "data" / "reference"
REFERENCE_RTOL = 1e-9


# ------------------------------------------------------------------------------ campaigns


@dataclass(frozen=True)
class Campaign:
    """One Monte Carlo campaign of a reproduction."""

    label: str
    """How tables and figures name it."""
    folder: str
    """Its folder under the reproduction's output folder."""
    system: str
    """Catalog system: ``<models>/<system>.ssp``."""
    estimator: str | None = None
    """FMU that replaces the system's component ``estimator`` (None: the system's own)."""
    parameters: dict[str, Any] = field(default_factory=dict)
    """Parameter overrides ('component.parameter') in every run."""


def campaign_source(campaign: Campaign, models: Path, backend: str = "core") -> SystemSource:
    """The SSP of the campaign's system, with its estimator swap, run on ``backend``."""
    ssp = Path(models) / f"{campaign.system}.ssp"
    if not ssp.is_file():
        raise CampaignError(f"no {ssp}: build the models first (python build_fmu.py)")
    if campaign.estimator is None:
        return SystemSource.from_path(ssp, backend=backend)
    swap = find_fmu("estimator", campaign.estimator, ssp, read_ssp(ssp).fmu_paths)
    return SystemSource.from_path(ssp, swap, backend=backend)


def paper_algorithm(source: SystemSource) -> dict[str, bool]:
    """Parameter overrides that turn ``fault_detection`` off in every estimator component
    of the campaign's system (its own estimator FMUs and a swapped-in one)."""
    spec = read_ssp(source.ssp).spec
    fmus = {c.name: c.fmu for c in spec.components}
    if source.swap is not None:
        fmus[source.swap.component] = source.swap.fmu
    return {f"{name}.fault_detection": False for name, fmu in fmus.items()
            if fmu in ESTIMATOR_CLASSES}


def run_campaigns(campaigns: tuple[Campaign, ...], options: ReproduceOptions,
                  default_runs: int) -> int:
    """Run every campaign, or with ``options.resume`` complete those already started; the
    exit status: 0 when every campaign is complete, 130 if interrupted, 1 if runs failed or a
    worker died, 2 if a campaign cannot start (its message printed)."""
    with kept_workers(Execution(options.workers, options.scheduler)) as execution:
        return _run_each(campaigns, options, default_runs, execution)


def _run_each(campaigns: tuple[Campaign, ...], options: ReproduceOptions, default_runs: int,
              execution: Execution) -> int:
    """:func:`run_campaigns` on ``execution``, one campaign after the other."""
    for campaign in campaigns:
        out = Path(options.out) / campaign.folder
        resume = options.resume and has_manifest(out)
        runs = options.runs if options.runs is not None or resume else default_runs
        print(f"{campaign.label} ({campaign.system}):", file=sys.stderr, flush=True)
        try:
            source = campaign_source(campaign, options.models, options.backend)
            parameters = {**(paper_algorithm(source) if options.paper_algorithm else {}),
                          **campaign.parameters}
            outcome = run_campaign(
                source, out, CampaignSettings(runs, options.master_seed, None, parameters),
                execution, resume=resume)
        except (CampaignError, SwapError) as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
        if outcome.failing:
            print(f"stopped: {outcome.stopped}", file=sys.stderr)
            return 1
        if outcome.stopped:
            print(f"stopped: {outcome.stopped}. Finished runs are kept in {out}; the same "
                  f"command with --resume completes the reproduction.", file=sys.stderr)
            return INTERRUPTED if outcome.stopped == "interrupted" else 1
        if not outcome.complete:
            first = min(outcome.failed, default=None)
            print(f"{len(outcome.failed)} run(s) of {campaign.label} failed (first: run "
                  f"{first}, {out}/runs/run_{first:05d}.failed.txt); --resume retries them",
                  file=sys.stderr)
            return 1
    return 0


# ------------------------------------------------------------------------------ loading runs


@dataclass
class RunArrays:
    """The finished runs of a campaign: recorded signals as arrays of shape (runs, times)."""

    runs: list[int]
    time: np.ndarray
    signals: dict[str, np.ndarray]
    manifest: dict[str, Any]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.signals[name]

    def error(self, estimate: str, truth: str) -> np.ndarray:
        return self.signals[estimate] - self.signals[truth]


def load_runs(folder: Path, names: tuple[str, ...]) -> RunArrays:
    """Signals ``names`` of every finished run of the campaign in ``folder``, by run index."""
    folder = Path(folder)
    manifest = read_manifest(folder)
    runs = [index for index in finished_runs(folder) if index < manifest["runs"]]
    if not runs:
        raise CampaignError(f"{folder} holds no finished runs")
    columns: dict[str, list[np.ndarray]] = {name: [] for name in names}
    time = None
    for index in runs:
        results = read_run(folder, index).results
        if time is None:
            time = results.time
        elif not np.array_equal(results.time, time):
            raise CampaignError(f"run {index} in {folder} has other output times than run "
                                f"{runs[0]}")
        for name in names:
            if name not in results.columns:
                raise CampaignError(f"{folder}: signal '{name}' was not recorded")
            columns[name].append(results[name])
    return RunArrays(runs, time, {n: np.vstack(v) for n, v in columns.items()}, manifest)


# ------------------------------------------------------------------------------ statistics


@dataclass
class RmsCurve:
    """RMS over runs versus time and its chi-square band (see ``rms_chi2_bounds``)."""

    label: str
    time: np.ndarray
    rms: np.ndarray
    low: np.ndarray
    high: np.ndarray


def rms_curve(label: str, time: np.ndarray, errors: np.ndarray,
              confidence: float = CONFIDENCE) -> RmsCurve:
    """RMS over the rows (runs) of ``errors`` at each time, with its band."""
    mean_square = np.mean(errors**2, axis=0)
    low, high = rms_chi2_bounds(mean_square, errors.shape[0], confidence)
    return RmsCurve(label, time, np.sqrt(mean_square), low, high)


@dataclass(frozen=True)
class Estimate:
    """A number with its confidence interval (None with a single run)."""

    value: float
    interval: Interval | None

    def text(self, digits: int = 4) -> str:
        value = f"{self.value:.{digits}g}"
        if self.interval is None:
            return value
        return f"{value} [{self.interval.low:.{digits}g}, {self.interval.high:.{digits}g}]"


def rms_over_runs(errors: np.ndarray, confidence: float = CONFIDENCE) -> Estimate:
    """RMS of all samples of ``errors`` (runs × samples), with the interval that takes each
    run as one independent sample (the square root of the t interval of the per-run mean
    squares; samples within a run are correlated)."""
    mean_squares = np.mean(errors**2, axis=1)
    return Estimate(float(np.sqrt(mean_squares.mean())),
                    root_interval(mean_squares, confidence))


# ------------------------------------------------------------------------------ paired runs


@dataclass(frozen=True)
class WinCount:
    """In how many of ``runs`` paired runs one estimator beat another, with the
    Clopper-Pearson (exact binomial) interval of the fraction of runs it wins."""

    wins: int
    runs: int
    interval: Interval

    @property
    def fraction(self) -> float:
        return self.wins / self.runs

    def text(self) -> str:
        return (f"{self.wins}/{self.runs} [{100 * self.interval.low:.0f}, "
                f"{100 * self.interval.high:.0f} %]")


def paired_wins(errors: np.ndarray, other: np.ndarray,
                confidence: float = CONFIDENCE) -> WinCount:
    """Runs (rows) in which ``errors`` have a smaller mean square than ``other``'s errors of
    the same run; the same run index of campaigns with one master seed sees the same noise."""
    wins = int(np.sum(np.mean(errors**2, axis=1) < np.mean(other**2, axis=1)))
    runs = errors.shape[0]
    low, high = stats.binomtest(wins, runs).proportion_ci(confidence, method="exact")
    return WinCount(wins, runs, Interval(float(low), float(high)))


BOOTSTRAP_RESAMPLES = 1000
BOOTSTRAP_SEED = 0


def percentile_over_runs(errors: np.ndarray, q: float, confidence: float = CONFIDENCE,
                         resamples: int = BOOTSTRAP_RESAMPLES) -> Estimate:
    """The ``q``-th percentile of |errors| pooled over all samples (runs × samples), with a
    percentile-bootstrap interval that resamples whole runs (samples within a run are
    correlated; the runs are independent), with a fixed seed."""
    magnitudes = np.abs(errors)
    value = float(np.percentile(magnitudes, q))
    runs = magnitudes.shape[0]
    if runs < 2:
        return Estimate(value, None)
    picks = np.random.default_rng(BOOTSTRAP_SEED).integers(0, runs, (resamples, runs))
    replicas = [np.percentile(magnitudes[pick], q) for pick in picks]
    low, high = np.percentile(replicas, [50 * (1 - confidence), 50 * (1 + confidence)])
    return Estimate(value, Interval(float(low), float(high)))


# ------------------------------------------------------------------------------ output


def figure(panels: int, height_ratios: tuple[float, ...] | None = None, height: float = 2.6):
    """A matplotlib figure (Agg backend) with ``panels`` stacked axes sharing the time axis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ratios = height_ratios or (1.0,) * panels
    fig, axes = plt.subplots(panels, 1, sharex=True, squeeze=False,
                             figsize=(9, height * sum(ratios) + 0.6),
                             gridspec_kw={"height_ratios": ratios})
    for ax in axes[:, 0]:
        ax.grid(True, alpha=0.3)
    return fig, list(axes[:, 0])


def save_figure(fig, path: Path, dpi: int = 110) -> Path:
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    atomic.save_figure(fig, path, dpi=dpi)
    plt.close(fig)
    return path


def markdown_table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


# ------------------------------------------------------------------------------ command


def run_reproduction(options: ReproduceOptions, name: str, campaigns: tuple[Campaign, ...],
                     default_runs: int, analyse: Callable[[Path], Any],
                     tables: Callable[[Any], str],
                     figures: Callable[[Any, Path], list[Path]]) -> int:
    """What ``altfusion reproduce NAME`` does: run (or complete) the campaigns, analyse them
    (``analyse(out)``), write the figures (``figures(analysis, out)``) and the tables
    (``tables(analysis)``, to ``<name>.md``), print them; the exit status (2 when the
    campaigns cannot be analysed: the message is printed)."""
    status = run_campaigns(campaigns, options, default_runs)
    if status:
        return status
    out = Path(options.out)
    try:
        analysis = analyse(out)
    except (CampaignError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    text = tables(analysis)
    table = out / f"{name}.md"
    write_text(table, text)
    paths = figures(analysis, out)
    print(text)
    print("\n".join(f"wrote {path}" for path in [*paths, table]))
    print("campaigns: " + ", ".join(str(out / c.folder) for c in campaigns)
          + " (altfusion report DIR)")
    return 0


# ------------------------------------------------------------------------------ references


@dataclass(frozen=True)
class Reference:
    """A paper scenario's reference result: run ``run`` of master seed ``master_seed`` of a
    catalog system, signals ``columns`` every ``interval`` seconds."""

    system: str
    columns: tuple[str, ...]
    interval: float
    master_seed: int = 0
    run: int = 0

    @property
    def file_name(self) -> str:
        return f"{self.system}_seed{self.master_seed}.csv"

    def stored(self, root: Path) -> Results:
        """The reference CSV kept in the project whose folder is ``root``."""
        return Results.from_csv(Path(root) / REFERENCE_FOLDER / self.file_name)

    def sampled(self, results: Results) -> Results:
        """This reference's columns of a run, every ``interval`` seconds (the run's own
        output interval is read from its time axis)."""
        every = round(self.interval / (results.time[1] - results.time[0]))
        rows = slice(0, None, every)
        return Results(results.time[rows], {n: results[n][rows] for n in self.columns},
                       {n: results.units.get(n, "") for n in self.columns})


def reference_results(reference: Reference, models: Path) -> Results:
    """Simulate the reference run and keep its columns every ``interval`` seconds."""
    loaded = read_ssp(Path(models) / f"{reference.system}.ssp")
    seeds = run_seeds(reference.master_seed, reference.run,
                      seeded_components(loaded.spec, loaded.fmu_paths))
    return reference.sampled(simulate(loaded.spec, loaded.fmu_paths, parameters=seeds))


def reference_differences(results: Results, stored: Results,
                          rtol: float = REFERENCE_RTOL) -> list[str]:
    """Where ``results`` differ from the stored reference by more than ``rtol`` of the value
    (with an absolute floor of ``rtol`` times the column's largest magnitude, for zeros)."""
    problems = []
    if list(results.columns) != list(stored.columns):
        return [f"columns {list(results.columns)} != stored {list(stored.columns)}"]
    if results.time.shape != stored.time.shape or not np.allclose(results.time, stored.time,
                                                                   rtol=0, atol=1e-9):
        return ["output times differ from the stored reference"]
    for name, expected in stored.columns.items():
        floor = rtol * max(float(np.abs(expected).max()), np.finfo(float).tiny)
        actual = results[name]
        bad = np.flatnonzero(~np.isclose(actual, expected, rtol=rtol, atol=floor))
        if bad.size:
            row = bad[0]
            problems.append(f"{name}: {bad.size} row(s) differ, first at t = "
                            f"{stored.time[row]:g} s: {actual[row]!r} != {expected[row]!r}")
    return problems


def write_references(names: list[str], models: Path, folder: Path) -> list[Path]:
    """The reference CSVs of the reproductions ``names`` (their ``REFERENCES``)."""
    written = []
    for name in names:
        for reference in reproduction(name).REFERENCES:
            path = Path(folder) / reference.file_name
            written.append(reference_results(reference, models).to_csv(path))
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m altfusion.reproduce.common",
        description="Write the reference CSVs of reproductions (run 0 of master seed 0, "
                    "decimated) for the system tests to compare to.")
    parser.add_argument("names", nargs="+", help="reproductions, e.g. whang2008 hajiyev")
    parser.add_argument("--models", type=Path, default=Path("models"))
    parser.add_argument("--out", type=Path, default=REFERENCE_FOLDER)
    args = parser.parse_args(argv)
    for path in write_references(args.names, args.models, args.out):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
