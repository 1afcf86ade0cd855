"""Temporary folders that do not outlive this process.

FMUs are extracted to disk to be loaded, and an SSP's FMUs are unpacked before that. A folder
left behind per run fills a user's ``/tmp`` (each run of a system left eight extracted FMUs,
about 1 MiB each). :mod:`tempfile`'s own clean-up runs from :mod:`atexit` and from the garbage
collector, and neither runs in a worker process of :mod:`multiprocessing` or
:mod:`concurrent.futures`: those leave by ``os._exit`` once their target returns. They do run
:mod:`multiprocessing`'s exit finalizers first, and so does the main process (at
:mod:`atexit`, after the handlers registered later, such as the release of pythonfmu's state,
which reads the libraries' paths): the folders here are removed by those.
"""

import shutil
import tempfile
from multiprocessing.util import Finalize
from pathlib import Path


class ScratchFolder:
    """A new empty folder (:attr:`path`), removed when this object is garbage-collected or,
    at the latest, when this process exits (worker processes included)."""

    def __init__(self, prefix: str):
        self.path = Path(tempfile.mkdtemp(prefix=prefix))
        Finalize(self, shutil.rmtree, args=(self.path,), kwargs={"ignore_errors": True},
                 exitpriority=0)
