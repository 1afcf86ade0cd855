"""Co-simulation speed: real-time factor, FMI overhead ratio and the cost per step of each
FMU and of the runner. Run by hand (never as a test):

    python benchmarks/cosim_speed.py [SYSTEM ...] [--stop T] [--repeat N]

SYSTEM names come from altfusion.systems (default: every system whose components all have
built FMUs in models/). For each system it prints:
- the real-time factor (simulated s per wall s) through the FMUs and with the core objects
  stepped directly (backend "core"), and their ratio (the FMI overhead ratio);
- whether both backends give identical results;
- the CPU time per call of each component's do_step and of the runner's own work (best
  of ``--repeat`` runs);
- with ``--engines``, the real-time factor of the same SSP in libcosim and ECOS (each run in
  a fresh process as the interop tests do; start-up is removed by subtracting a 1 s run).

Every time is given twice: wall clock, and CPU time of the simulating process (for engines
run in a subprocess: of the child processes). On an idle machine the two agree; on a shared
one the wall clock includes the time the process waited for a core, and the CPU time is the
figure that compares across measurements.
"""

import argparse
import resource
import statistics
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from altfusion.cosim import Simulation
from altfusion.systems import SYSTEMS, build_system

MODELS = Path(__file__).resolve().parents[1] / "models"


def timed_run(system, fmus, backend, stop, repeat):
    """Best wall and CPU time of ``repeat`` runs (instances reused), and the last results."""
    walls, cpus = [], []
    with Simulation(system, fmus, backend) as simulation:
        simulation.run(stop_time=min(stop, 1.0))  # warm-up: imports, first instantiation
        for _ in range(repeat):
            start, cpu = time.perf_counter(), time.process_time()
            results = simulation.run(stop_time=stop)
            walls.append(time.perf_counter() - start)
            cpus.append(time.process_time() - cpu)
    return min(walls), min(cpus), results


def step_costs(system, fmus, stop, repeat):
    """CPU seconds per do_step call of each component, and the runner's remaining CPU time per
    base step (the clock calls themselves, ~0.1 µs each, count in the component's share):
    each the best of ``repeat`` runs (instances reused), as the real-time factors are."""
    costs: dict[str, list[float]] = defaultdict(list)
    best: dict[str, float] = {}
    best_runner = float("inf")
    base_steps = round(stop / system.base_step)
    with Simulation(system, fmus, "fmu") as simulation:
        for component in simulation._components:
            original = component.step

            def timed(t, h, original=original, name=component.name):
                start = time.thread_time()
                original(t, h)
                costs[name].append(time.thread_time() - start)

            component.step = timed
        for _ in range(repeat):
            costs.clear()
            start = time.thread_time()
            simulation.run(stop_time=stop)
            wall = time.thread_time() - start
            stepping = sum(sum(c) for c in costs.values())
            for name, c in costs.items():
                best[name] = min(best.get(name, float("inf")), statistics.fmean(c))
            best_runner = min(best_runner, (wall - stepping) / base_steps)
    return best, best_runner


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def engine_rtf(engine: str, ssp: Path, stop: float) -> tuple[float, float]:
    """Simulated seconds per wall second and per CPU second of ``engine``, start-up and
    loading excluded."""
    from altfusion.interop.engines import run_in_subprocess

    walls, cpus = [], []
    for duration in (1.0, stop):
        start, cpu = time.perf_counter(), children_cpu()
        run_in_subprocess(engine, ssp, stop_time=duration)
        walls.append(time.perf_counter() - start)
        cpus.append(children_cpu() - cpu)
    return ((stop - 1.0) / max(walls[1] - walls[0], 1e-9),
            (stop - 1.0) / max(cpus[1] - cpus[0], 1e-9))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("systems", nargs="*")
    parser.add_argument("--stop", type=float, default=None, help="simulated time, s")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--engines", action="store_true",
                        help="also time the system in libcosim and ECOS (extra 'interop')")
    args = parser.parse_args()
    fmus = {p.stem: p for p in MODELS.glob("*.fmu")}
    names = args.systems or [n for n in SYSTEMS
                             if all(c.fmu in fmus for c in build_system(n).components)]
    for name in names:
        system = build_system(name)
        stop = args.stop or system.stop_time
        fmu_wall, fmu_cpu, fmu_results = timed_run(system, fmus, "fmu", stop, args.repeat)
        core_wall, core_cpu, core_results = timed_run(system, fmus, "core", stop, args.repeat)
        identical = all(np.array_equal(fmu_results[c], core_results[c])
                        for c in fmu_results.columns)
        print(f"\n{name}: {len(system.components)} components, base step "
              f"{system.base_step} s, {stop:g} s simulated")
        print("                                  wall      CPU")
        print(f"  real-time factor, FMUs      : {stop / fmu_wall:8.1f} {stop / fmu_cpu:8.1f}"
              f"  ({fmu_wall:.2f} s wall, {fmu_cpu:.2f} s CPU)")
        print(f"  real-time factor, core only : {stop / core_wall:8.1f} {stop / core_cpu:8.1f}"
              f"  ({core_wall:.2f} s wall, {core_cpu:.2f} s CPU)")
        print(f"  FMI overhead ratio          : {fmu_wall / core_wall:8.2f} "
              f"{fmu_cpu / core_cpu:8.2f}")
        print(f"  identical results           : {identical}")
        per_step, runner = step_costs(system, fmus, stop, args.repeat)
        for component, seconds in per_step.items():
            spec = system.component(component)
            print(f"  {component:<14} ({spec.fmu}, step {spec.step_size:g} s): "
                  f"{seconds * 1e6:7.1f} µs CPU per do_step")
        print(f"  runner (transfer, recording, bookkeeping): {runner * 1e6:7.1f} µs CPU per "
              f"base step")
        if args.engines:
            for engine in ("altfusion", "libcosim", "ecos"):
                wall_rtf, cpu_rtf = engine_rtf(engine, MODELS / f"{name}.ssp", stop)
                print(f"  real-time factor, {engine:<9} (own process, start-up excluded): "
                      f"{wall_rtf:8.1f} wall {cpu_rtf:8.1f} CPU")


if __name__ == "__main__":
    main()
