"""The GUID is a digest of the FMU's whole interface and the sources that define it: the
same sources build to the same GUID, a changed interface (two outputs' value references
swapped) to another, and the running instance carries the GUID of its modelDescription: an
instance asked for with another GUID is refused."""

import re
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
from fmpy import read_model_description

import build_fmu
from altfusion.cosim.instances import CosimError, FmuInstance, fmu_info

SCRIPT = build_fmu.HERE / "fmu_src" / "baseline_kf_slave.py"
FIRST, SECOND = ('fmi.Output("bias", "m", "Estimated baro bias b"),',
                 'fmi.Output("innovation", "m", "Innovation of the last fused sample"),')


def built_guid(script: Path, dest: Path) -> str:
    return read_model_description(str(build_fmu.build_fmu(script, dest))).guid


def test_rebuilding_unchanged_sources_keeps_the_guid(fmus, tmp_path):
    first = built_guid(SCRIPT, tmp_path / "first")
    assert built_guid(SCRIPT, tmp_path / "second") == first
    assert read_model_description(str(fmus["BaselineKF"])).guid == first


def swapped_build(folder: Path) -> Path:
    """BaselineKF built into ``folder`` with its outputs bias and innovation's value
    references swapped."""
    source = SCRIPT.read_text()
    assert FIRST in source and SECOND in source
    swapped = folder / "src" / SCRIPT.name
    swapped.parent.mkdir()
    swapped.write_text(source.replace(FIRST, "@@").replace(SECOND, FIRST).replace("@@", SECOND))
    return build_fmu.build_fmu(swapped, folder / "out")


def test_swapping_two_outputs_value_references_changes_the_guid(fmus, tmp_path):
    description = read_model_description(str(swapped_build(tmp_path)))
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


def test_an_instance_asked_for_with_another_builds_guid_is_refused_naming_both(fmus):
    """A host holding another build's modelDescription.xml (value references that may name
    other variables) gets no instance, and its log says why; the right GUID still works.
    (Through the runner's instances: their logger outlives fmpy's default one, which another
    fmpy user in the process may have freed.)"""
    info = fmu_info(fmus["Atmosphere"])
    stale = "11111111-2222-5333-8444-555555555555"
    with pytest.raises(CosimError, match=re.escape(
            f"component 'atmosphere': fmi2Instantiate: GUID '{stale}' is not this FMU's "
            f"('{info.guid}'): the host read the modelDescription.xml of another build")):
        FmuInstance("atmosphere", replace(info, guid=stale))
    run_briefly(FmuInstance("atmosphere", info))


def test_an_fmu_rebuilt_at_a_path_already_run_is_read_and_run_anew(fmus, tmp_path):
    """A process that ran an FMU and then finds another build at the same path (rebuilt
    between two runs of one session) reads the new build's description and extracts and
    runs the new build, not the first one's files (the description was cached by path: its
    stale GUID now meets the new build's extraction and is refused)."""
    path = tmp_path / "BaselineKF.fmu"
    shutil.copy(fmus["BaselineKF"], path)
    first = fmu_info(path)
    run_briefly(FmuInstance("estimator", first))
    shutil.copy(swapped_build(tmp_path), path)
    second = fmu_info(path)
    assert second.guid != first.guid
    assert (second.variables["bias"].value_reference,
            second.variables["innovation"].value_reference) == (
        first.variables["innovation"].value_reference, first.variables["bias"].value_reference)
    run_briefly(FmuInstance("estimator", second))


def run_briefly(instance: FmuInstance) -> None:
    instance.initialize({}, 0.01, 0.0, 1.0)
    instance.exit_initialization()
    instance.do_step(0.0, 0.01)
    instance.free()
