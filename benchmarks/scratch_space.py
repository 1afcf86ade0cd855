"""Temporary-folder space and worker memory of ``altfusion evaluate`` over its campaigns (run
by hand; results in benchmarks/RESULTS.md).

Runs ``altfusion evaluate`` with a temporary folder of its own (``TMPDIR``) and samples that
folder's size every ``--interval`` s while the evaluation runs: its peak, its size after
each campaign (each campaign is one scenario in one ``--told`` mode) and what is left at the
end. The workers' resident memory is read from the runs (every run records its worker's).
``--root`` runs another checkout's ``altfusion`` on that checkout's FMUs (e.g. a worktree of
an older commit, built there with ``python build_fmu.py``), to compare versions:

    python benchmarks/scratch_space.py                      # 6 scenarios x 2 modes, 2 runs
    python benchmarks/scratch_space.py --root /tmp/before --told nothing,noise,models
"""

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MIB = 1 << 20
SCENARIOS = "hajiyev,bao2017,nominal_flight,baro_step,gnss_step,yang2020"


def folder_size(folder: Path) -> int:
    """Bytes of the files under ``folder`` (files vanishing meanwhile are skipped)."""
    total = 0
    for path, _, files in os.walk(folder):
        for name in files:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(path, name)).st_size
    return total


def worker_memory(out: Path) -> list[tuple[float, str, int]]:
    """(finish time, worker, resident bytes) of every run stored under ``out``."""
    found = []
    for path in out.glob("*/*/runs/*.npz"):
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
        if meta.get("worker_rss"):
            found.append((path.stat().st_mtime, meta["worker"], meta["worker_rss"]))
    return sorted(found)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", type=Path, default=ROOT, help="checkout to run")
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--scenarios", default=SCENARIOS)
    parser.add_argument("--told", default="nothing,noise")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--stop", type=float, help="cap every scenario's stop time, s")
    parser.add_argument("--interval", type=float, default=0.2)
    args = parser.parse_args()
    root = args.root.resolve()
    with tempfile.TemporaryDirectory() as work:
        scratch, out = Path(work) / "tmp", Path(work) / "out"
        scratch.mkdir()
        command = [sys.executable, "-c", "import sys; import altfusion; "
                   "print(altfusion.__file__, file=sys.stderr); from altfusion.cli import main;"
                   " sys.argv[0] = 'altfusion'; sys.exit(main())",
                   "evaluate", "--runs", str(args.runs), "--scenarios", args.scenarios,
                   "--told", args.told, "--workers", str(args.workers), "--quiet",
                   "--models", str(root / "models"), "--out", str(out),
                   *(["--stop", str(args.stop)] if args.stop else [])]
        env = {**os.environ, "TMPDIR": str(scratch), "PYTHONPATH": str(root)}
        start = time.perf_counter()
        process = subprocess.Popen(command, env=env, cwd=work, stderr=subprocess.PIPE,
                                   text=True, stdout=subprocess.DEVNULL)
        peak, samples = 0, []
        while process.poll() is None:
            size = folder_size(scratch)
            peak = max(peak, size)
            samples.append((time.perf_counter() - start, size))
            time.sleep(args.interval)
        stderr = process.stderr.read()
        wall = time.perf_counter() - start
        left = folder_size(scratch)
        memory = worker_memory(out)
    imported = stderr.splitlines()[0] if stderr else "?"
    if process.returncode != 0 or not imported.startswith(str(root)):
        sys.exit(f"evaluate failed (exit {process.returncode}, altfusion {imported}):\n{stderr}")
    campaigns = len(args.scenarios.split(",")) * sum(
        2 if mode == "misstated" else 1 for mode in args.told.split(","))
    print(f"altfusion from {imported}")
    print(f"{campaigns} campaigns ({args.scenarios} x {args.told}), {args.runs} runs each, "
          f"{args.workers} workers, {wall:.0f} s")
    print(f"temporary folder: peak {peak / MIB:.1f} MiB ({peak / MIB / campaigns:.1f} MiB per "
          f"campaign), left after the command {left / MIB:.1f} MiB")
    growth = ", ".join(f"{max((s for t, s in samples if t <= wall * q), default=0) / MIB:.0f}"
                       for q in (0.25, 0.5, 0.75, 1.0))
    print(f"  its peak after a quarter, half, three quarters and all of the time: {growth} MiB")
    by_worker: dict[str, list[int]] = {}
    for _, worker, rss in memory:
        by_worker.setdefault(worker, []).append(rss)
    for worker, values in sorted(by_worker.items()):
        print(f"worker {worker}: resident memory {values[0] / MIB:.1f} MiB at its first run, "
              f"{values[-1] / MIB:.1f} MiB at its last ({len(values)} runs)")


if __name__ == "__main__":
    main()
