"""The ``mc``, ``report`` and ``compare`` subcommands of the ``altfusion`` command line."""

import argparse
import sys
from pathlib import Path
from typing import Any

from altfusion.atomic import output_folder
from altfusion.montecarlo.source import CampaignError
from altfusion.montecarlo.swap import SwapError

INTERRUPTED = 130
SHOWN_FAILURES = 5


def _parameters(system: Path, settings: list[str]) -> dict[str, Any] | None:
    if not settings:
        return None
    from altfusion.cosim.settings import parse_settings
    from altfusion.cosim.ssp import read_ssp

    return parse_settings(read_ssp(system), settings)


def _settings(args: argparse.Namespace):
    from altfusion.montecarlo.execution import CampaignSettings

    return CampaignSettings(args.runs, args.seed, args.stop, _parameters(args.system, args.set))


def _execution(args: argparse.Namespace):
    from altfusion.montecarlo.execution import Execution

    return Execution(args.workers, args.scheduler, progress=not args.quiet)


def _headline(message: str) -> str:
    """The informative line of a stored failure: the error line after a traceback, else the
    first line (a CosimError names the component first)."""
    lines = [line for line in message.splitlines() if line.strip()] or [""]
    return lines[-1] if lines[0].startswith("Traceback") else lines[0]


def _report_outcome(outcome, resume_hint: str) -> int:
    """Print what a campaign session did; the exit status."""
    print(f"{len(outcome.finished)}/{outcome.runs} runs finished in {outcome.out} "
          f"({outcome.executed} executed in this session on "
          f"{outcome.backend or 'no workers'}, {outcome.elapsed:.1f} s)")
    for index, reason in sorted(outcome.damaged.items()):
        print(f"run {index} was damaged, re-run: {reason}")
    for index, message in list(sorted(outcome.failed.items()))[:SHOWN_FAILURES]:
        print(f"run {index} failed: {_headline(message)}", file=sys.stderr)
    if len(outcome.failed) > SHOWN_FAILURES:
        print(f"... {len(outcome.failed)} failed runs in all ({outcome.out}/runs/*.failed.txt)",
              file=sys.stderr)
    if outcome.failing:
        print(f"stopped: {outcome.stopped}", file=sys.stderr)
    elif outcome.stopped:
        print(f"stopped: {outcome.stopped}. Finished runs are kept; {resume_hint} "
              f"completes the campaign.", file=sys.stderr)
        return INTERRUPTED if outcome.stopped == "interrupted" else 1
    return 0 if outcome.complete else 1


def command_mc(args: argparse.Namespace) -> int:
    from altfusion.montecarlo.aggregation import aggregate
    from altfusion.montecarlo.execution import run_campaign
    from altfusion.montecarlo.source import SystemSource
    from altfusion.montecarlo.tables import format_statistics

    out = output_folder(args.out or Path("results") / "mc" / args.system.stem)
    source = SystemSource.from_path(args.system, fault=args.fault)
    if args.run is not None:
        return _rerun(args, source, out)
    outcome = run_campaign(source, out, _settings(args), _execution(args), resume=args.resume)
    status = _report_outcome(outcome, f"altfusion mc {args.system} --out {out} --resume")
    if outcome.finished:
        statistics = aggregate(out)
        print(format_statistics(statistics))
        _print_health(out, statistics.manifest["system"]["name"])
        print(f"plots and HTML report: altfusion report {out}")
    return status


def _rerun(args: argparse.Namespace, source, out: Path) -> int:
    from altfusion.cosim.ssp import read_ssp
    from altfusion.montecarlo.rerun import rerun
    from altfusion.summary import format_summary, write_warnings

    result = rerun(source, args.run, _settings(args), out)
    record = result.record
    files = [record.results.to_csv(out / f"rerun_{args.run:05d}.csv")]
    seeds = ", ".join(f"{name} = {value}" for name, value in record.seeds.items()) or "none"
    print(f"run {args.run}: seeds {seeds}; {record.elapsed:.2f} s")
    print(format_summary(record.results, read_ssp(args.system).spec.metrics))
    warnings = write_warnings(record.results, out / f"rerun_{args.run:05d}.warnings.txt")
    if warnings:
        files.append(warnings[0])
        print(f"\n{warnings[1]}")
    print(f"wrote {', '.join(map(str, files))}")
    if result.identical is None:
        return 0
    if result.identical:
        print(f"identical to run {args.run} of the campaign in {out}")
        return 0
    print(f"DIFFERS from run {args.run} of the campaign in {out}", file=sys.stderr)
    return 1


def _print_health(out: Path, name: str) -> None:
    """What the estimators did over the runs of the campaign in ``out`` (where they record
    their status), headed by ``name``, and the CSV written with every event."""
    from altfusion.montecarlo.campaign_events import campaign_health, records_health

    if records_health(out):
        health = campaign_health(out, name)
        print(f"{health.said(name)}\nevery event of every run: {health.events}")


def command_report(args: argparse.Namespace) -> int:
    from altfusion.montecarlo.report import write_report
    from altfusion.montecarlo.tables import format_statistics

    report = write_report(args.results)
    for index, reason in sorted(report.statistics.skipped.items()):
        print(f"skipped run {index}: {reason} (altfusion mc --resume re-runs it)")
    print(format_statistics(report.statistics))
    if report.health is not None:
        print(report.health.said(report.statistics.manifest["system"]["name"]))
    events = f", {report.health.events}" if report.health else ""
    print(f"wrote {report.html}, {report.summary}{events} and {len(report.pngs)} plots")
    return 0


def command_compare(args: argparse.Namespace) -> int:
    from altfusion.montecarlo.compare import format_comparison, run_comparison, write_comparison

    estimators = [name.strip() for name in args.estimators.split(",") if name.strip()]
    out = output_folder(args.out or Path("results") / "compare" / args.system.stem)
    outcomes = run_comparison(args.system, estimators, out, _settings(args), _execution(args),
                              resume=args.resume)
    status = 0
    for contender, outcome in outcomes:
        print(f"{contender.name}: ", end="")
        status = max(status, _report_outcome(
            outcome, f"altfusion compare {args.system} --estimators {args.estimators} "
                     f"--out {out} --resume"))
    if len(outcomes) < len(estimators) or any(not o.finished for _, o in outcomes):
        return status or 1
    page, reports = write_comparison(out, estimators)
    print(format_comparison([(name, report.statistics) for name, report in reports]))
    for name, report in reports:
        if report.health is not None:
            print(report.health.said(name))
    print(f"wrote {page}")
    return status


def guarded(command):
    """``command`` with a user's campaign mistake (:class:`CampaignError`, which the
    evaluation's errors extend, or :class:`SwapError`) as one ``error:`` line, status 2."""
    def run(args: argparse.Namespace) -> int:
        try:
            return command(args)
        except (CampaignError, SwapError) as error:
            print(f"error: {error}", file=sys.stderr)
            return 2
    return run


def _campaign_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system", type=Path, help="SSP archive (models/*.ssp)")
    parser.add_argument("-n", "--runs", type=int, default=None,
                        help="number of runs (required unless resuming)")
    parser.add_argument("--seed", type=int, default=None,
                        help="master seed from which every run's seeds derive (default 0)")
    parser.add_argument("--stop", type=float, default=None, help="stop time, s")
    parser.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE",
                        help="override a parameter in every run (repeatable)")
    parser.add_argument("--workers", type=int, default=None,
                        help="local worker processes (default: every available core)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="run on the Dask scheduler at tcp://host:port instead")
    parser.add_argument("--resume", action="store_true",
                        help="complete the interrupted campaign in --out")
    parser.add_argument("--quiet", action="store_true", help="no progress line")


def add_commands(commands) -> None:
    """Register ``mc``, ``report`` and ``compare`` on the CLI's subparsers."""
    mc = commands.add_parser("mc", help="Monte Carlo campaign of seeded runs of an SSP system")
    _campaign_options(mc)
    mc.add_argument("--out", default=None,
                    help="campaign folder (default: results/mc/<system>)")
    mc.add_argument("--fault", default=None, metavar="NAME",
                    help="apply fault scenario NAME of the fault suite (docs/faults.md) to "
                         "every run")
    mc.add_argument("--run", type=int, default=None, metavar="I",
                    help="re-run run I alone (settings from --out's campaign if there is one) "
                         "and check it against the stored run")
    mc.set_defaults(handler=guarded(command_mc))
    report = commands.add_parser("report", help="plots and an HTML report of a campaign")
    report.add_argument("results", type=Path, help="campaign folder (altfusion mc --out)")
    report.set_defaults(handler=guarded(command_report))
    compare = commands.add_parser(
        "compare", help="the same seeded runs through several estimators, side by side")
    _campaign_options(compare)
    compare.add_argument("--estimators", required=True, metavar="A,B,...",
                         help="FMU names (inside the SSP or next to it) for the component "
                              "named 'estimator'")
    compare.add_argument("--out", default=None,
                         help="comparison folder (default: results/compare/<system>)")
    compare.set_defaults(handler=guarded(command_compare))
