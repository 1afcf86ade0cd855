"""``altfusion timing``: run a system in a host, or read a host's result file, and check every
sensor stream's timing; ``altfusion run --record timing``'s recording."""

import argparse
import tempfile
import zipfile
from dataclasses import replace
from pathlib import Path

from altfusion.cosim.results import Results
from altfusion.cosim.ssp import LoadedSystem, read_ssp, write_ssp
from altfusion.errors import UsageError
from altfusion.systems.spec import SystemSpec
from altfusion.timing.check import StreamResult, check_stream
from altfusion.timing.report import format_report
from altfusion.timing.streams import Stream, sensor_streams, timing_signals
from altfusion.timing.table import ResultTable, first_row_per_time, read_result

HOSTS = ("ours", "libcosim", "ecos")
"""Hosts ``altfusion timing SYSTEM.ssp`` runs a system in: our runner (in this process),
libcosim and ECOS (each in a process of its own, through ``altfusion.interop``)."""


def with_timing_record(spec: SystemSpec, fmu_paths: dict[str, Path]) -> SystemSpec:
    """``spec`` recording, every base step, its recorded signals (every output if it names
    none) and every stream's count and stamp and its consumers' input counts."""
    from altfusion.cosim.instances import FMI_TYPES, fmu_info

    recorded = spec.record or tuple(
        f"{c.name}.{v.name}" for c in spec.components
        for v in fmu_info(fmu_paths[c.fmu]).variables.values()
        if v.causality == "output" and v.type in FMI_TYPES)
    signals = timing_signals(sensor_streams(spec, fmu_paths))
    return replace(spec, record=tuple(dict.fromkeys(recorded + signals)),
                   output_interval=None)


def run_for_timing(loaded: LoadedSystem, host: str, stop: float | None) -> Results:
    """The system of ``loaded`` run in ``host`` with :func:`with_timing_record`."""
    spec = with_timing_record(loaded.spec, loaded.fmu_paths)
    if host == "ours":
        from altfusion.cosim.runner import simulate

        return simulate(spec, loaded.fmu_paths, stop_time=stop)
    from altfusion.interop.engines import run_in_subprocess

    with tempfile.TemporaryDirectory(prefix="altfusion_timing_") as work:
        ssp = write_ssp(spec, loaded.fmu_paths, Path(work) / f"{spec.name}.ssp")
        return run_in_subprocess(host, ssp, stop)


def results_table(results: Results) -> ResultTable:
    """Our Results as a :class:`ResultTable` (first row of each time)."""
    rows = first_row_per_time(results.time)
    return ResultTable(results.time[rows], {name: values[rows] for name, values in
                                            results.columns.items()}, "altfusion")


def check_table(streams: tuple[Stream, ...], table: ResultTable,
                step: float | None = None) -> list[StreamResult]:
    """Every stream checked on ``table``; a UsageError if the table records none of them."""
    results = [check_stream(stream, table.time, table.columns, step) for stream in streams]
    if not any(result.recorded for result in results):
        names = ", ".join(s.count_column for s in streams)
        raise UsageError(f"the result records no sample count and stamp of the system's "
                         f"streams ({names}): record them with altfusion run --record timing "
                         f"or altfusion timing SYSTEM.ssp --engine HOST --csv OUT.csv")
    return results


def is_ssp(path: Path) -> bool:
    """Whether ``path`` is an SSP archive (a zip holding SystemStructure.ssd)."""
    return zipfile.is_zipfile(path) and "SystemStructure.ssd" in zipfile.ZipFile(
        path).namelist()


def command_timing(args: argparse.Namespace) -> int:
    """0 when every recorded stream holds its declared timing, 1 when any does not."""
    target = Path(args.target)
    if args.step is not None and args.step <= 0:
        raise UsageError(f"--step {args.step!r}: expected a step > 0 s")
    if not target.is_file():
        raise UsageError(f"{target}: no such file")
    if is_ssp(target):
        if args.system is not None:
            raise UsageError(f"{target} is a system: --system names the system of a result "
                             f"file")
        loaded = read_ssp(target)
        streams = sensor_streams(loaded.spec, loaded.fmu_paths)
        host = args.engine or "ours"
        results = run_for_timing(loaded, host, args.stop)
        if args.csv is not None:
            results.to_csv(args.csv)
        table = results_table(results)
        source = f"{loaded.spec.name} run in {host} to {results.time[-1]:g} s"
    else:
        if args.system is None:
            raise UsageError(f"{target}: a result file needs --system SYSTEM.ssp (the system "
                             f"it is a result of)")
        if args.engine is not None or args.stop is not None or args.csv is not None:
            raise UsageError("--engine, --stop and --csv run a system; a result file is "
                             "checked as it is")
        loaded = read_ssp(args.system)
        streams = sensor_streams(loaded.spec, loaded.fmu_paths)
        table = read_result(target, {c.name for c in loaded.spec.components})
        source = f"{target} ({table.layout} layout, {table.time.size} rows to " \
                 f"{table.time[-1]:g} s) against {loaded.spec.name}"
    checked = check_table(streams, table, args.step)
    print(f"timing of {source}\n")
    print(format_report(checked))
    return 0 if all(result.ok for result in checked) else 1


def add_command(commands: argparse._SubParsersAction, finite_time) -> None:
    """The ``timing`` subcommand; ``finite_time`` parses --stop (as ``altfusion run``)."""
    timing = commands.add_parser(
        "timing", help="check every sensor stream's multi-rate timing in a run or a result "
                       "file (docs/timing.md)")
    timing.add_argument("target", type=Path,
                        help="SSP archive to run, or a result CSV from any host (with --system)")
    timing.add_argument("--system", type=Path, default=None,
                        help="the SSP archive a result CSV is a result of")
    timing.add_argument("--engine", choices=HOSTS, default=None,
                        help="host to run the system in (default: ours)")
    timing.add_argument("--stop", type=finite_time, default=None, help="stop time, s")
    timing.add_argument("--csv", type=Path, default=None,
                        help="also write the run's result here")
    timing.add_argument("--step", type=finite_time, default=None,
                        help="the communication step the host took for every component, s "
                             "(default: each component's own step in the SSP)")
    timing.set_defaults(handler=command_timing)
