"""FMU archives extracted to disk, once per process and per content.

An FMU is loaded from a folder it was unpacked to (its libraries stay mapped from there while
the process lives). The same FMU reaches a process under many paths: every campaign of
``altfusion evaluate`` unpacks its own SSP archive, holding the same FMUs as every other
campaign's, and a kept worker runs campaign after campaign. Keyed by path, each campaign
extracted every FMU anew into each worker and loaded its libraries again (with each
campaign's unpacked archive, kept too: 45.8 MiB of the temporary folder per campaign on two
workers; 4.8 GiB, gone only when the workers ended, after the 105 campaigns of ``altfusion
evaluate --told noise,models,nothing,misstated``: ``benchmarks/scratch_space.py``). Keyed by
the archive's SHA-256, an FMU is extracted once per process whatever the path, and a
rebuilt FMU at a path already seen is extracted anew instead of being served stale.
"""

import hashlib
import os
from pathlib import Path

from fmpy import extract

from altfusion.cosim.scratch import ScratchFolder

_EXTRACTED: dict[str, str] = {}
"""SHA-256 of an FMU archive -> the folder this process extracted it to."""
_EXTRACTED_BY: int | None = None
_FMU_FOLDER: ScratchFolder | None = None


def file_sha256(path: Path) -> str:
    """The SHA-256 of the file at ``path``, hexadecimal."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def extracted_folder(path: Path) -> str:
    """The folder the FMU archive at ``path`` is extracted to: the one this process already
    extracted an archive of the same bytes to, or a new one in a folder of this process's
    that is removed when it exits (:mod:`altfusion.cosim.scratch`). A forked child keeps using
    what its parent extracted (its libraries are mapped from there) and extracts what is new
    into a folder of its own."""
    global _EXTRACTED_BY, _FMU_FOLDER
    content = file_sha256(path)
    folder = _EXTRACTED.get(content)
    if folder is None:
        if os.getpid() != _EXTRACTED_BY:
            _EXTRACTED_BY, _FMU_FOLDER = os.getpid(), ScratchFolder("altfusion_fmus_")
        target = _FMU_FOLDER.path / f"{len(_EXTRACTED)}_{Path(path).stem}"
        folder = _EXTRACTED[content] = str(extract(str(path), unzipdir=target))
    return folder
