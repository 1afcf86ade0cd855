"""The environment a host without Python of its own runs our FMUs in (README's C-host
recipe): the interpreter's shared library preloaded, ``PYTHONHOME`` naming this interpreter's
installation and ``PYTHONPATH`` its site-packages (numpy)."""

import os
import site
import sys
import sysconfig
from pathlib import Path


def libpython() -> Path:
    """The interpreter's shared library, as README's recipe names it."""
    return Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("LDLIBRARY")


def has_shared_libpython() -> bool:
    """Whether this Python has a shared libpython a C host can preload."""
    return bool(sysconfig.get_config_var("Py_ENABLE_SHARED"))


def preload_environment() -> dict[str, str]:
    """This process's environment with README's ``LD_PRELOAD``, ``PYTHONHOME`` and
    ``PYTHONPATH``."""
    return {**os.environ, "LD_PRELOAD": str(libpython()), "PYTHONHOME": sys.base_prefix,
            "PYTHONPATH": os.pathsep.join(site.getsitepackages())}
