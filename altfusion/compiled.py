"""The core's hot modules compiled to C by mypyc, used only while they match their sources.

:data:`COMPILED` names the modules ``build_fmu.py`` compiles (:mod:`altfusion.compile_core`)
into a folder ``_compiled`` of their package, for the interpreter that runs the build: the
in-process core's own copy and every FMU's private copy of the core get theirs. A package
whose modules may run compiled puts that folder first on its ``__path__``
(:func:`compiled_path`), so ``import altfusion.estimators.kalman`` loads the extension module
there instead of ``kalman.py``. The Python sources stay the one statement of the algorithm: the
extension is generated from them, computes the same IEEE 754 operations in the same order
(compiled with ``-ffp-contract=off``: no fused multiply-adds) and so gives the same bits
(tests/test_compiled_core.py compares every estimator's checksums both ways).

The folder's ``manifest.json`` records the interpreter (``sys.implementation.cache_tag``) and
the SHA-256 of each compiled source. The folder is used only if both match: another Python
(an FMU in a host running 3.12) or a source edited since the build runs the sources, the
latter with a warning naming the module and the command that compiles it again. Setting the
environment variable :data:`PURE_PYTHON` (to anything but empty or ``0``) runs the sources
always.
"""

import hashlib
import json
import os
import sys
import warnings
from pathlib import Path

COMPILED = {"estimators": ("kalman", "restorable", "aid_source", "fault_detection", "stuck",
                            "noise_check", "prediction_judges", "accelerometer_check",
                            "process_noise", "range_aid", "ground_range",
                            "reference_handover", "arrivals", "gate", "floats",
                            "window_sum")}
"""Package (relative to the core) -> its modules compiled by mypyc: the Kalman steps every
estimator runs and the machinery its members are made of (one aid source per sensor stream,
the samples arriving on each stream, the fault layer's tests and checks), typed. Their
classes, native classes once compiled, derive from
:class:`~altfusion.estimators.restorable.Restorable` (the FMU state codec makes them blank).
The estimators' own classes are not compiled: they are mixins
(:class:`~altfusion.estimators.intake.SampleIntake`, ...), which mypyc's native classes
cannot be; their work at every step is done by members of the compiled modules (an
estimator passes itself to :class:`~altfusion.estimators.arrivals.Arrivals`, which calls it
back only for what a sample does to it beyond the intake)."""
FOLDER = "_compiled"
"""The folder of a package's compiled modules."""
MANIFEST = "manifest.json"
"""The folder's record of the interpreter and the sources it was compiled for."""
PURE_PYTHON = "ALTFUSION_PURE_PYTHON"
"""Environment variable: set, the compiled modules are not used."""


def source_sha256(path: Path) -> str:
    """The SHA-256 of a source file's bytes, hex."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def manifest_for(package_dir: Path, modules: tuple[str, ...]) -> dict:
    """The manifest that compiled ``modules`` of the package at ``package_dir`` must carry
    to be used in this interpreter."""
    return {"cache_tag": sys.implementation.cache_tag,
            "sources": {f"{m}.py": source_sha256(package_dir / f"{m}.py") for m in modules}}


def stale_sources(package_dir: Path) -> list[str] | None:
    """The sources of the package at ``package_dir`` edited since they were compiled for this
    interpreter, or listed in :data:`COMPILED` since and not compiled ([] when all match);
    None when nothing was compiled for it."""
    try:
        manifest = json.loads((package_dir / FOLDER / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(manifest, dict) or manifest.get("cache_tag") != \
            sys.implementation.cache_tag or not isinstance(manifest.get("sources"), dict):
        return None
    digests = manifest["sources"]
    listed = {f"{module}.py" for module in COMPILED.get(package_dir.name, ())}
    return sorted(name for name in listed | digests.keys()
                  if not (package_dir / name).is_file() or name not in digests
                  or source_sha256(package_dir / name) != digests[name])


def compiled_path(package_dir: str) -> list[str]:
    """The folders to put first on the ``__path__`` of the package at ``package_dir``: its
    compiled modules' folder when they were compiled for this interpreter from the sources
    as they are and :data:`PURE_PYTHON` is not set; none otherwise."""
    if os.environ.get(PURE_PYTHON, "") not in ("", "0"):
        return []
    folder = Path(package_dir)
    stale = stale_sources(folder)
    if stale:
        warnings.warn(f"{', '.join(stale)} in {folder} changed since compiled: running the "
                      "Python sources (python build_fmu.py compiles them again)", stacklevel=2)
    return [str(folder / FOLDER)] if stale == [] else []


def is_compiled(module: object) -> bool:
    """True if ``module`` was loaded from a compiled extension."""
    return str(getattr(module, "__file__", "")).endswith((".so", ".pyd"))
