"""Command line: ``altfusion run SYSTEM.ssp`` and friends."""

import argparse
import math
import platform
import signal
import sys
from dataclasses import replace
from importlib import import_module
from pathlib import Path
from typing import NoReturn

from altfusion.atomic import output_folder
from altfusion.compiled import COMPILED, is_compiled
from altfusion.cosim.instances import CosimError
from altfusion.cosim.runner import RunFailedError, RunInterruptedError, Simulation
from altfusion.cosim.settings import parse_settings
from altfusion.cosim.ssp import LoadedSystem, read_ssp
from altfusion.errors import ParameterError, UsageError
from altfusion.estimators.registry import ESTIMATOR_CLASSES
from altfusion.evaluation.command import add_command as add_evaluate_command
from altfusion.montecarlo.commands import add_commands as add_montecarlo_commands
from altfusion.timing.command import add_command as add_timing_command
from altfusion.timing.command import with_timing_record
from altfusion.version import CORE_VERSION

INCOMPLETE = ".incomplete"
"""Suffix before '.csv'/'.png' of the results of a run that failed or was interrupted part
way."""

INTERRUPTED = 130
"""Exit status after Ctrl-C (128 + SIGINT), as ``altfusion mc``'s."""


def command_run(args: argparse.Namespace) -> int:
    from altfusion.health_events import format_events, health_events, write_events
    from altfusion.plotting import plot_results
    from altfusion.summary import format_summary, write_warnings

    loaded = read_ssp(args.system)
    if args.fault is not None:
        loaded = apply_fault(args.system, loaded, args.fault)
    settings = parse_settings(loaded, args.set)
    spec = loaded.spec
    if args.record == "timing":
        spec = with_timing_record(spec, loaded.fmu_paths)
    out = output_folder(args.out)
    failure = None
    with Interrupts() as interrupts, \
            Simulation(spec, loaded.fmu_paths, backend=args.backend) as simulation:
        interrupts.watch(simulation)
        try:
            results = simulation.run(stop_time=args.stop, parameters=settings)
        except RunFailedError as error:
            failure, results = error, error.results
        except ParameterError as error:
            if error.name == "stop_time" and args.stop is not None:
                raise UsageError(f"--stop {args.stop:g}: {error.reason}") from error
            raise
    stem = f"{spec.name}{INCOMPLETE}" if failure else spec.name
    csv_path = results.to_csv(out / f"{stem}.csv")
    files = [str(csv_path)]
    if len(results.time) > 1:
        files.append(str(plot_results(results, out / f"{stem}.png", spec.name,
                                      spec.description)))
    events = health_events(results)
    events_file = str(write_events(events, out / f"{stem}.events.csv")) if events else ""
    warnings = write_warnings(results, out / f"{stem}.warnings.txt")
    files += [events_file] if events else []
    files += [str(warnings[0])] if warnings else []
    print(f"{spec.name}: {spec.description}")
    print(f"simulated {results.time[0]:g} s to {results.time[-1]:g} s "
          f"({len(spec.components)} components, base step {spec.base_step:g} s)\n")
    if len(results.time) > 1:
        print(format_summary(results, spec.metrics))
    if events:
        print(f"\n{format_events(events, events_file)}")
    if warnings:
        print(f"\n{warnings[1]}")
    print(f"\nwrote {', '.join(files)}")
    if isinstance(failure, RunInterruptedError):
        print(f"error: {failure}, results so far written (marked {INCOMPLETE})",
              file=sys.stderr)
        return INTERRUPTED
    if failure:
        print(f"error: run failed after t = {results.time[-1]:g} s, results so far written "
              f"(marked {INCOMPLETE}): {one_line(failure)}", file=sys.stderr)
        return 1
    return 0


class Interrupts:
    """Ctrl-C (SIGINT) noted, never raised, while a simulation runs: a KeyboardInterrupt
    raised inside an FMU's Python code would become that FMU's fmi2Fatal. Every press asks the
    watched simulation to stop after its current base step (:meth:`Simulation.interrupt`)."""

    def __init__(self) -> None:
        self.simulation: Simulation | None = None
        self.requested = False

    def __enter__(self) -> "Interrupts":
        self._previous = signal.signal(signal.SIGINT, self._note)
        return self

    def __exit__(self, *_exc) -> None:
        signal.signal(signal.SIGINT, self._previous)

    def _note(self, _signum, _frame) -> None:
        self.requested = True
        if self.simulation is not None:
            self.simulation.interrupt()

    def watch(self, simulation: Simulation) -> None:
        """Stop ``simulation`` on Ctrl-C (at once if it was pressed while it was built)."""
        self.simulation = simulation
        if self.requested:
            simulation.interrupt()


def apply_fault(ssp: Path, loaded: LoadedSystem, fault: str) -> LoadedSystem:
    """``loaded`` with fault scenario ``fault`` inserted, its SensorFaults FMU taken from the
    SSP or found next to it; ValueError for an unknown fault or one the system cannot take."""
    from altfusion.montecarlo.swap import find_fmu
    from altfusion.systems.faults import FAULT_COMPONENT, FAULT_FMU, with_fault

    spec = with_fault(loaded.spec, fault)
    located = find_fmu(FAULT_COMPONENT, FAULT_FMU, ssp, loaded.fmu_paths)
    fmu_paths = dict(loaded.fmu_paths)
    if located.path is not None:
        fmu_paths[located.fmu] = located.path
    return replace(loaded, spec=spec, fmu_paths=fmu_paths)


def command_replay(args: argparse.Namespace) -> int:
    from altfusion.health_events import format_events, health_events, write_events
    from altfusion.replay.compare import format_table, sample_counts
    from altfusion.replay.run import plan_replay, run_replay
    from altfusion.replay.ulog import LogReadError
    from altfusion.summary import write_warnings

    out = output_folder(args.out)
    fmu_paths = {path.stem: path for path in Path(args.models).glob("*.fmu")}
    if not fmu_paths:
        raise UsageError(f"no FMU in {args.models} (build them: python build_fmu.py, or give "
                         f"their folder with --models)")
    estimators = [name.strip() for name in args.estimators.split(",") if name.strip()]
    if not estimators:
        raise UsageError(f"--estimators {args.estimators!r}: names no estimator (FMU model "
                         f"names, comma-separated)")
    try:
        plan = plan_replay(args.log, estimators, fmu_paths, args.paper_tuning,
                           args.time_offset)
        settings = parse_settings(LoadedSystem(plan.spec, fmu_paths), args.set)
        replay = run_replay(plan, fmu_paths, out, settings)
    except LogReadError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    log = replay.log
    print(f"{Path(args.log).name}: {log.duration:.3f} s replayed to "
          f"{replay.results.time[-1]:g} s (base step {replay.spec.base_step:g} s)")
    for line in log.report():
        print(f"  log: {line}")
    for name, inputs in replay.unconnected.items():
        print(f"  warning: {name} inputs not in the log, left at their defaults: "
              f"{', '.join(inputs)}")
    expected = {p: len(s) for p, s in log.streams.items()}
    counts = ", ".join(f"{p} {n} of {expected.get(p, 0)}"
                       for p, n in sample_counts(replay.results).items() if expected.get(p))
    print(f"  samples delivered: {counts}")
    print(f"\nFrom t = {replay.settle_time:.2f} s (5 s after the first GPS fix: offsets "
          f"learnt); heights in m, MSL. 'vs EKF2' at EKF2 samples: d = h - ekf_h, std = d in "
          f"a common datum (mean removed); GPS innov = gps_h - prior h; NIS over h_std² + "
          f"epv²; h-range = implied ground height, flat ground.\n")
    print(format_table(replay.reports))
    events = health_events(replay.results)
    files = [*replay.files, write_events(events, out / f"{replay.spec.name}.events.csv")]
    print(f"\n{format_events(events, str(files[-1]))}")
    warnings = write_warnings(replay.results, out / f"{replay.spec.name}.warnings.txt",
                              leave_out=("replay",))        # the log's report, printed above
    if warnings:
        files.append(warnings[0])
        print(f"\n{warnings[1]}")
    print(f"\nwrote {', '.join(str(f) for f in files)}")
    return 0


def command_controller_design(args: argparse.Namespace) -> int:
    from altfusion.physics.controller_design import design, report

    print(report(design()))
    return 0


def command_reproduce(args: argparse.Namespace) -> int:
    from altfusion.reproduce import ReproduceOptions, reproduction

    options = ReproduceOptions(out=output_folder(args.out or f"results/reproduce_{args.name}"),
                               runs=args.runs, workers=args.workers, scheduler=args.scheduler,
                               master_seed=args.seed, resume=args.resume, models=args.models,
                               paper_algorithm=args.paper_algorithm, backend=args.backend)
    return reproduction(args.name).reproduce(options)


def version() -> str:
    """The core version, the interpreter, and whether the estimators' Kalman steps and
    machinery run compiled here (:mod:`altfusion.compiled`: the same bits either way, the
    compiled ones faster)."""
    modules = [import_module(f"altfusion.{package}.{name}")
               for package, names in COMPILED.items() for name in names]
    how = "compiled (mypyc)" if all(map(is_compiled, modules)) else (
        "Python sources (python build_fmu.py compiles them for this Python)")
    return (f"altfusion {CORE_VERSION}, Python {platform.python_version()}, "
            f"estimator machinery: {how}")


class _Version(argparse.Action):
    """``--version``: :func:`version` as it is, unwrapped."""

    def __call__(self, parser, namespace, values, option_string=None) -> NoReturn:
        print(version())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="altfusion", description=__doc__)
    parser.add_argument("--debug", action="store_true",
                        help="show Python tracebacks instead of one-line errors")
    parser.add_argument("--version", action=_Version, nargs=0,
                        help="print the core version, the Python and whether the estimator "
                             "machinery runs compiled, and exit")
    commands = parser.add_subparsers(dest="command", required=True,
                                     parser_class=_Parser)
    run = commands.add_parser("run", help="co-simulate an SSP system, write CSV and a plot")
    run.add_argument("system", type=Path, help="SSP archive (models/*.ssp)")
    run.add_argument("--stop", type=finite_time, default=None, help="stop time, s")
    run.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE",
                     help="override a parameter (repeatable)")
    run.add_argument("--out", default="results", help="output folder (default: results)")
    run.add_argument("--backend", choices=("fmu", "core"), default="fmu",
                     help="step the FMUs (default) or their core objects directly")
    run.add_argument("--fault", default=None, metavar="NAME",
                     help="apply fault scenario NAME of the fault suite (docs/faults.md)")
    run.add_argument("--record", choices=("timing",), default=None,
                     help="timing: also record every sensor stream's count, stamp and "
                          "validity and the estimators' input counts, every base step "
                          "(altfusion timing)")
    run.set_defaults(handler=command_run)
    replay = commands.add_parser(
        "replay", help="run estimators on a PX4 flight log (ULog), compare with PX4 EKF2")
    replay.add_argument("log", type=Path, help="PX4 ULog file (.ulg)")
    replay.add_argument("--estimators", default=",".join(ESTIMATOR_CLASSES),
                        help="comma-separated estimator FMU names (default: %(default)s)")
    replay.add_argument("--models", default="models", help="folder of the built FMUs")
    replay.add_argument("--out", default="results", help="output folder (default: results)")
    replay.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE",
                        help="override a parameter (repeatable; components: replay and the "
                             "estimator names)")
    replay.add_argument("--paper-tuning", action="store_true",
                        help="run the estimators with their papers' defaults instead of the "
                             "replay tuning")
    replay.add_argument("--time-offset", type=finite_time, default=0.0,
                        help="log time replayed at simulation time 0, s")
    replay.set_defaults(handler=command_replay)
    design = commands.add_parser("controller-design",
                                 help="print the FlightController design (poles, margins)")
    design.set_defaults(handler=command_controller_design)
    add_montecarlo_commands(commands)
    add_evaluate_command(commands)
    add_timing_command(commands, finite_time)
    from altfusion.reproduce import REPRODUCTIONS

    reproduce = commands.add_parser("reproduce",
                                    help="run a paper's simulation section, write its figures")
    reproduce.add_argument("name", choices=REPRODUCTIONS)
    reproduce.add_argument("-n", "--runs", type=int, default=None,
                           help="Monte Carlo runs (default: the paper's)")
    reproduce.add_argument("--workers", type=int, default=None)
    reproduce.add_argument("--scheduler", default=None, help="Dask scheduler address")
    reproduce.add_argument("--seed", type=int, default=0, help="master seed")
    reproduce.add_argument("--resume", action="store_true")
    reproduce.add_argument("--models", type=Path, default=Path("models"))
    reproduce.add_argument("--paper-algorithm", action="store_true",
                           help="every estimator with fault_detection false (the papers' "
                                "algorithms, without resets, isolation and bias states)")
    reproduce.add_argument("--backend", choices=("core", "fmu"), default="core",
                           help="step the FMUs' core objects in-process (default, same numbers, "
                                "faster) or through FMI")
    reproduce.add_argument("--out", default=None,
                           help="output folder (default: results/reproduce_NAME)")
    reproduce.set_defaults(handler=command_reproduce)
    return parser


class _Parser(argparse.ArgumentParser):
    """argparse with the one-line ``error: ...`` convention (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"error: {self.prog}: {message} (see {self.prog} --help)\n")


def finite_time(text: str) -> float:
    """A finite time >= 0 in s (argparse type of --stop)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a time in s, not {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"expected a finite time >= 0 s, not {text!r}")
    return value


USER_ERRORS = (UsageError, ParameterError, CosimError, OSError, KeyError, ValueError)
"""What a user's mistake raises (a bad file, name or value): reported in one line, status 2."""


def one_line(error: BaseException) -> str:
    """The first line of an error's message (a component's report may append its traceback;
    ``--debug`` shows all of it)."""
    message = error.args[0] if isinstance(error, KeyError) and error.args else str(error)
    return str(message).strip().splitlines()[0] if str(message).strip() else repr(error)


def main(argv: list[str] | None = None) -> int:
    """Run a command: 0 on success, 1 when a run failed (results so far written),
    2 on a user's mistake (one line ``error: ...`` on stderr; ``--debug``: the traceback)."""
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("error: interrupted", file=sys.stderr)
        return INTERRUPTED
    except USER_ERRORS as error:
        if args.debug:
            raise
        print(f"error: {one_line(error)}", file=sys.stderr)
        return 2
    except Exception as error:
        if args.debug:
            raise
        print(f"error: {type(error).__name__}: {one_line(error)} (rerun with --debug for "
              f"the traceback)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
