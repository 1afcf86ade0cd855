"""The private core copy each FMU carries (altfusion.fmi.bundle)."""

import ast
import json
from pathlib import Path

import pytest

from altfusion.fmi.bundle import (
    imported_packages,
    private_name,
    public_module,
    rename_imports,
    stage_core,
    stage_script,
)
from altfusion.version import BUNDLE_MANIFEST, CORE_VERSION

ROOT = Path(__file__).resolve().parents[1]


def test_private_name_follows_the_core_digest():
    assert private_name("0.1.0+0123456789ab") == "altfusion_0123456789ab"
    assert public_module("altfusion_0123456789ab.estimators.yang") == "altfusion.estimators.yang"
    assert public_module("altfusion.estimators.yang") == "altfusion.estimators.yang"
    assert public_module("numpy.linalg") == "numpy.linalg"


def test_every_import_form_is_renamed_and_nothing_else():
    source = (
        "import altfusion\n"
        "import altfusion.physics.atmosphere as atm\n"
        "from altfusion import fmi\n"
        "from altfusion.estimators.base import (\n    Stream,\n)\n"
        "if True:\n    from altfusion.units import BASE_UNITS\n"
        "import altfusion_other\n"
        "text = 'from altfusion import x'\n"
    )
    renamed = rename_imports(source, "altfusion_abc")
    assert renamed.splitlines() == [
        "import altfusion_abc",
        "import altfusion_abc.physics.atmosphere as atm",
        "from altfusion_abc import fmi",
        "from altfusion_abc.estimators.base import (",
        "    Stream,",
        ")",
        "if True:",
        "    from altfusion_abc.units import BASE_UNITS",
        "import altfusion_other",
        "text = 'from altfusion import x'",
    ]


def test_an_import_it_cannot_rename_fails_the_build():
    with pytest.raises(ValueError, match="slave.py: cannot rename the import of altfusion"):
        rename_imports("import os, altfusion\n", "altfusion_abc", "slave.py")


def test_the_staged_copy_holds_what_the_slaves_import_renamed(tmp_path):
    scripts = [ROOT / "fmu_src" / "atmosphere_slave.py"]
    core = stage_core(ROOT / "altfusion", scripts, CORE_VERSION, tmp_path)
    assert core.name == private_name(CORE_VERSION)
    manifest = json.loads((core / BUNDLE_MANIFEST).read_text())
    assert manifest["core_version"] == CORE_VERSION
    assert {"physics.atmosphere", "fmi.slave", "constants"} <= set(manifest["modules"])
    assert "cosim" not in manifest["modules"] and "cli" not in manifest["modules"]
    for path in core.rglob("*.py"):
        imported = imported_packages(ast.parse(path.read_text()))
        assert not {n for n in imported if n.split(".")[0] == "altfusion"}, path
    script = stage_script(scripts[0], core, tmp_path)
    assert script.stem.startswith("atmosphere_slave_")
    assert f"from {core.name} import fmi" in script.read_text()
