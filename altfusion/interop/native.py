"""Native libraries the engines need from the Python environment, not from the system.

libcosimc and ECOS link ``libtbb.so.12`` (oneTBB). The ``interop`` extra installs it from the
``tbb`` wheel into ``<environment>/lib``, which the dynamic loader does not search: it is loaded
here with ``RTLD_GLOBAL`` before libcosimpy or ecospy is imported, and the folder is put on
``LD_LIBRARY_PATH`` for the engines' own executables (``ecos``, ``proxyfmu``). A system-wide
libtbb12 (Debian's package) works as well; without either, importing the engines fails with
the loader's message.
"""

import ctypes
import sys
from pathlib import Path

TBB = "libtbb.so.12"


def environment_lib() -> Path:
    """The environment's own library folder, where wheels such as ``tbb`` put shared objects."""
    return Path(sys.prefix) / "lib"


def preload_engine_libraries() -> bool:
    """Load the environment's libtbb globally if it has one; True if it did (idempotent)."""
    library = environment_lib() / TBB
    if not sys.platform.startswith("linux") or not library.is_file():
        return False
    ctypes.CDLL(str(library), mode=ctypes.RTLD_GLOBAL)
    return True
