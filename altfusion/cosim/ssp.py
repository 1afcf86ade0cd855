"""SSP 1.0 archives (``.ssp``) for our systems: a writer and a reader.

The writer embeds the FMUs under ``resources/`` and declares every component's inputs,
outputs and bound parameters as typed connectors (units from the modelDescription). An archive
holds two descriptions of the same system:

* ``SystemStructure.ssd``, the one every host reads: components, their parameter bindings
  (each component's ``step_size``, its tick, among them), connections, units, the
  DefaultExperiment with OSP's base step (``osp:FixedStepAlgorithm``) and our recording and
  error metrics (an ``org.altfusion.cosim`` annotation other tools ignore), and on the system
  OMSimulator's annotation (a fixed-step master on the base step), which its command line
  needs. It has no annotation on a component, which OMSimulator's command line refuses, and
  no String binding equal to the FMU's default (its command line cannot set a String:
  ``docs/interop.md``). Every host can step every component on the base step: each FMU ticks
  on its own ``step_size``.
* :data:`OSP_SSD`, the same with OSP's ``osp:StepSizeHint`` on each component, from which
  libcosim and ECOS step each component at its own rate (:mod:`altfusion.interop.engines`).

The reader parses and schema-validates ``SystemStructure.ssd`` with fmpy's SSP reader and
reads those annotations.
"""

import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from fmpy import read_model_description
from fmpy.ssp.ssd import read_ssd
from lxml import etree

from altfusion.cosim.scratch import ScratchFolder
from altfusion.errors import UsageError
from altfusion.systems.spec import ComponentSpec, Connection, Metric, SystemSpec
from altfusion.units import BASE_UNITS
from altfusion.version import CORE_VERSION

NS = {
    "ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
    "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
    "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations",
    "af": "urn:altfusion:cosim",
    "oms": "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd",
}
OSP_ANNOTATION = "com.opensimulationplatform"
OMS_ANNOTATION = "org.openmodelica"
"""OMSimulator's annotation: the system type (weakly coupled, its fixed-step master) and the
master's step, which its command line needs to import an SSP."""
AF_ANNOTATION = "org.altfusion.cosim"
FMU_MIME = "application/x-fmu-sharedlibrary"
OSP_SSD = "SystemStructureOSP.ssd"
"""The archive's second description: ``SystemStructure.ssd`` with each component's step hint."""

for _prefix, _uri in NS.items():
    ET.register_namespace(_prefix, _uri)


def _q(prefix: str, tag: str) -> str:
    return f"{{{NS[prefix]}}}{tag}"


def _typed_value(parent: ET.Element, prefix: str, value: Any) -> None:
    if isinstance(value, bool):
        ET.SubElement(parent, _q(prefix, "Boolean"), value=str(value).lower())
    elif isinstance(value, int):
        ET.SubElement(parent, _q(prefix, "Integer"), value=str(value))
    elif isinstance(value, float):
        ET.SubElement(parent, _q(prefix, "Real"), value=repr(value))
    elif isinstance(value, str):
        ET.SubElement(parent, _q(prefix, "String"), value=value)
    else:
        raise TypeError(f"parameter value {value!r} has an unsupported type")


def _annotation(parent: ET.Element, annotation_type: str) -> ET.Element:
    annotations = ET.SubElement(parent, _q("ssd", "Annotations"))
    return ET.SubElement(annotations, _q("ssc", "Annotation"), type=annotation_type)


def _bindings(component: ComponentSpec, md) -> dict[str, Any]:
    """The parameters to bind: the component's (a String only if it is not the FMU's
    default) and its ``step_size``."""
    defaults = {v.name: v.start for v in md.modelVariables if v.type == "String"}
    return {**{name: value for name, value in component.parameters.items()
               if not (isinstance(value, str) and defaults.get(name) == value)},
            "step_size": component.step_size}


def system_structure(system: SystemSpec, fmu_paths: dict[str, Path],
                     step_hints: bool = False) -> ET.Element:
    """The SystemStructureDescription element of ``system`` (with ``step_hints``, each
    component's ``osp:StepSizeHint``: :data:`OSP_SSD`)."""
    # The OSP description's own name: OMSimulator's Python API takes every .ssd of an archive
    # as a variant, named after it.
    name = f"{system.name}_osp" if step_hints else system.name
    root = ET.Element(_q("ssd", "SystemStructureDescription"), version="1.0", name=name,
                      generationTool=f"altfusion {CORE_VERSION}")
    sys_el = ET.SubElement(root, _q("ssd", "System"), name=system.name,
                           description=system.description)
    elements = ET.SubElement(sys_el, _q("ssd", "Elements"))
    used_units: set[str] = set()
    descriptions = {c.fmu: read_model_description(str(fmu_paths[c.fmu]))
                    for c in system.components}
    for component in system.components:
        md = descriptions[component.fmu]
        comp_el = ET.SubElement(elements, _q("ssd", "Component"), name=component.name,
                                type=FMU_MIME, source=f"resources/{component.fmu}.fmu")
        connectors = ET.SubElement(comp_el, _q("ssd", "Connectors"))
        bound = _bindings(component, md)
        for var in md.modelVariables:
            if var.causality in ("input", "output") or var.name in bound:
                kind = var.causality
                conn = ET.SubElement(connectors, _q("ssd", "Connector"), name=var.name,
                                     kind=kind)
                attrs = {"unit": var.unit} if var.type == "Real" and var.unit else {}
                used_units.update(attrs.values())
                ET.SubElement(conn, _q("ssc", var.type), **attrs)
        bindings = ET.SubElement(comp_el, _q("ssd", "ParameterBindings"))
        binding = ET.SubElement(bindings, _q("ssd", "ParameterBinding"))
        values = ET.SubElement(binding, _q("ssd", "ParameterValues"))
        pset = ET.SubElement(values, _q("ssv", "ParameterSet"), version="1.0", name="parameters")
        params_el = ET.SubElement(pset, _q("ssv", "Parameters"))
        for name, value in bound.items():
            ET.SubElement(params_el, _q("ssv", "Parameter"), name=name)
            _typed_value(params_el[-1], "ssv", value)
        if step_hints:
            hint = _annotation(comp_el, OSP_ANNOTATION)
            ET.SubElement(hint, _q("osp", "StepSizeHint"), value=repr(component.step_size))
    connections = ET.SubElement(sys_el, _q("ssd", "Connections"))
    for connection in system.connections:
        start_el, start_var = connection.start.split(".", 1)
        end_el, end_var = connection.end.split(".", 1)
        ET.SubElement(connections, _q("ssd", "Connection"), startElement=start_el,
                      startConnector=start_var, endElement=end_el, endConnector=end_var)
    oms = ET.SubElement(_annotation(sys_el, OMS_ANNOTATION), _q("oms", "Annotations"))
    ET.SubElement(ET.SubElement(oms, _q("oms", "SimulationInformation")),
                  _q("oms", "FixedStepMaster"), description="oms-ma",
                  stepSize=repr(system.base_step), absoluteTolerance="0.0001",
                  relativeTolerance="0.0001")
    units = ET.SubElement(root, _q("ssd", "Units"))
    for unit in sorted(used_units):
        unit_el = ET.SubElement(units, _q("ssc", "Unit"), name=unit)
        ET.SubElement(unit_el, _q("ssc", "BaseUnit"),
                      **{k: str(v) for k, v in BASE_UNITS[unit].items()})
    experiment = ET.SubElement(root, _q("ssd", "DefaultExperiment"),
                               startTime=repr(system.start_time), stopTime=repr(system.stop_time))
    algorithm = ET.SubElement(_annotation(experiment, OSP_ANNOTATION), _q("osp", "Algorithm"))
    ET.SubElement(algorithm, _q("osp", "FixedStepAlgorithm"), baseStepSize=repr(system.base_step))
    # Beside OSP's on the DefaultExperiment: OMSimulator refuses other annotations at the top.
    ours = ET.SubElement(ET.SubElement(experiment[0], _q("ssc", "Annotation"),
                                       type=AF_ANNOTATION), _q("af", "Cosim"))
    recording = ET.SubElement(ours, _q("af", "Recording"))
    if system.output_interval is not None:
        recording.set("interval", repr(system.output_interval))
    for signal in system.record:
        ET.SubElement(recording, _q("af", "Signal"), name=signal)
    for metric in system.metrics:
        ET.SubElement(ours, _q("af", "Metric"), name=metric.name, estimate=metric.estimate,
                      truth=metric.truth)
    return root


def write_ssp(system: SystemSpec, fmu_paths: dict[str, Path], path: Path) -> Path:
    """Write ``system`` as an SSP archive embedding its FMUs; return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, step_hints in (("SystemStructure.ssd", False), (OSP_SSD, True)):
            root = system_structure(system, fmu_paths, step_hints)
            ET.indent(root)
            archive.writestr(name, ET.tostring(root, encoding="UTF-8", xml_declaration=True))
        for fmu in sorted({c.fmu for c in system.components}):
            archive.write(fmu_paths[fmu], f"resources/{fmu}.fmu")
    return path


def _parameter_value(parameter: Any) -> Any:
    kind, text = parameter.type, parameter.value
    if kind == "Real":
        return float(text)
    if kind == "Integer":
        return int(text)
    if kind == "Boolean":
        return text.strip().lower() in ("true", "1")
    return text


@dataclass
class LoadedSystem:
    """A system read from an SSP archive, with its FMUs unpacked to a temporary folder that
    is removed with this object (or when the process exits)."""

    spec: SystemSpec
    fmu_paths: dict[str, Path]
    folder: ScratchFolder | None = field(default=None, repr=False)
    """Where the FMUs were unpacked (kept by copies made with ``dataclasses.replace``)."""


def read_ssp(path: Path) -> LoadedSystem:
    """Read and schema-validate an SSP archive written by :func:`write_ssp`."""
    path = Path(path)
    if path.is_dir():
        found = sorted(path.glob("*.ssp"))
        hint = f", such as {found[0]}" if found else ""
        raise UsageError(f"{path}: a folder; expected an SSP archive (a .ssp file){hint}")
    if not path.is_file():
        raise UsageError(f"{path}: no such file")
    try:
        ssd = read_ssd(str(path), validate=True)
        with zipfile.ZipFile(path) as archive:
            root = etree.fromstring(archive.read("SystemStructure.ssd"))
            folder = ScratchFolder("altfusion_ssp_")
            archive.extractall(folder.path, [n for n in archive.namelist()
                                        if n.startswith("resources/")])
    except (OSError, zipfile.BadZipFile, KeyError, etree.LxmlError, ValueError) as error:
        raise UsageError(f"{path}: not a valid SSP archive ({error})") from error
    system = ssd.system
    components, fmu_paths = [], {}
    for element in system.elements:
        hint = root.find(f"ssd:System/ssd:Elements/ssd:Component[@name='{element.name}']"
                         f"/ssd:Annotations/ssc:Annotation/osp:StepSizeHint", NS)
        params: dict[str, Any] = {}
        for binding in element.parameterBindings:
            for pset in binding.parameterValues:
                params.update({p.name: _parameter_value(p) for p in pset.parameters})
        step = params.pop("step_size", None)
        if hint is not None:
            step = float(hint.get("value"))
        if step is None:
            raise UsageError(f"{path}: component {element.name} has no step size")
        fmu = Path(element.source).stem
        fmu_paths[fmu] = folder.path / element.source
        if not fmu_paths[fmu].is_file():
            raise UsageError(f"{path}: component {element.name}: FMU {element.source} "
                             f"missing from the archive")
        components.append(ComponentSpec(element.name, fmu, float(step), params))
    connections = tuple(
        Connection(f"{c.startElement}.{c.startConnector}", f"{c.endElement}.{c.endConnector}")
        for c in system.connections
    )
    experiment = root.find("ssd:DefaultExperiment", NS)
    algorithm = experiment.find(".//osp:FixedStepAlgorithm", NS)
    ours = experiment.find(f"ssd:Annotations/ssc:Annotation[@type='{AF_ANNOTATION}']/af:Cosim",
                           NS)
    recording = ours.find("af:Recording", NS) if ours is not None else None
    interval = recording.get("interval") if recording is not None else None
    spec = SystemSpec(
        name=root.get("name"),
        description=system.description or "",
        components=tuple(components),
        connections=connections,
        stop_time=float(experiment.get("stopTime")),
        base_step=float(algorithm.get("baseStepSize")),
        start_time=float(experiment.get("startTime", 0.0)),
        output_interval=float(interval) if interval is not None else None,
        record=tuple(s.get("name") for s in recording.findall("af:Signal", NS))
        if recording is not None else (),
        metrics=tuple(Metric(m.get("name"), m.get("estimate"), m.get("truth"))
                      for m in ours.findall("af:Metric", NS)) if ours is not None else (),
    )
    return LoadedSystem(spec, fmu_paths, folder)
