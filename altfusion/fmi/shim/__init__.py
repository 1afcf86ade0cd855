"""The native FMI 2.0 shim every FMU's linux64 binary is (source: ``fmi2_shim.c``).

pythonfmu 0.7.0's library segfaults on the resource URIs ``file:/p`` and
``file://localhost/p``, aborts a C host at exit unless it calls the non-standard
``finalizePythonInterpreter`` (which finalizes the interpreter pythonfmu started, so a host
freeing its instances later crashes), forwards no message while ``loggingOn`` is off and
returns fmi2OK for failures the Python side can only log. Our shim, compiled here with the system C
compiler, becomes ``binaries/linux64/<model identifier>.so``; pythonfmu's library moves beside
it as :data:`PYTHONFMU_LIBRARY`, which the shim loads (``dlopen``) and forwards FMI calls
to; while an instance steps, the shim reads and sets its inputs and outputs and calls its
``do_step`` itself, past pythonfmu's bridge. The win64 binary stays pythonfmu's own. Design:
DEVELOPERS.md, "The native shim".
"""

import os
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

SOURCE = Path(__file__).with_name("fmi2_shim.c")
PYTHONFMU_LIBRARY = "pythonfmu-export.so"
"""pythonfmu's linux64 library inside an FMU, beside the shim that loads it."""
BINARIES = "binaries/linux64/"


class ShimBuildError(RuntimeError):
    """The shim cannot be compiled or installed (the message says why)."""


def compile_shim(folder: Path) -> Path:
    """Compile the shim into ``folder`` with the system C compiler (``$CC``, default ``cc``);
    the shared library's path. No Python headers are needed: the few Python C-API functions
    the shim calls are declared in it and resolved from the host process when it is loaded
    (``-z now``: without a Python in the process, loading fails naming the symbol)."""
    compiler = os.environ.get("CC", "cc")
    if shutil.which(compiler) is None:
        raise ShimBuildError(
            f"building the FMUs needs a C compiler for their native shim ({SOURCE.name}), and "
            f"'{compiler}' is not on PATH: install one (Debian/Ubuntu: apt-get install gcc) or "
            "set CC")
    folder.mkdir(parents=True, exist_ok=True)
    library = folder / "fmi2_shim.so"
    command = [compiler, "-shared", "-fPIC", "-O2", "-Wall", "-Wextra", "-fvisibility=hidden",
               "-Wl,-z,now",
               f'-DPYTHONFMU_LIBRARY="{PYTHONFMU_LIBRARY}"', "-o", str(library), str(SOURCE),
               "-ldl", "-lpthread"]
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise ShimBuildError(f"compiling {SOURCE.name} failed ({' '.join(command)}):\n"
                             f"{done.stderr.strip()}")
    return library


def install_shim(fmu: Path, shim: Path) -> None:
    """Rewrite the archive ``fmu`` as built by pythonfmu: its ``binaries/linux64/<id>.so``
    moves to ``binaries/linux64/pythonfmu-export.so`` and the ``shim`` takes its name."""
    with zipfile.ZipFile(fmu) as archive:
        entries = archive.infolist()
        libraries = [e.filename for e in entries
                     if e.filename.startswith(BINARIES) and e.filename.endswith(".so")]
        if len(libraries) != 1 or libraries[0] == BINARIES + PYTHONFMU_LIBRARY:
            raise ShimBuildError(f"{fmu.name}: expected pythonfmu's one linux64 library, found "
                                 f"{libraries}")
        with tempfile.NamedTemporaryFile(dir=fmu.parent, suffix=".fmu", delete=False) as out:
            partial = Path(out.name)
        try:
            with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as rewritten:
                for entry in entries:
                    data = archive.read(entry)
                    if entry.filename == libraries[0]:
                        moved = zipfile.ZipInfo(BINARIES + PYTHONFMU_LIBRARY, entry.date_time)
                        moved.external_attr = entry.external_attr
                        rewritten.writestr(moved, data, zipfile.ZIP_DEFLATED)
                        data = shim.read_bytes()
                    rewritten.writestr(entry, data, zipfile.ZIP_DEFLATED)
        except BaseException:
            partial.unlink()
            raise
    os.replace(partial, fmu)
