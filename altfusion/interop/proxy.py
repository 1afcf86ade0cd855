"""Our FMUs in a host without Python: ECOS's command-line program and its ``proxyfmu``.

pythonfmu's library is not linked to libpython: it runs the model in the Python of the process
that loads it. A C++ host (``ecos simulate``, or ``proxyfmu``, the process ECOS starts per FMU
for ``proxyfmu://`` sources) has none, so libpython is preloaded (``LD_PRELOAD``) with
``PYTHONHOME`` and a ``PYTHONPATH`` that holds numpy (:func:`python_environment`). The
binaries are linux64 and win64 only and need glibc >= 2.32. ECOS's CSV has 6 decimals (``%f``).
"""

import csv
import os
import shutil
import site
import subprocess
import sys
import sysconfig
import tempfile
import zipfile
from pathlib import Path

from altfusion.cosim.results import Results
from altfusion.cosim.ssp import OSP_SSD
from altfusion.interop.engines import (
    SSP_PARAMETER_SET,
    EngineError,
    Recording,
    parameter_set_names,
    reject_bad_parameters,
)
from altfusion.interop.native import environment_lib
from altfusion.systems.spec import SystemSpec


def libpython() -> Path:
    """This interpreter's shared libpython, which a non-Python host must preload."""
    library = Path(sysconfig.get_config_var("LIBDIR") or "") / (
        sysconfig.get_config_var("INSTSONAME") or "")
    if not library.is_file():
        raise EngineError(f"{sys.executable} has no shared libpython ({library}): pythonfmu "
                          f"FMUs need a Python built with --enable-shared in non-Python hosts")
    return library


def python_environment() -> dict[str, str]:
    """What a non-Python host needs to run our FMUs: libpython preloaded, this Python's home
    and the site-packages that hold numpy; the environment's library folder (libtbb) on the
    loader's path."""
    paths = [*site.getsitepackages(), *os.environ.get("PYTHONPATH", "").split(os.pathsep)]
    libraries = [str(environment_lib()), *os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep)]
    return {
        "LD_PRELOAD": str(libpython()),
        "LD_LIBRARY_PATH": os.pathsep.join(p for p in libraries if p),
        "PYTHONHOME": sys.base_prefix,
        "PYTHONPATH": os.pathsep.join(p for p in paths if p),
    }


def ecos_binaries() -> Path:
    """ecospy's bundled ``ecos`` and ``proxyfmu`` executables, made executable if needed (the
    wheel may ship them without the executable bit)."""
    import ecospy

    folder = Path(ecospy.__file__).parent / "binaries"
    executables = [folder / "ecos", folder / "proxyfmu"]
    if all(os.access(p, os.X_OK) for p in executables):
        return folder
    try:
        for path in executables:
            path.chmod(path.stat().st_mode | 0o111)
        return folder
    except PermissionError:
        copy = Path(tempfile.mkdtemp(prefix="altfusion_ecos_"))
        for path in executables:
            shutil.copy2(path, copy / path.name)
            (copy / path.name).chmod(0o755)
        return copy


def proxy_ssp(ssp: Path, target: Path) -> Path:
    """A copy of ``ssp`` whose components ECOS loads through ``proxyfmu`` (one process each),
    stepping each at its own rate (the archive's OSP description as its
    ``SystemStructure.ssd``)."""
    with zipfile.ZipFile(ssp) as source, zipfile.ZipFile(target, "w",
                                                         zipfile.ZIP_DEFLATED) as copy:
        for item in source.infolist():
            if item.filename == "SystemStructure.ssd":
                continue
            data = source.read(item.filename)
            if item.filename == OSP_SSD:
                data = data.replace(b'source="resources/',
                                    b'source="proxyfmu://localhost?file=resources/')
                item.filename = "SystemStructure.ssd"
            copy.writestr(item, data)
    return target


def _ecos_csv_config(recording: Recording, path: Path) -> Path:
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ecos:CsvConfig xmlns:ecos="urn:ecos" decimationFactor="{recording.every}">',
             "  <ecos:components>"]
    by_component: dict[str, list[str]] = {}
    for signal in recording.signals:
        by_component.setdefault(signal.component, []).append(signal.variable)
    for component, variables in by_component.items():
        lines.append(f'    <ecos:component name="{component}">')
        lines += [f'      <ecos:variable name="{v}"/>' for v in variables]
        lines.append("    </ecos:component>")
    lines += ["  </ecos:components>", "</ecos:CsvConfig>"]
    path.write_text("\n".join(lines) + "\n")
    return path


ECOS_CSV_TYPES = {"Real": "REAL", "Integer": "INT", "Boolean": "BOOL"}


def run_ecos_proxy(ssp: Path, system: SystemSpec, fmu_paths: dict[str, Path],
                   stop_time: float | None = None, timeout: float = 600.0) -> Results:
    """Run ``ssp`` with ECOS's command-line host, each FMU in its own ``proxyfmu`` process.

    The host and the proxies are C++ programs: pythonfmu's library finds Python only because
    libpython is preloaded (:func:`python_environment`)."""
    recording = Recording.of(system, fmu_paths, stop_time)
    reject_bad_parameters(system, fmu_paths)
    binaries = ecos_binaries()
    # ECOS adds its steps up in floats: asked to stop at the last row's time, it can stop a
    # step short of it (yang2020 to 1 s: 10 rows of 11); half a step past, it writes that
    # row, and the rows past the recording's are dropped
    stop = recording.clock.time((recording.rows - 1) * recording.every) + 0.5 * system.base_step
    with tempfile.TemporaryDirectory(prefix="altfusion_ecos_proxy_") as work:
        work = Path(work)
        proxied = proxy_ssp(ssp, work / f"{system.name}.ssp")
        config = _ecos_csv_config(recording, work / "csv_config.xml")
        command = [str(binaries / "ecos"), "simulate", "--path", str(proxied),
                   "--stepSize", repr(system.base_step), "--stopTime", repr(stop),
                   "--csvConfig", str(config), "--noParallel", "--logLevel", "warn"]
        if SSP_PARAMETER_SET in parameter_set_names(ssp):
            command += ["--parameterSet", SSP_PARAMETER_SET]
        # TMPDIR: ECOS unpacks the archive and each proxyfmu its FMU and socket there, and
        # leaves them (1.3 MB a run): in the work folder they go with it
        completed = subprocess.run(command, cwd=work,
                                   env={**os.environ, **python_environment(), "TMPDIR": str(work)},
                                   capture_output=True, text=True, timeout=timeout)
        output = work / f"{system.name}.csv"
        if completed.returncode != 0 or not output.exists():
            raise EngineError(f"ecos simulate failed ({completed.returncode}):\n"
                              f"{completed.stdout[-3000:]}\n{completed.stderr[-3000:]}")
        with open(output, newline="") as handle:
            reader = csv.reader(handle, skipinitialspace=True)
            header = next(reader)
            table = [row for row in reader if row]
    column = {name: i for i, name in enumerate(header)}
    indices = [column[f"{s.component}::{s.variable}[{ECOS_CSV_TYPES[s.type]}]"]
               for s in recording.signals]
    rows = [[float(row[i]) for i in indices] for row in table[:recording.rows]]
    if len(rows) != recording.rows:
        raise EngineError(f"ecos wrote {len(rows)} rows, expected {recording.rows}")
    return recording.results(rows)
