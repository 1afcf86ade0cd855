"""The generated FMU reference (docs/fmu_reference.md) is current and complete."""

import re
from pathlib import Path

from fmpy import read_model_description

from altfusion.docs import fmu_reference

REFERENCE = Path(__file__).resolve().parents[1] / "docs" / "fmu_reference.md"


def test_the_committed_reference_is_the_generated_one(fmus):
    assert REFERENCE.read_text() == fmu_reference(sorted(fmus.values())), \
        "docs/fmu_reference.md is stale: run python build_fmu.py and commit docs/"


def test_every_parameter_input_and_output_has_its_unit_default_and_description(fmus):
    text = REFERENCE.read_text()
    for path in fmus.values():
        md = read_model_description(str(path))
        section = text.split(f"\n## {md.modelName}\n", 1)[1].split("\n## ", 1)[0]
        cells = [[c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
                 for line in section.splitlines() if line.startswith("| `")]
        rows = {row[0].strip("`"): row for row in cells}
        for var in md.modelVariables:
            if var.causality not in ("parameter", "input", "output"):
                continue
            name, kind, unit, detail, _low, _high, description = rows[var.name]
            assert (kind, unit, description) == (var.type, var.unit or "",
                                                 var.description.replace("|", "\\|")), var.name
            assert var.description, f"{md.modelName}.{var.name} has no description"
            if var.causality != "output":
                assert detail == (var.start or ""), f"{md.modelName}.{var.name} default"
