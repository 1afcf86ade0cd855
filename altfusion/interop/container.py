"""Pack a subsystem of a system into one FMU: an FMU container of fmu-manipulation-toolbox.

The container embeds the members' FMUs (each under its component name), sets their parameters
(``step_size`` included) as start values, links them as the system does, and exposes

* an input ``component.variable`` for every member input driven from outside the subsystem;
* an output ``component.variable`` for every recorded member output and every member output
  that drives a component outside the subsystem (an output that also feeds another member is
  the container's local variable of the link instead, which the toolbox names
  ``component.variable`` with the component name in lower case).

The container steps its members one after the other ("sequential" mode) in our runner's
upstream-first order, so each member sees the outputs its upstream members just computed: the
same values our runner gives feedthrough inputs. Our runner gives the other inputs the value
latched at the start of the step; sequential stepping reproduces that only when such a link
runs against the order (the source steps after its consumer), which :func:`build_container`
checks. The container has a single internal step, so every member must have the same
``step_size``.

An FMU host such as fmpy sets the container's inputs at the start of each step: an input that
our runner would read at the end of the step (feedthrough) is therefore fed one row early by
:func:`input_table`.
"""

import graphlib
import logging
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from altfusion.cosim.instances import fmu_info
from altfusion.cosim.results import Results
from altfusion.systems.spec import SystemSpec
from altfusion.timegrid import TickClock

NUMPY_TYPES = {"Real": np.float64, "Integer": np.int32, "Boolean": np.bool_}


class ContainerError(ValueError):
    """The subsystem cannot be packed into a container that reproduces our runner."""


@dataclass(frozen=True)
class ContainerSpec:
    """A built container and how it is wired to the rest of its system."""

    path: Path
    step_size: float
    members: tuple[str, ...]
    """Member components in stepping order."""
    inputs: dict[str, str]
    """Container input ('component.variable') -> its source outside the subsystem."""
    input_types: dict[str, str]
    feedthrough_inputs: frozenset[str]
    """Inputs our runner reads at the end of the step (some output depends on them)."""
    outputs: tuple[str, ...]
    variables: dict[str, str]
    """Output ('component.variable') -> the container variable that carries it."""
    units: dict[str, str]


def _stepping_order(system: SystemSpec, members: list[str], infos) -> list[str]:
    graph = graphlib.TopologicalSorter({name: set() for name in members})
    for connection in system.connections:
        source, _, _ = connection.start.partition(".")
        target, _, variable = connection.end.partition(".")
        if (source in members and target in members
                and variable in infos[target].feedthrough_inputs):
            graph.add(target, source)
    index = {name: i for i, name in enumerate(members)}
    graph.prepare()
    order: list[str] = []
    while graph.is_active():
        ready = sorted(graph.get_ready(), key=index.__getitem__)
        order += ready
        graph.done(*ready)
    return order


def _start_value(value: Any) -> Any:
    if isinstance(value, bool):
        return value
    if isinstance(value, float):
        return repr(value)
    return str(value)


def build_container(system: SystemSpec, members: list[str], fmu_paths: dict[str, Path],
                    path: Path) -> ContainerSpec:
    """Build ``path`` (``<Name>.fmu``) holding the components ``members`` of ``system``."""
    from fmu_manipulation_toolbox.assembly import AssemblyNode

    specs = {c.name: c for c in system.components}
    unknown = [m for m in members if m not in specs]
    if unknown:
        raise ContainerError(f"{system.name} has no component(s) {unknown}")
    steps = {specs[m].step_size for m in members}
    if len(steps) != 1:
        raise ContainerError(f"members step at {sorted(steps)} s: a container has one "
                             f"internal step, give them the same step_size")
    step = steps.pop()
    infos = {m: fmu_info(fmu_paths[specs[m].fmu]) for m in members}
    order = _stepping_order(system, members, infos)
    rank = {name: i for i, name in enumerate(order)}
    path = Path(path)
    node = AssemblyNode(path.name, step_size=step, sequential=True, auto_link=False,
                        auto_input=False, auto_output=False)
    inputs, input_types, feedthrough, outputs, linked = {}, {}, set(), [], set()
    with tempfile.TemporaryDirectory(prefix="altfusion_container_") as work:
        work = Path(work)
        for name in order:
            shutil.copyfile(fmu_paths[specs[name].fmu], work / f"{name}.fmu")
            node.add_fmu(f"{name}.fmu")
            for parameter, value in {**specs[name].parameters, "step_size": step}.items():
                node.add_start_value(f"{name}.fmu", parameter, _start_value(value))
        for connection in system.connections:
            source, _, source_var = connection.start.partition(".")
            target, _, target_var = connection.end.partition(".")
            if target in rank and source in rank:
                if target_var not in infos[target].feedthrough_inputs \
                        and rank[source] < rank[target]:
                    raise ContainerError(
                        f"{connection.start} -> {connection.end}: our runner gives this input "
                        f"the value from the start of the step, but {source} steps before "
                        f"{target} in the container")
                node.add_link(f"{source}.fmu", source_var, f"{target}.fmu", target_var)
                linked.add(connection.start)
            elif target in rank:
                node.add_input(connection.end, f"{target}.fmu", target_var)
                inputs[connection.end] = connection.start
                input_types[connection.end] = infos[target].variables[target_var].type
                if target_var in infos[target].feedthrough_inputs:
                    feedthrough.add(connection.end)
            elif source in rank and connection.start not in outputs:
                outputs.append(connection.start)
        recorded = system.record or [  # no list: every output, as our runner records
            f"{m}.{v.name}" for m in order for v in infos[m].variables.values()
            if v.causality == "output" and v.type in ("Real", "Integer", "Boolean")]
        outputs += [s for s in recorded if s.partition(".")[0] in rank and s not in outputs]
        variables = {}
        for output in outputs:
            component, _, variable = output.partition(".")
            if output in linked:
                variables[output] = f"{component.lower()}.{variable}"
            else:
                node.add_output(f"{component}.fmu", variable, output)
                variables[output] = output
        toolbox_log = logging.getLogger("fmu_manipulation_toolbox")
        level = toolbox_log.level
        toolbox_log.setLevel(logging.ERROR)
        try:
            node.make_fmu(work)
        finally:
            toolbox_log.setLevel(level)
        path.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(work / path.name, path)
    units = {}
    for output in outputs:
        component, _, variable = output.partition(".")
        units[output] = infos[component].variables[variable].unit or ""
    return ContainerSpec(path, step, tuple(order), inputs, input_types,
                         frozenset(feedthrough), tuple(outputs), variables, units)


def input_table(container: ContainerSpec, driving: Results, stop_time: float) -> np.ndarray:
    """The container's inputs for fmpy's ``simulate_fmu``, from a run of the whole system.

    ``driving`` must hold every source of :attr:`ContainerSpec.inputs` on the container's
    step grid. Row n (t_n = n·step, as fmpy computes it) is applied before the step to
    t_(n+1): it carries the source at t_(n+1) for a feedthrough input, at t_n otherwise. fmpy
    also applies row 0 during initialization, so the container's initial outputs see the
    feedthrough inputs of t_1."""
    clock = TickClock(container.step_size, 0.0)
    steps = clock.ticks_in(stop_time, "stop_time")
    expected = np.array([clock.time(n) for n in range(steps + 1)])
    if len(driving.time) < steps + 1 or not np.allclose(driving.time[:steps + 1], expected,
                                                         rtol=0, atol=1e-9):
        raise ContainerError("the driving run must be recorded at every container step")
    names = list(container.inputs)
    dtype = [("time", np.float64)] + [(n, NUMPY_TYPES[container.input_types[n]]) for n in names]
    table = np.zeros(steps + 1, dtype=dtype)
    table["time"] = np.arange(steps + 1) * container.step_size
    for name in names:
        values = driving[container.inputs[name]][:steps + 1]
        if name in container.feedthrough_inputs:
            values = np.append(values[1:], values[-1])
        table[name] = values
    return table


def simulate_container(path: Path, step_size: float, stop_time: float, outputs: list[str],
                       units: dict[str, str] | None = None,
                       inputs: np.ndarray | None = None) -> Results:
    """Simulate a container FMU with fmpy's ``simulate_fmu``, one row per step.

    fmpy unloads the FMU's library when it finishes; pythonfmu does not survive being loaded
    again in the same process, so call this once per process (see ``python -m
    altfusion.interop simulate-fmu``)."""
    from fmpy import simulate_fmu

    result = simulate_fmu(str(path), stop_time=stop_time, step_size=step_size,
                          output_interval=step_size, output=list(outputs), input=inputs)
    columns = {name: np.asarray(result[name], dtype=float) for name in outputs}
    return Results(np.asarray(result["time"], dtype=float), columns, dict(units or {}))


def simulate_in_subprocess(container: ContainerSpec, stop_time: float,
                           inputs: np.ndarray | None = None, timeout: float = 900.0) -> Results:
    """:func:`simulate_container` in a fresh Python process."""
    import subprocess
    import sys

    with tempfile.TemporaryDirectory(prefix="altfusion_container_run_") as work:
        out = Path(work) / "results.csv"
        command = [sys.executable, "-m", "altfusion.interop", "simulate-fmu",
                   str(container.path), "--step", repr(container.step_size),
                   "--stop", repr(stop_time), "--csv", str(out)]
        command += [f"--output={container.variables[name]}" for name in container.outputs]
        if inputs is not None:
            np.save(Path(work) / "inputs.npy", inputs)
            command += ["--input", str(Path(work) / "inputs.npy")]
        completed = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        if completed.returncode != 0 or not out.exists():
            raise ContainerError(f"simulating {container.path.name} failed "
                                 f"({completed.returncode}):\n{completed.stdout[-3000:]}\n"
                                 f"{completed.stderr[-3000:]}")
        raw = Results.from_csv(out)
    columns = {name: raw[container.variables[name]] for name in container.outputs}
    return Results(raw.time, columns, dict(container.units))
