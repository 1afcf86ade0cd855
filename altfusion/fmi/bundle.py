"""Each FMU carries its own private copy of the core (PythonFMU issue #228).

pythonfmu runs every FMU inside the host's one Python interpreter and imports the slave
script's modules by name. Bundled as ``altfusion``, the core of the first FMU a process loads
would serve every later FMU of ours: from that FMU's extraction folder, which hosts such as
fmpy delete after the run (a later FMU's ``import altfusion.physics.atmosphere`` then fails),
and whatever core version the later FMU was built from.

So an FMU's resources hold the core under a name of its own, ``altfusion_<digest>`` (the
digest of the core's sources, :data:`altfusion.version.CORE_VERSION`), with every import of
``altfusion`` in the bundled sources and in the slave script renamed to it at build time
(:func:`stage_core`); the slave script is bundled under a name of its own too
(:func:`stage_script`), since pythonfmu imports it by name. Only the modules the slave
scripts import are bundled, listed in the copy's ``bundle.json`` with the core version; the
copy's package ``__init__`` imports all of them at once, while its folder exists, so a later
deletion of the folder costs nothing. Two FMUs of one core version share one copy
(same name, same code); FMUs of different core versions each run their own.

The names written into the modelDescription (the core class of the vendor annotation) are the
public ``altfusion`` ones (:func:`public_module`): our runner imports its own copy by them.
"""

import ast
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from altfusion.compiled import PURE_PYTHON
from altfusion.version import BUNDLE_MANIFEST

PACKAGE = "altfusion"


def private_name(core_version: str) -> str:
    """The package name of the core copy built from ``core_version`` (``0.1.0+<digest>``)."""
    return f"{PACKAGE}_{core_version.rpartition('+')[2]}"


def public_module(module: str) -> str:
    """``module`` with a private copy's package name replaced by ``altfusion``."""
    head, dot, rest = module.partition(".")
    return PACKAGE + dot + rest if head.startswith(f"{PACKAGE}_") else module


def imported_packages(tree: ast.Module) -> set[str]:
    """The absolute module names the source's import statements name."""
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


_IMPORT = re.compile(rf"^(\s*(?:from|import)\s+){PACKAGE}\b", re.MULTILINE)


def rename_imports(source: str, new: str, origin: str = "<source>") -> str:
    """``source`` with each ``import altfusion...`` / ``from altfusion... import`` naming
    ``new`` instead; refuses an import of the package it could not rename."""
    renamed = _IMPORT.sub(rf"\g<1>{new}", source)
    left = {n for n in imported_packages(ast.parse(renamed))
            if n == PACKAGE or n.startswith(f"{PACKAGE}.")}
    if left:
        raise ValueError(f"{origin}: cannot rename the import of {', '.join(sorted(left))} "
                         f"(write it as one 'import' or 'from' statement per line)")
    return renamed


def slave_modules(scripts: list[Path], package_dir: Path) -> list[str]:
    """The core modules (relative names) that importing the slave ``scripts`` loads, found in
    a fresh interpreter so that nothing this process imported counts (running the Python
    sources: the compiled modules are compiled into the copy, :mod:`altfusion.compiled`)."""
    paths = [str(package_dir.parent), *sorted({str(s.parent) for s in scripts})]
    probe = (
        "import importlib, json, sys\n"
        f"sys.path[:0] = {paths!r}\n"
        f"for name in {[s.stem for s in scripts]!r}: importlib.import_module(name)\n"
        f"print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] == {PACKAGE!r})))\n"
    )
    found = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                           check=True, env={**os.environ, PURE_PYTHON: "1"})
    return [m.partition(".")[2] for m in json.loads(found.stdout) if m != PACKAGE]


def stage_core(package_dir: Path, scripts: list[Path], core_version: str, stage: Path) -> Path:
    """Write the private copy of the core the slave ``scripts`` need into ``stage`` (replacing
    any earlier copy there); returns its package folder."""
    name = private_name(core_version)
    target = stage / name
    modules = slave_modules(scripts, package_dir)
    staging = stage / f".{name}.partial"
    shutil.rmtree(staging, ignore_errors=True)
    for module in ["", *modules]:
        parts = module.split(".") if module else []
        source = package_dir.joinpath(*parts)
        source = source / "__init__.py" if source.is_dir() else source.with_suffix(".py")
        dest = staging / source.relative_to(package_dir)
        dest.parent.mkdir(parents=True, exist_ok=True)
        dest.write_text(rename_imports(source.read_text(), name, str(source)))
    manifest = {"core_version": core_version, "modules": modules}
    (staging / BUNDLE_MANIFEST).write_text(json.dumps(manifest, indent=1) + "\n")
    for old in stage.glob(f"{PACKAGE}_*"):
        shutil.rmtree(old)
    staging.rename(target)
    return target


def stage_script(script: Path, core: Path, stage: Path) -> Path:
    """A copy of the slave ``script`` in ``stage`` importing the private ``core`` copy, named
    ``<stem>_<digest of its text>.py``: pythonfmu imports the slave module by that name, and a
    module of one name serves every later FMU in the process."""
    text = rename_imports(script.read_text(), core.name, str(script))
    digest = hashlib.sha256(text.encode()).hexdigest()[:12]
    folder = stage / "scripts"
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob(f"{script.stem}_*.py"):
        old.unlink()
    dest = folder / f"{script.stem}_{digest}.py"
    dest.write_text(text)
    return dest
