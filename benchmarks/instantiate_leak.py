"""Memory kept per instantiate/free cycle (run by hand; results in benchmarks/RESULTS.md).

Each FMU is extracted once and its library loaded once; a cycle is what a host does for a
fresh instance: fmi2Instantiate, setupExperiment, enter/exitInitializationMode, one doStep,
fmi2FreeInstance. Each FMU is measured in a process of its own (pythonfmu 0.7.0 imports the
core of the first FMU a process loads). After ``--warmup`` cycles (allocator pools and caches
filled), the resident memory (/proc/self/statm) is read, ``--cycles`` more cycles run, and
the growth per cycle is printed. ``--trace`` adds the Python allocations kept over the cycles
(tracemalloc), largest first, to tell Python objects from native memory.

    python benchmarks/instantiate_leak.py                      # 2000 cycles per FMU
    python benchmarks/instantiate_leak.py --cycles 500 --trace BaselineKF
    python benchmarks/instantiate_leak.py --without-shim    # pythonfmu's library instead

The native shim (``altfusion.fmi.shim``) resets a freed instance and hands it to the next
fmi2Instantiate of the same FMU, so pythonfmu runs its per-instantiation path (which keeps
about 1 kB) only for the first instances.
"""

import argparse
import gc
import os
import shutil
import subprocess
import sys
import tempfile
import tracemalloc
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from altfusion.fmi.shim import PYTHONFMU_LIBRARY

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
DEFAULT_FMUS = ("BaselineKF", "XuSHAEKF", "GnssReceiver")


def resident_bytes() -> int:
    """Resident set size of this process (bytes)."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def cycles(fmu: FMU2Slave, count: int, step_size: float) -> None:
    """``count`` instantiate/initialize/step/free cycles on the loaded library."""
    for _ in range(count):
        fmu.instantiate()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.doStep(0.0, step_size)
        fmu.terminate()
        fmu.fmi2FreeInstance(fmu.component)


def measure(name: str, warmup: int, count: int, trace: bool, without_shim: bool) -> float:
    """Bytes of resident memory kept per cycle of the FMU ``name`` (``without_shim``: with
    pythonfmu's library in place of our native shim, as FMUs were built before it)."""
    path = MODELS / f"{name}.fmu"
    description = read_model_description(str(path))
    step_size = float(description.defaultExperiment.stepSize)
    identifier = description.coSimulation.modelIdentifier
    with tempfile.TemporaryDirectory() as folder:
        unzipped = extract(str(path), folder)
        if without_shim:
            binaries = Path(unzipped, "binaries", "linux64")
            shutil.copyfile(binaries / PYTHONFMU_LIBRARY, binaries / f"{identifier}.so")
        fmu = FMU2Slave(guid=description.guid, unzipDirectory=unzipped,
                        modelIdentifier=identifier, instanceName=name)
        cycles(fmu, warmup, step_size)
        gc.collect()
        if trace:
            tracemalloc.start(10)
            before_trace = tracemalloc.take_snapshot()
        before = resident_bytes()
        cycles(fmu, count, step_size)
        gc.collect()
        growth = (resident_bytes() - before) / count
        if trace:
            stats = tracemalloc.take_snapshot().compare_to(before_trace, "traceback")
            tracemalloc.stop()
            print(f"  Python allocations kept by {name} over {count} cycles:")
            for stat in stats[:8]:
                print(f"    {stat.size_diff / count:8.1f} B/cycle  {stat.traceback.format()[-1]}")
    return growth


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("fmus", nargs="*", default=DEFAULT_FMUS)
    parser.add_argument("--cycles", type=int, default=2000)
    parser.add_argument("--warmup", type=int, default=200)
    parser.add_argument("--trace", action="store_true")
    parser.add_argument("--without-shim", action="store_true",
                        help="run pythonfmu's library in place of the native shim")
    parser.add_argument("--one", action="store_true", help="measure in this process")
    args = parser.parse_args()
    if args.one:
        (name,) = args.fmus
        growth = measure(name, args.warmup, args.cycles, args.trace, args.without_shim)
        print(f"| {name} | {growth:.0f} B |")
        return
    binary = "pythonfmu's library" if args.without_shim else "native shim"
    print(f"| FMU | growth per instantiate/free cycle ({args.cycles} cycles, "
          f"after {args.warmup}; {binary}) |")
    print("|---|---:|")
    for name in args.fmus:
        options = ["--cycles", str(args.cycles), "--warmup", str(args.warmup),
                   *(["--trace"] if args.trace else []),
                   *(["--without-shim"] if args.without_shim else [])]
        subprocess.run([sys.executable, __file__, "--one", *options, name], check=True)


if __name__ == "__main__":
    main()
