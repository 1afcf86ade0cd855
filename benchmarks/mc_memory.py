"""Monte Carlo benchmark (run by hand; results in benchmarks/RESULTS.md).

1. Memory: one local worker process runs ``--runs`` runs through one reused Simulation; its
   resident memory (/proc/self/statm, recorded with every run) is printed after each batch.
   A worker whose memory grows with the number of runs it executes would fail long
   campaigns; reuse through fmi2Reset must keep it flat.
2. Contrast (``--contrast N``): N fresh Simulations (instantiate, run, free) in one process,
   the pattern the campaign avoids; shows the per-instantiation leak of pythonfmu 0.7.0.
3. Throughput: campaigns of ``--throughput-runs`` runs with 1 and 2 local workers, wall clock
   including worker start-up.

    python benchmarks/mc_memory.py                 # defaults: 200 runs, batches of 20
    python benchmarks/mc_memory.py --runs 1000 --contrast 50
"""

import argparse
import os
import platform
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from altfusion.cosim import Simulation, read_ssp
from altfusion.montecarlo.execution import CampaignSettings, Execution, run_campaign
from altfusion.montecarlo.source import SystemSource
from altfusion.montecarlo.storage import read_run, resident_memory, run_path

ROOT = Path(__file__).resolve().parents[1]
SSP = ROOT / "models" / "plant_yang2020.ssp"
RANDOM_WEATHER = {"atmosphere.lapse_rate_std": 0.003, "atmosphere.gust_std": 1.0,
                  "atmosphere.wind_mean": 3.0}
MIB = 1 << 20


def campaign(out: Path, runs: int, workers: int, stop: float) -> tuple[float, list]:
    """Run a campaign; (wall-clock seconds, run records)."""
    start = time.monotonic()
    outcome = run_campaign(SystemSource.from_path(SSP), out,
                           CampaignSettings(runs, 0, stop, RANDOM_WEATHER),
                           Execution(workers=workers, progress=False))
    elapsed = time.monotonic() - start
    assert outcome.complete, outcome
    return elapsed, [read_run(out, index) for index in range(runs)]


def memory(runs: int, batch: int, stop: float) -> None:
    with tempfile.TemporaryDirectory() as folder:
        _, records = campaign(Path(folder), runs, 1, stop)
        size = np.mean([run_path(folder, i).stat().st_size for i in range(runs)])
    rss = np.array([r.worker_rss for r in records], dtype=float)
    assert len({r.worker for r in records}) == 1
    print(f"\n## Worker memory: {runs} runs of plant_yang2020 ({stop:g} s, random weather) "
          f"through one Simulation\n")
    print("| runs done | worker RSS (MiB) | change since first batch (MiB) |")
    print("|---:|---:|---:|")
    first = rss[batch - 1]
    for end in range(batch, runs + 1, batch):
        print(f"| {end} | {rss[end - 1] / MIB:.1f} | {(rss[end - 1] - first) / MIB:+.2f} |")
    half = np.arange(runs // 2, runs)
    slope = np.polyfit(half, rss[runs // 2:], 1)[0] if half.size > 1 else 0.0
    print(f"\nRSS slope over the second half of the runs: {slope / 1024:+.2f} KiB/run; "
          f"run file on disk: {size / 1024:.1f} KiB/run; "
          f"mean run time {np.mean([r.elapsed for r in records]):.3f} s")


def fresh_simulations(count: int, stop: float) -> list[int]:
    """In this (worker) process: instantiate, run once and free a Simulation ``count`` times."""
    loaded = read_ssp(SSP)
    sizes = []
    for _ in range(count):
        with Simulation(loaded.spec, loaded.fmu_paths) as simulation:
            simulation.run(stop_time=stop, parameters=RANDOM_WEATHER)
        sizes.append(resident_memory())
    return sizes


def contrast(count: int, stop: float) -> None:
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        sizes = np.array(pool.submit(fresh_simulations, count, stop).result(), dtype=float)
    slope = np.polyfit(np.arange(1, count), sizes[1:], 1)[0]
    print(f"\n## Contrast: {count} fresh Simulations (3 FMU instances each) in one process\n")
    print(f"RSS after 1: {sizes[0] / MIB:.1f} MiB, after {count}: {sizes[-1] / MIB:.1f} MiB, "
          f"slope {slope / 1024:+.1f} KiB per Simulation")


def burn(loops: int) -> float:
    """Seconds of pure-Python work."""
    start = time.perf_counter()
    total = 0
    for i in range(loops):
        total += i * i
    return time.perf_counter() - start


def parallel_capacity(loops: int = 10_000_000) -> float:
    """How many times the work of one process two processes get done in the same time
    (2.0 on two idle cores; less on a shared or loaded machine)."""
    with ProcessPoolExecutor(2, mp_context=get_context("spawn")) as pool:
        single = pool.submit(burn, loops).result()
        double = max(pool.map(burn, [loops, loops]))
    return 2 * single / double


def throughput(runs: int, stop: float) -> None:
    print(f"\n## Throughput: {runs} runs of plant_yang2020 ({stop:g} s), wall clock incl. "
          f"worker start-up\n")
    print(f"machine: load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} CPUs, "
          f"parallel capacity of 2 processes {parallel_capacity():.2f}x one\n")
    print("| workers | wall clock (s) | runs/min | mean run time (s) |")
    print("|---:|---:|---:|---:|")
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as folder:
            elapsed, records = campaign(Path(folder), runs, workers, stop)
        print(f"| {workers} | {elapsed:.1f} | {60 * runs / elapsed:.0f} | "
              f"{np.mean([r.elapsed for r in records]):.3f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=200, help="memory runs; 0: skip")
    parser.add_argument("--batch", type=int, default=20)
    parser.add_argument("--stop", type=float, default=60.0, help="simulated time per run, s")
    parser.add_argument("--contrast", type=int, default=0, metavar="N")
    parser.add_argument("--throughput-runs", type=int, default=60, help="0: skip")
    args = parser.parse_args()
    print(f"# altfusion Monte Carlo benchmark, {time.strftime('%Y-%m-%d')}, "
          f"{platform.node()}, {platform.processor() or platform.machine()}, "
          f"Python {platform.python_version()}")
    if args.runs:
        memory(args.runs, args.batch, args.stop)
    if args.contrast:
        contrast(args.contrast, args.stop)
    if args.throughput_runs:
        throughput(args.throughput_runs, args.stop)


if __name__ == "__main__":
    main()
