"""Compliance checks that run offline: FMUs against FMI 2.0, SSP files against SSP 1.0.

* :func:`fmu_problems`: fmpy's validator and fmu-manipulation-toolbox's checkers (the FMI 2.0
  XSD and the semantic rules the XSD cannot express).
* :func:`ssp_problems`: both descriptions of the archive (``SystemStructure.ssd`` and the OSP
  one, :data:`~altfusion.cosim.ssp.OSP_SSD`) against the SSP 1.0
  ``SystemStructureDescription.xsd`` and every inline parameter set against
  ``SystemStructureParameterValues.xsd`` (the SSD schema admits any content there), both
  shipped with fmpy; then what libcosim, ECOS and OMSimulator need beyond the schema: the
  ``osp`` namespace declared on the root, a positive base step on the DefaultExperiment
  (libcosim crashes without one), in the OSP description a step-size hint per component that
  is a whole multiple of it, in ``SystemStructure.ssd`` OMSimulator's fixed-step master and no
  annotation on a component or at the top (its command line refuses them), each component's
  FMU inside the archive, and every bound parameter and connector present in its FMU.
"""

import logging
import tempfile
import zipfile
from fractions import Fraction
from pathlib import Path

from lxml import etree

from altfusion.cosim.ssp import NS, OSP_ANNOTATION, OSP_SSD


def fmu_problems(path: Path) -> list[str]:
    """Problems fmpy and fmu-manipulation-toolbox find in the FMU (empty: compliant)."""
    from fmpy.validation import validate_fmu
    from fmu_manipulation_toolbox.checker import get_checkers
    from fmu_manipulation_toolbox.operations import FMU

    problems = [f"fmpy: {p}" for p in validate_fmu(str(path))]
    logger = logging.getLogger("fmu_manipulation_toolbox")

    class Collect(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            if record.levelno >= logging.ERROR:
                problems.append(f"fmu-manipulation-toolbox: {record.getMessage()}")

    handler, level, propagate = Collect(), logger.level, logger.propagate
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    logger.propagate = False
    try:
        with FMU(str(path)) as fmu:
            for checker in get_checkers():
                fmu.apply_operation(checker())
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
        logger.propagate = propagate
    return problems


def _schema(name: str) -> etree.XMLSchema:
    import fmpy.ssp

    return etree.XMLSchema(file=str(Path(fmpy.ssp.__file__).parent / "schema" / name))


def _schema_errors(schema: etree.XMLSchema, element, what: str) -> list[str]:
    if schema.validate(element):
        return []
    return [f"{what}: line {e.line}: {e.message}" for e in schema.error_log]


def _positive(text: str | None) -> Fraction | None:
    try:
        value = Fraction(text) if text is not None else None
    except ValueError:
        return None
    return value if value is not None and value > 0 else None


def ssp_problems(path: Path) -> list[str]:
    """Problems found in an SSP archive (empty: valid for fmpy, libcosim, ECOS and
    OMSimulator)."""
    from fmpy import read_model_description

    with zipfile.ZipFile(path) as archive:
        names = set(archive.namelist())
        problems = []
        for ssd, step_hints in (("SystemStructure.ssd", False), (OSP_SSD, True)):
            if ssd not in names:
                problems.append(f"no {ssd} in the archive")
                continue
            root = etree.fromstring(archive.read(ssd))
            problems += [f"{ssd}: {p}" for p in _ssd_problems(
                root, step_hints, archive, names, read_model_description)]
    return problems


def _ssd_problems(root, step_hints: bool, archive, names, read_model_description) -> list[str]:
    problems = _schema_errors(_schema("SystemStructureDescription.xsd"), root, "SSD")
    values_schema = _schema("SystemStructureParameterValues.xsd")
    for pset in root.iter(f"{{{NS['ssv']}}}ParameterSet"):
        problems += _schema_errors(values_schema, pset, f"ParameterSet {pset.get('name')}")
    if root.nsmap.get("osp") != NS["osp"]:
        problems.append("the osp namespace is not declared on the root element")
    algorithm = root.find("ssd:DefaultExperiment//osp:FixedStepAlgorithm", NS)
    base = _positive(algorithm.get("baseStepSize") if algorithm is not None else None)
    if base is None:
        problems.append("DefaultExperiment has no positive osp:FixedStepAlgorithm baseStepSize")
    if not step_hints:
        master = root.find("ssd:System/ssd:Annotations//oms:FixedStepMaster", NS)
        if _positive(master.get("stepSize") if master is not None else None) != base:
            problems.append("the system has no oms:FixedStepMaster on the base step")
        if root.find("ssd:Annotations", NS) is not None or \
                root.find("ssd:System/ssd:Elements/ssd:Component/ssd:Annotations", NS) \
                is not None:
            problems.append("an annotation at the top or on a component (OMSimulator's "
                            "command line refuses the file)")
    with tempfile.TemporaryDirectory(prefix="altfusion_ssp_check_") as work:
        for component in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
            problems += _component_problems(component, archive, names, base, step_hints,
                                            Path(work), read_model_description)
    return problems


def _component_problems(component, archive, names, base, step_hints, work,
                        read_model_description):
    name, source = component.get("name"), component.get("source")
    problems = []
    hint = component.find(f"ssd:Annotations/ssc:Annotation[@type='{OSP_ANNOTATION}']"
                          f"/osp:StepSizeHint", NS)
    step = _positive(hint.get("value") if hint is not None else None)
    if step_hints and step is None:
        problems.append(f"component {name}: no positive osp:StepSizeHint")
    elif step_hints and base is not None and (step / base).denominator != 1:
        problems.append(f"component {name}: step {step} is not a multiple of the base step")
    if source not in names:
        return problems + [f"component {name}: {source} is not in the archive"]
    fmu = work / f"{name}.fmu"
    fmu.write_bytes(archive.read(source))
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    for connector in component.iterfind("ssd:Connectors/ssd:Connector", NS):
        var = variables.get(connector.get("name"))
        if var is None:
            problems.append(f"component {name}: connector {connector.get('name')} is not a "
                            f"variable of {source}")
        elif connector.get("kind") != var.causality:
            problems.append(f"component {name}: connector {var.name} is {connector.get('kind')}"
                            f", the FMU says {var.causality}")
    for parameter in component.iterfind(".//ssv:Parameter", NS):
        var = variables.get(parameter.get("name"))
        if var is None or var.causality != "parameter":
            problems.append(f"component {name}: {source} has no parameter "
                            f"{parameter.get('name')}")
    return problems
