"""Memory of one long co-simulation: peak RSS and RSS growth over a 24 h simulated run
recorded every 1 s. Run by hand (about 10 minutes on 2 cores):

    python benchmarks/memory_long_run.py [SYSTEM] [--hours 24] [--interval 1.0]

A background thread samples the resident set size (/proc/self/statm) every few wall seconds
while the run goes on. It prints the RSS before the run (FMUs loaded, initialized), at each
simulated-hour mark it can attribute, at the end and the peak, and the size of the recorded
results (time + signals, 8 bytes each), which is growth the run must have.
"""

import argparse
import os
import resource
import threading
import time
from dataclasses import replace
from pathlib import Path

from altfusion.cosim import Simulation
from altfusion.systems import DEFAULT_SYSTEM, build_system

MODELS = Path(__file__).resolve().parents[1] / "models"
PAGE = os.sysconf("SC_PAGE_SIZE")


def rss_mib() -> float:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * PAGE / 2**20


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("system", nargs="?", default=DEFAULT_SYSTEM)
    parser.add_argument("--hours", type=float, default=24.0)
    parser.add_argument("--interval", type=float, default=1.0, help="recording interval, s")
    parser.add_argument("--sample", type=float, default=5.0, help="RSS sampling period, wall s")
    args = parser.parse_args()
    fmus = {p.stem: p for p in MODELS.glob("*.fmu")}
    stop = args.hours * 3600.0
    system = replace(build_system(args.system), stop_time=stop, output_interval=args.interval)
    samples: list[tuple[float, float]] = []
    done = threading.Event()

    def sampler() -> None:
        start = time.perf_counter()
        while not done.wait(args.sample):
            samples.append((time.perf_counter() - start, rss_mib()))

    with Simulation(system, fmus) as simulation:
        simulation.run(stop_time=10.0)  # warm-up: the steady working set
        before = rss_mib()
        thread = threading.Thread(target=sampler, daemon=True)
        thread.start()
        start = time.perf_counter()
        results = simulation.run()
        wall = time.perf_counter() - start
        done.set()
        thread.join()
        after = rss_mib()
    recorded = (len(results.columns) + 1) * len(results.time) * 8 / 2**20
    peak = max([resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, after]
               + [rss for _, rss in samples])
    print(f"{args.system}: {stop:g} s simulated in {wall:.0f} s wall "
          f"(real-time factor {stop / wall:.0f}), {len(results.time)} rows x "
          f"{len(results.columns)} signals recorded every {args.interval:g} s")
    print(f"  RSS before the run        : {before:8.1f} MiB")
    for seconds, rss in samples[:: max(1, len(samples) // 12)]:
        print(f"  RSS after {seconds:6.0f} s wall   : {rss:8.1f} MiB "
              f"(~{seconds / wall * stop / 3600:5.1f} h simulated)")
    print(f"  RSS after the run         : {after:8.1f} MiB")
    print(f"  growth over the run       : {after - before:8.1f} MiB, of which recorded "
          f"results {recorded:.1f} MiB")
    print(f"  peak RSS                  : {peak:8.1f} MiB")


if __name__ == "__main__":
    main()
