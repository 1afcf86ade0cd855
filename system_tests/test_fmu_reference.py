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


def test_every_fmu_has_a_current_page_with_its_text_and_reference_plot(fmus):
    """docs/fmus/<Model>.md is what build_fmu.py generates from fmu_src/docs/<Model>.md (whose
    reference run names a catalog system holding the component) and links its plot."""
    from altfusion.docs import fmu_page, read_fmu_text
    from altfusion.systems import build_system

    root = REFERENCE.parent.parent
    for name, path in fmus.items():
        text = read_fmu_text(root / "fmu_src" / "docs" / f"{name}.md")
        assert build_system(text.reference.system).component(text.reference.component).fmu \
            == name
        assert (REFERENCE.parent / "fmus" / f"{name}.png").is_file(), f"{name}: no plot"
        page = REFERENCE.parent / "fmus" / f"{name}.md"
        assert page.read_text() == fmu_page(path, text, f"{name}.png"), \
            f"docs/fmus/{name}.md is stale: run python build_fmu.py and commit docs/"
