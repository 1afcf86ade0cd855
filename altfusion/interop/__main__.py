"""``python -m altfusion.interop``: run one engine once, in this process, and write a CSV.

    python -m altfusion.interop run --engine libcosim models/plant_yang2020.ssp --csv out.csv
    python -m altfusion.interop simulate-fmu Container.fmu --step 0.01 --stop 10 \\
        --output plant.h --csv out.csv [--input inputs.npy]

Third-party engines may unload FMU libraries, which pythonfmu does not survive within one
process: the tests run each engine through this entry point in a fresh process. At exit, the
pythonfmu state of every FMU library the engine loaded is released before the C++ static
destructors run (``altfusion.cosim.instances.release_mapped_pythonfmu_state``), which
otherwise abort the process now and then ("corrupted double-linked list").
"""

import argparse
import atexit
import sys
from pathlib import Path

import numpy as np

from altfusion.cosim.results import Results


def run_engine(engine: str, ssp: Path, stop_time: float | None = None,
               osp: Path | None = None) -> Results:
    """Run the system of ``ssp`` in ``engine`` (``libcosim-osp`` runs the folder ``osp``)."""
    from altfusion.cosim.ssp import read_ssp
    from altfusion.interop.engines import ENGINES, run_altfusion, run_ecos, run_libcosim
    from altfusion.interop.proxy import run_ecos_proxy

    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}; known: {ENGINES}")
    if engine in ("altfusion", "altfusion-jacobi"):
        master = "jacobi" if engine.endswith("jacobi") else "ordered"
        return run_altfusion(ssp, stop_time, master)
    loaded = read_ssp(ssp)
    system, fmu_paths = loaded.spec, loaded.fmu_paths
    if engine == "libcosim":
        return run_libcosim(ssp, system, fmu_paths, stop_time)
    if engine == "libcosim-osp":
        if osp is None:
            raise ValueError("engine libcosim-osp needs the OSP folder")
        return run_libcosim(osp, system, fmu_paths, stop_time)
    if engine == "ecos":
        return run_ecos(ssp, system, fmu_paths, stop_time)
    return run_ecos_proxy(ssp, system, fmu_paths, stop_time)


def main(argv: list[str] | None = None) -> int:
    from altfusion.cosim.instances import CosimError, release_mapped_pythonfmu_state
    from altfusion.interop.engines import ENGINES, EngineError

    atexit.register(release_mapped_pythonfmu_state)
    parser = argparse.ArgumentParser(prog="python -m altfusion.interop",
                                     description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="run an SSP system in one engine")
    run.add_argument("system", type=Path, help="the .ssp archive")
    run.add_argument("--engine", choices=ENGINES, required=True)
    run.add_argument("--csv", type=Path, required=True, help="where to write the results")
    run.add_argument("--stop", type=float, default=None, help="stop time, s")
    run.add_argument("--osp", type=Path, default=None, help="OSP folder (libcosim-osp)")
    fmu = commands.add_parser("simulate-fmu", help="simulate one FMU with fmpy")
    fmu.add_argument("fmu", type=Path)
    fmu.add_argument("--step", type=float, required=True, help="communication step, s")
    fmu.add_argument("--stop", type=float, required=True, help="stop time, s")
    fmu.add_argument("--output", action="append", required=True, help="output to record")
    fmu.add_argument("--input", type=Path, default=None, help="input table (.npy)")
    fmu.add_argument("--csv", type=Path, required=True)
    args = parser.parse_args(argv)
    try:
        if args.command == "run":
            results = run_engine(args.engine, args.system, args.stop, args.osp)
        else:
            from altfusion.interop.container import simulate_container

            inputs = np.load(args.input) if args.input is not None else None
            results = simulate_container(args.fmu, args.step, args.stop, args.output,
                                         inputs=inputs)
    except EngineError as error:                # the engine's run failed: its own words
        print(f"error: {error}", file=sys.stderr)
        return 1
    except (CosimError, OSError, ValueError) as error:   # a bad file, system or value
        print(f"error: {error}", file=sys.stderr)
        return 2
    results.to_csv(args.csv)
    return 0


if __name__ == "__main__":
    sys.exit(main())
