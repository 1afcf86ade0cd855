"""Temporary folders that do not outlive this process.

FMUs are extracted to disk to be loaded, and an SSP's FMUs are unpacked before that. A folder
left behind per run fills a user's ``/tmp`` (each run of a system left eight extracted FMUs,
about 1 MiB each). :mod:`tempfile`'s own clean-up runs from :mod:`atexit` and from the garbage
collector, and neither runs in a worker process of :mod:`multiprocessing` or
:mod:`concurrent.futures`: those leave by ``os._exit`` once their target returns. They do run
:mod:`multiprocessing`'s exit finalizers first, and so does the main process (at
:mod:`atexit`, after the handlers registered later, such as the release of pythonfmu's state,
which reads the libraries' paths): the folders here are removed by those. A process that
leaves without them (a campaign's worker stopped by SIGTERM or ending itself when its parent
died: ``altfusion.montecarlo.worker``) calls :func:`remove_scratch_folders` first; only a
SIGKILL leaves its folders behind.
"""

import os
import shutil
import tempfile
from multiprocessing.util import Finalize
from pathlib import Path

_LIVE: dict[Path, int] = {}
"""Scratch folders not yet removed -> the process that made them (a forked child inherits
its parent's entries, and must not remove the parent's folders)."""


class ScratchFolder:
    """A new empty folder (:attr:`path`), removed when this object is garbage-collected or,
    at the latest, when this process exits (worker processes included)."""

    def __init__(self, prefix: str):
        self.path = Path(tempfile.mkdtemp(prefix=prefix))
        _LIVE[self.path] = os.getpid()
        Finalize(self, _remove, args=(self.path,), exitpriority=0)


def _remove(path: Path) -> None:
    _LIVE.pop(path, None)
    shutil.rmtree(path, ignore_errors=True)


def remove_scratch_folders() -> None:
    """Remove every scratch folder this process made, now: for a process about to leave by
    ``os._exit`` or on a signal, which runs no finalizer."""
    me = os.getpid()
    for path, owner in list(_LIVE.items()):
        if owner == me:
            _remove(path)
