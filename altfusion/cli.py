"""Command line: ``altfusion run SYSTEM.ssp`` and friends."""

import argparse
import sys
from pathlib import Path
from typing import Any

from altfusion.cosim.instances import PY_TYPES, CosimError, fmu_info
from altfusion.cosim.runner import Simulation
from altfusion.cosim.ssp import LoadedSystem, read_ssp
from altfusion.montecarlo.commands import add_commands as add_montecarlo_commands


def parse_settings(loaded: LoadedSystem, settings: list[str]) -> dict[str, Any]:
    """'comp.var=value' strings converted to each parameter's FMI type."""
    values: dict[str, Any] = {}
    for setting in settings:
        path, sep, text = setting.partition("=")
        component, _, name = path.partition(".")
        if not sep or not name:
            raise SystemExit(f"--set {setting!r}: expected component.parameter=value")
        spec = loaded.spec.component(component)
        var = fmu_info(loaded.fmu_paths[spec.fmu]).variables.get(name)
        if var is None or var.causality != "parameter":
            raise SystemExit(f"--set {setting!r}: {spec.fmu} has no parameter '{name}'")
        kind = PY_TYPES[var.type]
        if kind is bool:
            values[path] = text.strip().lower() in ("1", "true", "yes")
        else:
            values[path] = kind(float(text)) if kind is int else kind(text)
    return values


def command_run(args: argparse.Namespace) -> int:
    from altfusion.plotting import plot_results
    from altfusion.summary import format_summary

    loaded = read_ssp(args.system)
    settings = parse_settings(loaded, args.set)
    spec = loaded.spec
    with Simulation(spec, loaded.fmu_paths, backend=args.backend) as simulation:
        results = simulation.run(stop_time=args.stop, parameters=settings)
    out = Path(args.out)
    csv_path = results.to_csv(out / f"{spec.name}.csv")
    png_path = plot_results(results, out / f"{spec.name}.png", spec.name, spec.description)
    print(f"{spec.name}: {spec.description}")
    print(f"simulated {results.time[0]:g} s to {results.time[-1]:g} s "
          f"({len(spec.components)} components, base step {spec.base_step:g} s)\n")
    print(format_summary(results, spec.metrics))
    print(f"\nwrote {csv_path} and {png_path}")
    return 0


def command_controller_design(args: argparse.Namespace) -> int:
    from altfusion.physics.controller_design import design, report

    print(report(design()))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="altfusion", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="co-simulate an SSP system, write CSV and a plot")
    run.add_argument("system", type=Path, help="SSP archive (models/*.ssp)")
    run.add_argument("--stop", type=float, default=None, help="stop time, s")
    run.add_argument("--set", action="append", default=[], metavar="COMP.PARAM=VALUE",
                     help="override a parameter (repeatable)")
    run.add_argument("--out", default="results", help="output folder (default: results)")
    run.add_argument("--backend", choices=("fmu", "core"), default="fmu",
                     help="step the FMUs (default) or their core objects directly")
    run.set_defaults(handler=command_run)
    design = commands.add_parser("controller-design",
                                 help="print the FlightController design (poles, margins)")
    design.set_defaults(handler=command_controller_design)
    add_montecarlo_commands(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except CosimError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
