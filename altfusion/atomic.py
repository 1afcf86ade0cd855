"""Atomic result files: every file is written under a temporary name in its own folder and
renamed into place (``os.replace`` is atomic), so a failed or interrupted write (full disk,
kill) leaves either the previous file or none under the final name, never a truncated one."""

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from altfusion.errors import UsageError


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


def write_text(path: Path, text: str) -> Path:
    """:func:`atomic_write` of a UTF-8 text."""
    return atomic_write(path, lambda handle: handle.write(text.encode()))


def save_figure(fig: Any, path: Path, **options: Any) -> Path:
    """``fig.savefig`` through :func:`atomic_write`, the format taken from the suffix."""
    path = Path(path)
    return atomic_write(path, lambda handle: fig.savefig(handle, format=path.suffix[1:],
                                                         **options))


def output_folder(out: str | Path, option: str = "--out") -> Path:
    """The output folder ``out``, checked before any work (a run's results are not lost to a
    folder that cannot take them) without creating it (a refused command leaves nothing
    behind; the first result written creates it), or a UsageError naming it as the
    command-line ``option``. The check creates and removes a folder where ``out`` would
    start (permission bits do not tell, e.g. for root or on a read-only file system)."""
    folder = Path(out)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{option} {out}: a file, not a folder")
    existing = folder.absolute()
    while not existing.exists():
        existing = existing.parent
    if not existing.is_dir():
        raise UsageError(f"{option} {out}: cannot create the folder ({existing} is a file)")
    try:
        os.rmdir(tempfile.mkdtemp(dir=existing, prefix=".altfusion-check-"))
    except OSError as error:
        what = "folder not writable" if existing == folder.absolute() else \
            f"cannot create the folder ({existing}: {error.strerror})"
        raise UsageError(f"{option} {out}: {what}") from None
    return folder
