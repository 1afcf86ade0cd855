"""Compile the core's hot modules (:data:`altfusion.compiled.COMPILED`) with mypyc.

``build_fmu.py`` compiles them for the interpreter running it, before it imports the
estimators (so that it runs them compiled, and warns of no stale compilation), into the folder
:data:`~altfusion.compiled.FOLDER` of their package: once in the in-process core (the
package's own folder, ignored by git) and once in the private copy every FMU bundles (whose
module names differ, and a compiled module knows its name). Each compilation runs in a
scratch copy of the core's Python sources, so that mypy sees what the compiled modules
import, but checks only them (``--follow-imports=silent``: the modules left interpreted are
read for their types, not judged); the extension modules and the manifest that lets
:func:`altfusion.compiled.compiled_path` trust them are then moved into place. The C compiler
is the one setuptools uses (``$CC``, default ``cc``), with ``-ffp-contract=off`` added: a
multiply and an add stay two roundings, as in Python, on processors with fused multiply-adds
too.
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from altfusion.compiled import COMPILED, FOLDER, MANIFEST, manifest_for, stale_sources

GROUP = "native"
"""The name of the shared library of a package's compiled modules (``native__mypyc``)."""

_SETUP = """
import json, sys
from setuptools import setup
from mypyc.build import mypycify
paths, group = json.loads(sys.argv[1])
setup(name="compiled-core", ext_modules=mypycify(paths, opt_level="3", debug_level="0",
                                                              group_name=group),
      script_args=["build_ext", "--inplace", "--quiet"])
"""


class CompileError(RuntimeError):
    """The core's modules cannot be compiled (the message says why)."""


def outdated(core: Path) -> list[Path]:
    """The package folders of the core at ``core`` whose compiled modules are missing or
    older than their sources, for this interpreter."""
    return [core / package for package in COMPILED
            if stale_sources(core / package) != []]


def compile_core(core: Path) -> list[Path]:
    """Compile the :data:`COMPILED` modules of the core package at ``core`` (``altfusion`` or
    an FMU's private copy) where they are out of date; the package folders compiled."""
    done = []
    for folder in outdated(core):
        compile_package(core.name, folder, COMPILED[folder.name])
        done.append(folder)
    return done


def compile_package(core_name: str, folder: Path, modules: tuple[str, ...]) -> None:
    """Compile ``modules`` of the package at ``folder`` (within the core ``core_name``) into
    its :data:`FOLDER`, with their manifest."""
    try:
        import mypyc  # noqa: F401  (only checks that it is installed)
    except ImportError as error:
        raise CompileError("compiling the core needs mypyc (pip install mypy)") from error
    package = f"{core_name}.{folder.name}"
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        shutil.copytree(folder.parent, root / core_name,
                        ignore=shutil.ignore_patterns(FOLDER, "__pycache__", "*.so", "*.pyd"))
        target = root / core_name / folder.name
        paths = [f"{core_name}/{folder.name}/{module}.py" for module in modules]
        environment = {**os.environ,
                       "CFLAGS": f"{os.environ.get('CFLAGS', '')} -ffp-contract=off".strip()}
        done = subprocess.run([sys.executable, "-c", _SETUP,
                               json.dumps([[*paths, "--follow-imports=silent"],
                                           f"{package}.{GROUP}"])],
                              cwd=root, env=environment, capture_output=True, text=True,
                              check=False)
        if done.returncode != 0:
            raise CompileError(f"compiling {', '.join(paths)} with mypyc failed:\n"
                               f"{(done.stdout + done.stderr).strip()[-4000:]}")
        built = sorted(p for p in target.iterdir() if p.suffix in (".so", ".pyd"))
        destination = folder / FOLDER
        shutil.rmtree(destination, ignore_errors=True)
        destination.mkdir()
        for library in built:
            shutil.move(library, destination / library.name)
    manifest = manifest_for(folder, modules)
    (destination / MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n")
