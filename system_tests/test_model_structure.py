"""Every FMU's declared dependencies are true to its code, found by perturbation through fmpy.

FMI 2.0 section 2.2.8: an output's ``dependencies`` list the inputs it depends on directly (no
attribute: every input, which makes a host such as OMSimulator see algebraic loops that are
not there). Here each input of each FMU is set to several values and the outputs are read
without stepping: in Initialization Mode (ModelStructure/InitialUnknowns) and after a step
(ModelStructure/Outputs). The outputs that change must be exactly the declared ones: none
missing (a host would order components wrongly), none false (a host would see loops).
"""

import math
from pathlib import Path

import pytest
from fmpy import read_model_description

from altfusion.cosim.instances import FmuInstance, fmu_info

PERTURBATIONS = {"Real": (0.37, 1000.0, -1000.0), "Integer": (3,), "Boolean": (None,)}
"""Values added to a Real's start (0.37 scaled by its size, then ±1000 set outright: large
enough to lift a resting vehicle or saturate a controller), added to an Integer, and a
Boolean flipped."""


def _start(var) -> object:
    kind = {"Real": float, "Integer": int}.get(var.type)
    if kind:
        return kind(var.start or 0)
    return str(var.start).lower() in ("true", "1")


def _values(var) -> list:
    start = _start(var)
    if var.type == "Boolean":
        return [not start]
    if var.type == "Integer":
        return [start + d for d in PERTURBATIONS["Integer"]]
    return [start + 0.37 * (1.0 + abs(start)), 1000.0, -1000.0]


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b))


def observed_dependencies(path: Path, stepped: bool) -> dict[str, set[str]]:
    """Output name -> the inputs whose change changes it without a step (through our
    runner's fmpy instance, whose logger outlives any other fmpy user in the process)."""
    variables = read_model_description(str(path)).modelVariables
    inputs = [v for v in variables if v.causality == "input"]
    outputs = [v for v in variables if v.causality == "output"]
    instance = FmuInstance("probe", fmu_info(path))

    def read() -> dict[str, object]:
        return {o.name: instance.get(o.type, [o.valueReference])[0] for o in outputs}

    found = {o.name: set() for o in outputs}
    try:
        instance.initialize({}, 0.0, 0.0, 1.0)
        if stepped:
            instance.exit_initialization()
            instance.do_step(0.0, 0.01)
        for var in inputs:
            baseline = read()
            for value in _values(var):
                instance.set(var.type, [var.valueReference], [value])
                found_now = read()
                found.update({n: found[n] | {var.name} for n in found
                              if not _same(baseline[n], found_now[n])})
            instance.set(var.type, [var.valueReference], [_start(var)])
            restored = read()
            assert all(_same(baseline[n], restored[n]) for n in baseline), var.name
    finally:
        instance.free()
    return found


def declared_dependencies(path: Path, section: str) -> dict[str, set[str]]:
    md = read_model_description(str(path))
    unknowns = md.outputs if section == "Outputs" else md.initialUnknowns
    declared = {}
    for unknown in unknowns:
        assert unknown.dependencies is not None, f"{unknown.variable.name}: no dependencies"
        declared[unknown.variable.name] = {d.name for d in unknown.dependencies}
    return declared


@pytest.mark.parametrize("section", ["InitialUnknowns", "Outputs"])
def test_declared_dependencies_are_the_ones_a_perturbation_finds(fmus, section):
    wrong = {}
    for name, path in sorted(fmus.items()):
        declared = declared_dependencies(path, section)
        observed = observed_dependencies(path, stepped=section == "Outputs")
        assert set(declared) == set(observed), name
        for output, inputs in observed.items():
            if declared[output] != inputs:
                wrong[f"{name}.{output}"] = (sorted(declared[output]), sorted(inputs))
    assert not wrong, f"(declared, observed) differ: {wrong}"


def test_no_output_depends_directly_on_an_input_after_initialization(fmus):
    """Our outputs change only in doStep: a host sees no direct feedthrough and no loop."""
    for name, path in fmus.items():
        assert all(not deps for deps in declared_dependencies(path, "Outputs").values()), name
