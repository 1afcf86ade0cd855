"""Compliance checks that run offline: FMUs against FMI 2.0, SSP files against SSP 1.0.

* :func:`fmu_problems`: fmpy's validator and fmu-manipulation-toolbox's checkers (the FMI 2.0
  XSD and the semantic rules the XSD cannot express).
* :func:`ssp_problems`: the SSD against the SSP 1.0 ``SystemStructureDescription.xsd`` and every
  inline parameter set against ``SystemStructureParameterValues.xsd`` (the SSD schema admits
  any content there), both shipped with fmpy; then what libcosim and ECOS need beyond the
  schema: the ``osp`` namespace declared on the root, a positive base step on the
  DefaultExperiment (libcosim crashes without one), a step-size hint per component that is a
  whole multiple of it, each component's FMU inside the archive, and every bound parameter and
  connector present in its FMU.
"""

import logging
import tempfile
import zipfile
from fractions import Fraction
from pathlib import Path

from lxml import etree

from altfusion.cosim.ssp import NS, OSP_ANNOTATION


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
    """Problems found in an SSP archive (empty: valid for fmpy, libcosim and ECOS)."""
    from fmpy import read_model_description

    with zipfile.ZipFile(path) as archive:
        names = set(archive.namelist())
        if "SystemStructure.ssd" not in names:
            return ["no SystemStructure.ssd in the archive"]
        root = etree.fromstring(archive.read("SystemStructure.ssd"))
        problems = _schema_errors(_schema("SystemStructureDescription.xsd"), root, "SSD")
        values_schema = _schema("SystemStructureParameterValues.xsd")
        for pset in root.iter(f"{{{NS['ssv']}}}ParameterSet"):
            problems += _schema_errors(values_schema, pset, f"ParameterSet {pset.get('name')}")
        if root.nsmap.get("osp") != NS["osp"]:
            problems.append("the osp namespace is not declared on the root element")
        algorithm = root.find("ssd:DefaultExperiment//osp:FixedStepAlgorithm", NS)
        base = _positive(algorithm.get("baseStepSize") if algorithm is not None else None)
        if base is None:
            problems.append("DefaultExperiment has no positive osp:FixedStepAlgorithm "
                            "baseStepSize")
        with tempfile.TemporaryDirectory(prefix="altfusion_ssp_check_") as work:
            for component in root.iterfind("ssd:System/ssd:Elements/ssd:Component", NS):
                problems += _component_problems(component, archive, names, base, Path(work),
                                                read_model_description)
    return problems


def _component_problems(component, archive, names, base, work, read_model_description):
    name, source = component.get("name"), component.get("source")
    problems = []
    hint = component.find(f"ssd:Annotations/ssc:Annotation[@type='{OSP_ANNOTATION}']"
                          f"/osp:StepSizeHint", NS)
    step = _positive(hint.get("value") if hint is not None else None)
    if step is None:
        problems.append(f"component {name}: no positive osp:StepSizeHint")
    elif base is not None and (step / base).denominator != 1:
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
