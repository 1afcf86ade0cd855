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
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from altfusion.atomic import atomic_write, write_text
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


class DamagedRunError(ValueError):
    """A stored run file that cannot be read back whole (truncated, corrupted, keys missing)."""


def load_run(out: Path, index: int) -> RunRecord:
    """:func:`read_run`, checked: every array read (the zip's CRC checked) and consistent;
    a DamagedRunError says what is wrong."""
    path = run_path(out, index)
    try:
        record = read_run(out, index)
    except KeyError as error:
        raise DamagedRunError(f"{path.name}: missing {error.args[0]}") from error
    except (OSError, ValueError, EOFError, IndexError, TypeError,
            zipfile.BadZipFile) as error:
        raise DamagedRunError(f"{path.name}: {type(error).__name__}: {error}") from error
    time = record.results.time
    if time.ndim != 1 or not record.results.columns:
        raise DamagedRunError(f"{path.name}: time of shape {time.shape} and "
                              f"{len(record.results.columns)} columns; expected a series and "
                              f"at least one column")
    rows = {values.shape for values in record.results.columns.values()}
    if record.index != index or rows - {time.shape}:
        raise DamagedRunError(f"{path.name}: inconsistent content (index {record.index}, "
                              f"column shapes {sorted(rows)} vs time {time.shape})")
    dtypes = {str(a.dtype) for a in (time, *record.results.columns.values())
              if a.dtype.kind != "f"}
    if dtypes:
        raise DamagedRunError(f"{path.name}: values of dtype {', '.join(sorted(dtypes))}; "
                              f"a run records floating-point numbers")
    return record


def damaged_runs(out: Path) -> dict[int, str]:
    """Stored run index -> what is wrong with its file, for the runs that fail :func:`load_run`
    (each file is read whole: about 1 ms per run of 10^4 rows)."""
    damaged = {}
    for index in finished_runs(out):
        try:
            load_run(out, index)
        except DamagedRunError as error:
            damaged[index] = str(error)
    return damaged


def write_failure(out: Path, index: int, message: str) -> Path:
    return write_text(failure_path(out, index), message)


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
    return write_text(Path(out) / MANIFEST, text)


MANIFEST_FIELDS = {"format": int, "system": dict, "ssp": str, "ssp_sha256": str, "runs": int,
                   "master_seed": int, "parameters": dict, "seeded_components": list,
                   "recorded": list, "metrics": list, "versions": dict, "created": str,
                   "sessions": list}
"""The fields of a campaign's manifest that are read back, and their JSON types."""


class DamagedManifestError(ValueError):
    """A ``manifest.json`` that is not a campaign's manifest (missing, unreadable, not JSON, a
    field missing or of another type)."""


def read_manifest(out: Path) -> dict[str, Any]:
    """The campaign manifest in ``out``, checked to be one: a JSON object with every field of
    :data:`MANIFEST_FIELDS` of its type (bytes from outside: a damaged or foreign file is
    refused naming it, not read into a KeyError halfway through a command)."""
    path = Path(out) / MANIFEST
    try:
        manifest = json.loads(path.read_bytes())
    except FileNotFoundError:
        raise DamagedManifestError(f"{out}: not a campaign folder (no {MANIFEST}: altfusion mc "
                                   f"or compare writes one)") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise DamagedManifestError(f"{path}: not a campaign manifest ({error})") from None
    if not isinstance(manifest, dict):
        raise DamagedManifestError(f"{path}: not a campaign manifest (a JSON "
                                   f"{type(manifest).__name__}, not an object)")
    wrong = [f"{key} ({'missing' if key not in manifest else 'not ' + kind.__name__})"
             for key, kind in MANIFEST_FIELDS.items()
             if not isinstance(manifest.get(key), kind) or isinstance(manifest[key], bool)]
    if wrong:
        raise DamagedManifestError(f"{path}: not a campaign manifest: {', '.join(wrong)}")
    return manifest


def has_manifest(out: Path) -> bool:
    return (Path(out) / MANIFEST).is_file()
