"""Export a system in the Open Simulation Platform's own format: ``OspSystemStructure.xml``.

The folder holds the XML and a copy of every FMU it names, so it can be handed to libcosim
(``cosim run``, libcosimpy's ``CosimExecution.from_osp_config_file``) as it is. Each simulator
carries its own ``stepSize`` (an integer multiple of ``BaseStepSize``) and its parameter values,
``step_size`` included, as ``InitialValues``. libcosim validates the file against its embedded
``OspSystemStructure.xsd`` (version 0.1) when it loads it.
"""

import shutil
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from fmpy import read_model_description

from altfusion.systems.spec import SystemSpec

OSP_NS = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
OSP_FILE = "OspSystemStructure.xml"


def _q(tag: str) -> str:
    return f"{{{OSP_NS}}}{tag}"


def _initial_value(parent: ET.Element, name: str, value: Any, fmi_type: str) -> None:
    element = ET.SubElement(parent, _q("InitialValue"), variable=name)
    if fmi_type == "Boolean":
        text = str(bool(value)).lower()
    elif fmi_type == "Real":
        text = repr(float(value))
    else:
        text = str(value)
    ET.SubElement(element, _q(fmi_type), value=text)


def osp_system_structure(system: SystemSpec, fmu_paths: dict[str, Path]) -> ET.Element:
    """The ``OspSystemStructure`` element of ``system``; FMUs are named ``<model>.fmu``."""
    ET.register_namespace("", OSP_NS)
    root = ET.Element(_q("OspSystemStructure"), version="0.1")
    ET.SubElement(root, _q("StartTime")).text = repr(system.start_time)
    ET.SubElement(root, _q("EndTime")).text = repr(system.stop_time)
    ET.SubElement(root, _q("BaseStepSize")).text = repr(system.base_step)
    ET.SubElement(root, _q("Algorithm")).text = "fixedStep"
    simulators = ET.SubElement(root, _q("Simulators"))
    types: dict[str, dict[str, str]] = {}
    for component in system.components:
        if component.fmu not in types:
            md = read_model_description(str(fmu_paths[component.fmu]))
            types[component.fmu] = {v.name: v.type for v in md.modelVariables}
        simulator = ET.SubElement(simulators, _q("Simulator"), name=component.name,
                                  source=f"{component.fmu}.fmu",
                                  stepSize=repr(component.step_size))
        values = ET.SubElement(simulator, _q("InitialValues"))
        for name, value in {**component.parameters, "step_size": component.step_size}.items():
            if name not in types[component.fmu]:
                raise KeyError(f"{component.name}: {component.fmu} has no variable '{name}'")
            _initial_value(values, name, value, types[component.fmu][name])
    connections = ET.SubElement(root, _q("Connections"))
    for connection in system.connections:
        link = ET.SubElement(connections, _q("VariableConnection"))
        for end in (connection.start, connection.end):
            simulator, _, variable = end.partition(".")
            ET.SubElement(link, _q("Variable"), simulator=simulator, name=variable)
    return root


def write_osp(system: SystemSpec, fmu_paths: dict[str, Path], folder: Path) -> Path:
    """Write ``folder/OspSystemStructure.xml`` and copy the system's FMUs beside it."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    root = osp_system_structure(system, fmu_paths)
    ET.indent(root)
    (folder / OSP_FILE).write_bytes(ET.tostring(root, encoding="UTF-8", xml_declaration=True))
    for fmu in sorted({c.fmu for c in system.components}):
        target = folder / f"{fmu}.fmu"
        source = Path(fmu_paths[fmu])
        if not target.exists() or target.read_bytes() != source.read_bytes():
            shutil.copyfile(source, target)
    return folder / OSP_FILE
