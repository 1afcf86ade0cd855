"""The compiled core modules, the Kalman steps and the estimators' machinery
(:mod:`altfusion.compiled`): used only while they match their sources, and the same bits as
the sources.

``build_fmu.py`` compiles :data:`~altfusion.compiled.COMPILED` with mypyc for the interpreter
running it. Here: after the build, the estimators step on the compiled modules; a stale,
foreign or unreadable compilation is never used; and the Python sources, run in a process
with :data:`~altfusion.compiled.PURE_PYTHON` set, give every estimator's recorded checksums
(tests/test_estimator_checksums.py checks the compiled ones in this process), so each path
is checked against the same recorded bits.
"""

import json
import os
import re
import shutil
import subprocess
import sys
import warnings
from importlib import import_module
from pathlib import Path

import pytest

import altfusion
from altfusion.compiled import (
    COMPILED,
    FOLDER,
    MANIFEST,
    PURE_PYTHON,
    compiled_path,
    is_compiled,
    manifest_for,
    stale_sources,
)

TESTS = Path(__file__).resolve().parent
CORE = Path(altfusion.__file__).parent


def compiled_here(package: str) -> bool:
    """Whether the build compiled ``package`` for this interpreter and the sources are not
    forced (otherwise the compiled path cannot be checked here)."""
    return stale_sources(CORE / package) is not None and \
        os.environ.get(PURE_PYTHON, "") in ("", "0")


@pytest.mark.parametrize("package", sorted(COMPILED))
def test_the_estimators_step_on_the_compiled_modules_after_the_build(package):
    """With a compilation for this interpreter that matches the sources (what ``build_fmu.py``
    leaves, ``build_fmu.py --check`` fails otherwise), every module of :data:`COMPILED` is
    the extension module in the package's compiled folder."""
    if not compiled_here(package):
        pytest.skip("nothing compiled for this interpreter (python build_fmu.py compiles) "
                    f"or {PURE_PYTHON} set")
    stale = stale_sources(CORE / package)
    assert stale == [], f"{stale} changed since compiled: run python build_fmu.py"
    for name in COMPILED[package]:
        module = import_module(f"altfusion.{package}.{name}")
        assert is_compiled(module), module.__file__
        # a module first imported by another compiled module is named by mypyc as if its
        # group's library sat at the core's root: <folder>/altfusion/<package>/<module>.so
        assert CORE / package / FOLDER in Path(module.__file__).parents, module.__file__


@pytest.fixture
def package(tmp_path) -> Path:
    """A package folder with one source and a manifest matching it for this interpreter."""
    (tmp_path / "steps.py").write_text("def double(x: float) -> float:\n    return 2.0 * x\n")
    (tmp_path / FOLDER).mkdir()
    manifest = manifest_for(tmp_path, ("steps",))
    (tmp_path / FOLDER / MANIFEST).write_text(json.dumps(manifest))
    return tmp_path


def _path(package: Path) -> tuple[list[str], list[str]]:
    """compiled_path of ``package`` and the warnings it gave."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        path = compiled_path(str(package))
    return path, [str(w.message) for w in caught]


def test_a_compilation_matching_its_sources_is_used(package, monkeypatch):
    monkeypatch.delenv(PURE_PYTHON, raising=False)
    assert _path(package) == ([str(package / FOLDER)], [])


def test_a_source_edited_since_compiled_runs_as_python_with_a_warning(package, monkeypatch):
    """An edited source: the compilation is not used, and the warning names the source and
    the command that compiles it again."""
    monkeypatch.delenv(PURE_PYTHON, raising=False)
    (package / "steps.py").write_text("def double(x: float) -> float:\n    return x + x\n")
    path, messages = _path(package)
    assert path == []
    assert len(messages) == 1 and "steps.py" in messages[0] and "build_fmu.py" in messages[0]
    (package / "steps.py").unlink()
    assert _path(package)[0] == []


@pytest.mark.parametrize("manifest", [
    {"cache_tag": "cpython-399", "sources": {}},      # compiled for another interpreter
    {"sources": {}},
    ["not", "a", "manifest"],
    "{truncated",
])
def test_a_foreign_or_unreadable_compilation_is_silently_not_used(package, monkeypatch,
                                                                  manifest):
    """Another interpreter's compilation (an FMU in a host running another Python) or a
    manifest that is no manifest: the sources run, without a warning."""
    monkeypatch.delenv(PURE_PYTHON, raising=False)
    text = manifest if isinstance(manifest, str) else json.dumps(manifest)
    (package / FOLDER / MANIFEST).write_text(text)
    assert _path(package) == ([], [])


@pytest.mark.parametrize("value, used", [("1", False), ("yes", False), ("0", True), ("", True)])
def test_the_environment_variable_runs_the_sources(package, monkeypatch, value, used):
    monkeypatch.setenv(PURE_PYTHON, value)
    assert _path(package)[0] == ([str(package / FOLDER)] if used else [])


WORKER = """
import json, sys
sys.path.insert(0, sys.argv[1])
import altfusion.estimators.kalman as kalman
from altfusion.compiled import is_compiled
from test_estimator_checksums import CASES, checksums
results = [[name, detection, checksums(name, detection)]
           for name in CASES for detection in (True, False)]
print(json.dumps({"compiled": is_compiled(kalman), "results": results}))
"""


def test_the_python_sources_give_every_recorded_checksum():
    """Every case of tests/test_estimator_checksums.py (every estimator, each paper system,
    the fault suite's flights, fault detection on and off) stepped on the Python sources
    gives the checksums recorded there, as the compiled modules do in this process."""
    from test_estimator_checksums import CHECKSUMS

    environment = {**os.environ, PURE_PYTHON: "1"}
    done = subprocess.run([sys.executable, "-c", WORKER, str(TESTS)], env=environment,
                          capture_output=True, text=True, check=True)
    found = json.loads(done.stdout)
    assert found["compiled"] is False
    assert len(found["results"]) == len(CHECKSUMS)
    for name, detection, sums in found["results"]:
        assert sums == CHECKSUMS[(name, detection)], (name, detection)


def test_a_source_mypy_rejects_fails_the_compilation_naming_the_error(tmp_path):
    """compile_core on a core whose compiled module does not type-check: a CompileError
    quoting mypy's message with the file and line, and nothing left to be used."""
    from altfusion.compile_core import CompileError, compile_core

    core = tmp_path / "altfusion"
    shutil.copytree(CORE, core, ignore=shutil.ignore_patterns(FOLDER, "__pycache__", "*.so"))
    folder = core / "estimators"
    kalman = folder / "kalman.py"
    lines = kalman.read_text().count("\n")
    with kalman.open("a") as source:
        source.write("\n\ndef gain(P: float) -> float:\n    return 'P'\n")
    with pytest.raises(CompileError,
                       match=rf"kalman\.py:{lines + 4}: error: Incompatible return"):
        compile_core(core)
    assert stale_sources(folder) is None


@pytest.mark.parametrize("pure", [False, True])
def test_the_command_line_says_whether_the_estimator_machinery_runs_compiled(pure):
    """``altfusion --version``: the core version, the Python, and which estimator machinery
    (compiled or its sources) a campaign started here would run (the environment variable
    forces the sources)."""
    if not pure and not (compiled_here("estimators")
                         and stale_sources(CORE / "estimators") == []):
        pytest.skip("nothing compiled for this interpreter (python build_fmu.py compiles)")
    environment = {**os.environ, PURE_PYTHON: "1" if pure else ""}
    done = subprocess.run([sys.executable, "-c",
                           "from altfusion.cli import main; main(['--version'])"],
                          env=environment, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    from altfusion.version import CORE_VERSION

    line = done.stdout.strip()
    assert line.startswith(f"altfusion {CORE_VERSION}, Python {sys.version.split()[0]}, ")
    assert line.endswith("estimator machinery: " + (
        "Python sources (python build_fmu.py compiles them for this Python)" if pure
        else "compiled (mypyc)"))


@pytest.mark.parametrize("package", sorted(COMPILED))
def test_every_class_of_a_compiled_module_can_be_made_blank(package):
    """The FMU state codec rebuilds an object blank (``cls.__new__(cls)``) and writes its
    fields; compiled, a class's generated ``__new__`` would run ``__init__``. So every class a
    compiled module defines derives from Restorable (an enum is rebuilt by its value), and a
    blank instance of it has none of its fields set, whether the module runs compiled or
    from its source."""
    import enum
    import inspect

    from altfusion.estimators.restorable import Restorable

    classes = [cls for name in COMPILED[package]
               for _, cls in inspect.getmembers(import_module(f"altfusion.{package}.{name}"),
                                                inspect.isclass)
               if cls.__module__ == f"altfusion.{package}.{name}"]
    with_classes = {f"altfusion.{package}.{name}" for name in COMPILED[package]
                    if re.search(r"^class ", (CORE / package / f"{name}.py").read_text(), re.M)}
    assert {cls.__module__ for cls in classes} == with_classes    # none missed by the scan
    for cls in classes:
        if issubclass(cls, enum.Enum):
            continue
        assert issubclass(cls, Restorable), f"{cls.__qualname__} does not derive from Restorable"
        if cls is not Restorable:
            blank = cls.__new__(cls)
            fields = getattr(cls, "__mypyc_attrs__", None) or [
                name for klass in cls.__mro__ for name in klass.__dict__.get("__slots__", ())]
            assert not [name for name in fields if hasattr(blank, name)], cls.__qualname__
