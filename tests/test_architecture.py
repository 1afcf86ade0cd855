"""The architecture of DEVELOPERS.md, enforced.

The package's import contracts live in ``pyproject.toml`` (``[tool.importlinter]``) and are
checked by import-linter's ``lint-imports``: every top-level module and package of ``altfusion``
sits in one layer of the stack and imports only the layers below it; the numerics (physics,
sensors, estimators) import no FMI edge, runner, CLI or campaign code and no FMI library; the
estimators are independent of each other; no two sibling modules or packages import each
other. Each contract is shown to fail on a copy of the package with one violating import
added. ``fmu_src/`` holds scripts, not a package, so its contract (a slave never imports the
runner) is an AST check here.
"""

import ast
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")

LAYERS = "Layers: each package imports only the layers below it"
NUMERICS = "The numerics import no FMI edge"
INDEPENDENCE = "Estimators are independent of each other"
ACYCLIC = "No import cycles between sibling modules or packages"
CONTRACTS = (LAYERS, NUMERICS, INDEPENDENCE, ACYCLIC)

# The runner and everything above it: an FMU runs inside a host, never a host inside an FMU.
FMU_SRC_FORBIDDEN = ("altfusion.cosim", "altfusion.montecarlo", "altfusion.evaluation",
                     "altfusion.cli", "altfusion.interop", "fmpy")


def lint_imports(root: Path) -> subprocess.CompletedProcess:
    """``lint-imports`` on the package and contracts found in ``root``."""
    return subprocess.run([str(LINT_IMPORTS), "--no-cache"], cwd=root, capture_output=True,
                          text=True, timeout=120)


def broken_contracts(output: str) -> set[str]:
    """The contracts whose summary line reads BROKEN (a long name wraps over two lines)."""
    text = " ".join(output.split())
    verdicts = {name: re.search(re.escape(name) + r"[^.]*?\b(KEPT|BROKEN)\b", text)
                for name in CONTRACTS}
    return {name for name, verdict in verdicts.items() if verdict and verdict[1] == "BROKEN"}


def test_import_contracts_hold():
    completed = lint_imports(ROOT)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert "4 kept, 0 broken" in completed.stdout


def test_every_top_level_module_is_in_a_layer():
    """A module or package outside the layers contract would escape it: each one of
    ``altfusion`` is named in exactly one layer."""
    block = re.search(r'type = "layers".*?^layers = \[(.*?)^\]', (ROOT / "pyproject.toml")
                      .read_text(), re.S | re.M)[1]
    layers = re.findall(r'"([^"]+)"', block)
    named = [name.strip() for layer in layers for name in re.split(r"[|:]", layer)]
    package = ROOT / "altfusion"
    present = {path.stem for path in package.glob("*.py") if path.stem != "__init__"} | {
        path.parent.name for path in package.glob("*/__init__.py")}
    assert sorted(named) == sorted(present)


@pytest.mark.parametrize(("module", "violation", "contract"), [
    ("physics/atmosphere.py", "import altfusion.fmi", NUMERICS),
    ("sensors/gnss.py", "from altfusion.cosim import runner", NUMERICS),
    ("estimators/kalman.py", "import altfusion.cli", NUMERICS),
    ("estimators/base.py", "import altfusion.montecarlo.storage", NUMERICS),
    ("sensors/sampling.py", "import altfusion.interop", NUMERICS),
    ("estimators/yang.py", "import fmpy", NUMERICS),
    ("estimators/xu.py", "from altfusion.estimators import yang", INDEPENDENCE),
    ("montecarlo/commands.py", "import altfusion.cli", ACYCLIC),
    ("systems/catalog.py", "import altfusion.replay.extract", ACYCLIC),
    ("interop/engines.py", "import altfusion.interop.proxy", ACYCLIC),
    ("cosim/ssp.py", "import altfusion.cosim.settings", ACYCLIC),
    ("cosim/runner.py", "import altfusion.montecarlo.storage", LAYERS),
    ("systems/catalog.py", "from altfusion.cosim import runner", LAYERS),
    ("estimators/base.py", "import altfusion.systems.spec", LAYERS),
    ("montecarlo/worker.py", "import altfusion.evaluation.metrics", LAYERS),
    ("reproduce/common.py", "import altfusion.evaluation.run", LAYERS),
    ("physics/atmosphere.py", "import altfusion.sensors.gnss", LAYERS),
    ("timegrid.py", "import altfusion.physics.atmosphere", LAYERS),
    ("scores.py", "import altfusion.systems.catalog", LAYERS),
])
def test_each_contract_fails_on_a_violating_import(tmp_path: Path, module: str, violation: str,
                                                   contract: str):
    """A copy of the package with one import appended breaks the expected contract (a contract
    that cannot fail would make test_import_contracts_hold vacuous). An edge import in the
    numerics may also close a cycle (the edges import the numerics), so other contracts may
    break too."""
    shutil.copytree(ROOT / "altfusion", tmp_path / "altfusion",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    target = tmp_path / "altfusion" / module
    target.write_text(target.read_text() + f"\n{violation}  # noqa\n")
    completed = lint_imports(tmp_path)
    assert completed.returncode != 0
    assert contract in broken_contracts(completed.stdout), completed.stdout


def forbidden_imports(source: str) -> list[str]:
    """The modules of ``FMU_SRC_FORBIDDEN`` (or below them) that ``source`` imports."""
    imported = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            imported += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            imported += [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
    return sorted({name for name in imported for forbidden in FMU_SRC_FORBIDDEN
                   if name == forbidden or name.startswith(forbidden + ".")})


def test_fmu_scripts_never_import_the_runner():
    scripts = sorted((ROOT / "fmu_src").glob("*_slave.py"))
    assert len(scripts) == 17
    violations = {script.name: forbidden_imports(script.read_text()) for script in scripts}
    assert {name: found for name, found in violations.items() if found} == {}


@pytest.mark.parametrize(("source", "found"), [
    ("from altfusion.cosim import Simulation", ["altfusion.cosim", "altfusion.cosim.Simulation"]),
    ("import altfusion.montecarlo.worker", ["altfusion.montecarlo.worker"]),
    ("from altfusion import cli", ["altfusion.cli"]),
    ("def f():\n    from fmpy import simulate_fmu", ["fmpy", "fmpy.simulate_fmu"]),
    ("from altfusion.fmi import CoreSlave\nfrom altfusion.cosimulation import x", []),
])
def test_fmu_script_check_finds_runner_imports(source: str, found: list[str]):
    assert forbidden_imports(source) == found


def test_system_description_imports_no_fmi_library():
    """Describing a system (plain data, the whole catalog) loads neither fmpy nor pythonfmu;
    the runner's package loads fmpy and exports the runner."""
    code = ("import sys\n"
            "import altfusion.systems.spec, altfusion.systems\n"
            "altfusion.systems.build_system(altfusion.systems.DEFAULT_SYSTEM)\n"
            "assert not {'fmpy', 'pythonfmu'} & set(sys.modules), 'FMI library loaded'\n"
            "from altfusion.cosim import Simulation, read_ssp\n"
            "assert 'fmpy' in sys.modules and callable(read_ssp) and Simulation.run\n")
    completed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               timeout=120)
    assert completed.returncode == 0, completed.stderr


NUMERICS_PACKAGES = ("physics", "sensors", "estimators")


def builtin_sum_calls(source: str) -> list[int]:
    """The lines of ``source`` that call the builtin ``sum``."""
    return [node.lineno for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
            and node.func.id == "sum"]


def test_the_numerics_never_sum_floats_with_the_builtin_sum():
    """Python 3.12 changed ``sum`` of floats to a compensated summation, which gives other
    bits than 3.11's additions one after the other: an estimator summing with it would give
    other outputs on another Python (FMUs run in the host's). The numerics add with
    ``kalman.running_sum`` (3.11's order, written out) or ``math.fsum`` (correctly rounded)."""
    found = {str(path.relative_to(ROOT)): lines
             for package in NUMERICS_PACKAGES
             for path in sorted((ROOT / "altfusion" / package).rglob("*.py"))
             if (lines := builtin_sum_calls(path.read_text()))}
    assert found == {}


def test_the_sum_check_finds_builtin_sum_calls():
    assert builtin_sum_calls("x = sum(w)\ny = math.fsum(w)\nz = np.sum(w)\n") == [1]


def imported_packages(source: str) -> set[str]:
    """The top-level packages ``source`` imports."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(alias.name.partition(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.partition(".")[0])
    return found


def test_the_estimators_import_no_numpy():
    """The estimators step on Python floats (``estimators/kalman.py``): numpy's BLAS sums a
    product's terms in an order of its processor's kernel, so that an estimator on arrays
    gives other bits on another machine (``tests/test_blas_independence.py``). Its array
    forms are the tests' reference (``tests/kalman_reference.py``)."""
    found = sorted(str(path.relative_to(ROOT))
                   for path in (ROOT / "altfusion" / "estimators").rglob("*.py")
                   if "numpy" in imported_packages(path.read_text()))
    assert found == []


def test_the_import_check_finds_numpy_however_imported():
    assert imported_packages("import numpy as np\nfrom numpy.linalg import solve\n"
                             "from . import numbers\nimport math\n") == {"numpy", "math"}
