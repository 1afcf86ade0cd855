"""The GUID is a digest of the FMU's whole interface and the sources that define it: the
same sources build to the same GUID, a changed interface (two outputs' value references
swapped) to another, and the running instance carries the GUID of its modelDescription."""

import shutil
from pathlib import Path

from fmpy import read_model_description

import build_fmu

SCRIPT = build_fmu.HERE / "fmu_src" / "baseline_kf_slave.py"
FIRST, SECOND = ('fmi.Output("bias", "m", "Estimated baro bias b"),',
                 'fmi.Output("innovation", "m", "Innovation of the last fused sample"),')


def built_guid(script: Path, dest: Path) -> str:
    return read_model_description(str(build_fmu.build_fmu(script, dest))).guid


def test_rebuilding_unchanged_sources_keeps_the_guid(fmus, tmp_path):
    first = built_guid(SCRIPT, tmp_path / "first")
    assert built_guid(SCRIPT, tmp_path / "second") == first
    assert read_model_description(str(fmus["BaselineKF"])).guid == first


def test_swapping_two_outputs_value_references_changes_the_guid(fmus, tmp_path):
    source = SCRIPT.read_text()
    assert FIRST in source and SECOND in source
    swapped = tmp_path / "src" / SCRIPT.name
    swapped.parent.mkdir()
    swapped.write_text(source.replace(FIRST, "@@").replace(SECOND, FIRST).replace("@@", SECOND))
    description = read_model_description(str(build_fmu.build_fmu(swapped, tmp_path / "out")))
    original = read_model_description(str(fmus["BaselineKF"]))
    refs = {v.name: v.valueReference for v in description.modelVariables}
    original_refs = {v.name: v.valueReference for v in original.modelVariables}
    assert (refs["bias"], refs["innovation"]) == (original_refs["innovation"],
                                                   original_refs["bias"])
    assert description.guid != original.guid


def test_a_copy_of_the_script_elsewhere_keeps_the_guid(fmus, tmp_path):
    """The GUID depends on the script's content, not on where it lies."""
    copy = tmp_path / "src" / SCRIPT.name
    copy.parent.mkdir()
    shutil.copy(SCRIPT, copy)
    assert built_guid(copy, tmp_path / "out") == read_model_description(
        str(fmus["BaselineKF"])).guid
