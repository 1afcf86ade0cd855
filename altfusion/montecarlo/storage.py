"""A campaign on disk: ``manifest.json`` and one file per finished run under ``runs/``.

Every file is written under a temporary name in the same folder and renamed into place
(``os.replace`` is atomic), so an interrupted campaign holds complete runs only; a leftover
temporary file is ignored and overwritten. A run that failed leaves ``run_NNNNN.failed.txt``
with the error instead; it is retried by ``--resume``.
"""

import json
import os
import re
import socket
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np

from altfusion.cosim.results import Results

MANIFEST = "manifest.json"
RUNS = "runs"
_RUN_FILE = re.compile(r"run_(\d+)\.npz")
_FAILED_FILE = re.compile(r"run_(\d+)\.failed\.txt")


@dataclass
class RunRecord:
    """One finished run: its seeds, its recorded results and where and how long it ran."""

    index: int
    seeds: dict[str, int]
    results: Results
    elapsed: float
    """Wall-clock time of the co-simulation, s."""
    worker: str = ""
    """'pid@host' of the process that ran it."""
    worker_rss: int | None = None
    """Resident memory of that process after the run, bytes (None where unknown)."""


def worker_name() -> str:
    return f"{os.getpid()}@{socket.gethostname()}"


def resident_memory() -> int | None:
    """This process's resident set size in bytes, from /proc/self/statm (Linux), else None."""
    try:
        with open("/proc/self/statm") as handle:
            pages = int(handle.read().split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return pages * os.sysconf("SC_PAGE_SIZE")


def atomic_write(path: Path, write: Callable[[IO[bytes]], None]) -> Path:
    """Write ``path`` through ``write(handle)`` to a temporary file, then rename it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.",
                                             suffix=".tmp")
    try:
        with os.fdopen(descriptor, "wb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(temporary, 0o644)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return path


def run_path(out: Path, index: int) -> Path:
    return Path(out) / RUNS / f"run_{index:05d}.npz"


def failure_path(out: Path, index: int) -> Path:
    return Path(out) / RUNS / f"run_{index:05d}.failed.txt"


def write_run(out: Path, record: RunRecord) -> Path:
    """Store a finished run (and clear a failure left by an earlier attempt)."""
    names = list(record.results.columns)
    meta = {"index": record.index, "seeds": record.seeds, "elapsed": record.elapsed,
            "worker": record.worker, "worker_rss": record.worker_rss}
    arrays = {
        "time": record.results.time,
        "values": np.column_stack([record.results.columns[n] for n in names]),
        "names": np.array(names, dtype=str),
        "units": np.array([record.results.units.get(n, "") for n in names], dtype=str),
        "meta": np.array(json.dumps(meta)),
    }
    path = atomic_write(run_path(out, record.index), lambda handle: np.savez(handle, **arrays))
    failure_path(out, record.index).unlink(missing_ok=True)
    return path


def read_run(out: Path, index: int) -> RunRecord:
    """Load run ``index`` of the campaign in ``out``."""
    with np.load(run_path(out, index), allow_pickle=False) as data:
        meta = json.loads(str(data["meta"]))
        names = [str(n) for n in data["names"]]
        values = data["values"]
        results = Results(data["time"], {n: values[:, i] for i, n in enumerate(names)},
                          dict(zip(names, (str(u) for u in data["units"]), strict=True)))
    return RunRecord(meta["index"], meta["seeds"], results, meta["elapsed"], meta["worker"],
                     meta["worker_rss"])


def write_failure(out: Path, index: int, message: str) -> Path:
    return atomic_write(failure_path(out, index), lambda handle: handle.write(message.encode()))


def _indices(out: Path, pattern: re.Pattern) -> list[int]:
    folder = Path(out) / RUNS
    if not folder.is_dir():
        return []
    found = (pattern.fullmatch(path.name) for path in folder.iterdir())
    return sorted(int(match.group(1)) for match in found if match)


def finished_runs(out: Path) -> list[int]:
    """Indices of the stored runs, ascending."""
    return _indices(out, _RUN_FILE)


def failed_runs(out: Path) -> dict[int, str]:
    """Run index -> error message of the runs whose last attempt failed."""
    return {index: failure_path(out, index).read_text()
            for index in _indices(out, _FAILED_FILE)}


def write_manifest(out: Path, manifest: dict[str, Any]) -> Path:
    text = json.dumps(manifest, indent=2, sort_keys=True) + "\n"
    return atomic_write(Path(out) / MANIFEST, lambda handle: handle.write(text.encode()))


def read_manifest(out: Path) -> dict[str, Any]:
    return json.loads((Path(out) / MANIFEST).read_text())


def has_manifest(out: Path) -> bool:
    return (Path(out) / MANIFEST).is_file()
