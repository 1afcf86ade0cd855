"""Monte Carlo throughput on a Dask cluster started as a user starts one, against local
worker processes: runs per minute with 1 and 2 workers. Run by hand (never as a test):

    python benchmarks/dask_scaling.py [--ssp models/yang2020.ssp] [--runs 6] [--stop T]

For each worker count W it starts ``dask scheduler --host 127.0.0.1 --port 0`` and W ``dask
worker --nthreads 1`` processes (``system_tests/dask_cluster.py``), warms every worker with a
campaign of W one-second runs (imports, FMU instantiation: a worker keeps its simulation),
then times ``altfusion mc SSP -n RUNS --scheduler ...``; and the same campaign with
``--workers W`` local processes (their start-up included, as a user sees it). It prints the
wall time, the runs per minute, the size of a stored run and the workers' resident memory.
"""

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "system_tests"))

from dask_cluster import dask_cluster  # noqa: E402

from altfusion.montecarlo.storage import finished_runs, read_run, run_path  # noqa: E402


def campaign(ssp: Path, runs: int, stop: float | None, out: Path, *where: str) -> float:
    """Wall seconds of ``altfusion mc`` (checked to finish every run)."""
    command = [sys.executable, "-m", "altfusion.cli", "mc", str(ssp), "-n", str(runs),
               "--out", str(out), "--quiet", *where, *(["--stop", str(stop)] if stop else [])]
    start = time.perf_counter()
    completed = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - start
    if completed.returncode:
        raise SystemExit(f"{' '.join(command)} failed:\n{completed.stderr}")
    assert finished_runs(out) == list(range(runs))
    return wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--ssp", type=Path, default=ROOT / "models" / "yang2020.ssp")
    parser.add_argument("--runs", type=int, default=6)
    parser.add_argument("--stop", type=float, default=None, help="simulated time, s")
    parser.add_argument("--workers", default="1,2")
    args = parser.parse_args()
    print(f"{args.ssp.name}, {args.runs} runs, stop {args.stop or 'the system default'}")
    print("backend            workers  wall s  runs/min  run file  worker RSS")
    with tempfile.TemporaryDirectory(prefix="dask-scaling-") as tmp:
        folder = Path(tmp)
        for workers in (int(w) for w in args.workers.split(",")):
            cluster_folder = folder / f"cluster{workers}"
            cluster_folder.mkdir()
            with dask_cluster(cluster_folder, workers) as address:
                campaign(args.ssp, workers, 1.0, folder / f"warm{workers}", "--scheduler",
                         address)
                report("Dask cluster", workers, args.runs, folder / f"dask{workers}", campaign(
                    args.ssp, args.runs, args.stop, folder / f"dask{workers}", "--scheduler",
                    address))
            local = folder / f"local{workers}"
            report("local processes", workers, args.runs, local, campaign(
                args.ssp, args.runs, args.stop, local, "--workers", str(workers)))


def report(backend: str, workers: int, runs: int, out: Path, wall: float) -> None:
    """One line of the table: wall time, runs per minute, run file size, worker memory."""
    size = run_path(out, 0).stat().st_size
    rss = max(read_run(out, index).worker_rss or 0 for index in range(runs))
    print(f"{backend:<18} {workers:>7} {wall:7.1f} {runs / wall * 60:9.1f} "
          f"{size / 1024:7.0f} kB {rss / 2**20:8.0f} MiB", flush=True)

if __name__ == "__main__":
    main()
