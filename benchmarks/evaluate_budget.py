"""``altfusion evaluate`` time budget (run by hand; results in benchmarks/RESULTS.md).

Runs a small evaluation (``--runs`` runs of every scenario, default 2) with the command
line's defaults and ``--workers`` local workers, then prints each scenario's mean run time
(the co-simulation's wall time, stored with every run), the process CPU time, and the
extrapolation to ``--target-runs`` runs (default 20):

    fixed = wall - (sum of run times) / workers        (start-up, SSPs, report)
    estimate = fixed + target_runs x (sum over scenarios of the mean run time) / workers

On a machine shared with other jobs the run times include their contention; the CPU time
(this process and its workers) is the work an idle machine would do, and gives the second,
idle-machine estimate.

    python benchmarks/evaluate_budget.py                # 2 runs, 2 workers
    python benchmarks/evaluate_budget.py --runs 1 --scenarios yang2020,baro_step
"""

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from altfusion.montecarlo.storage import finished_runs, read_run


def cpu_seconds() -> float:
    """CPU time of this process's finished children (the evaluation and its workers)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--target-runs", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scenarios", default=None)
    parser.add_argument("--backend", default="core")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="evaluate_budget_") as folder:
        out = Path(folder) / "evaluate"
        command = [sys.executable, "-m", "altfusion.cli", "evaluate", "--runs", str(args.runs),
                   "--workers", str(args.workers), "--backend", args.backend, "--quiet",
                   "--out", str(out)]
        if args.scenarios:
            command += ["--scenarios", args.scenarios]
        start, cpu = time.monotonic(), cpu_seconds()
        completed = subprocess.run(command, capture_output=True, text=True)
        wall, cpu = time.monotonic() - start, cpu_seconds() - cpu
        if completed.returncode != 0:
            print(completed.stdout[-2000:], completed.stderr[-3000:], file=sys.stderr)
            return 1
        print(f"load average before: {os.getloadavg()[0]:.1f}; {args.runs} run(s) per "
              f"scenario, {args.workers} workers, backend {args.backend}\n")
        print(f"{'scenario':26}{'mean run [s]':>14}")
        total = 0.0
        for scenario in sorted(p.parent for p in out.glob("*/*/runs")):
            times = [read_run(scenario, i).elapsed for i in finished_runs(scenario)]
            total += float(np.mean(times))
            print(f"{scenario.name:26}{np.mean(times):14.1f}")
    work = total * args.runs
    fixed = wall - work / args.workers
    print(f"\nsum of mean run times: {total:.1f} s per run of every scenario")
    print(f"wall {wall:.0f} s, CPU {cpu:.0f} s (runs {work:.0f} s, fixed {fixed:.0f} s)")
    estimate = fixed + args.target_runs * total / args.workers
    idle = fixed + args.target_runs * (cpu / args.runs) / args.workers
    print(f"--runs {args.target_runs} on {args.workers} workers: {estimate / 60:.1f} min at "
          f"this load; {idle / 60:.1f} min from the CPU time (an idle machine)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
