"""The multi-rate co-simulation runner on fmpy's FMU2Slave.

Timing: a fixed base step; every component has its own step, an integer multiple m of it.
Time is always computed from integer tick counts (``TickClock``), never accumulated.

Ordering: a component steps over (t_a, t_b] when the base clock reaches t_b. Its inputs come
from two kinds of connection, told apart by the FMU's ModelStructure output dependencies:

* feedthrough inputs (some output depends on them) take the source's value at t_b, so sources
  are stepped first: components are ordered upstream-first along these connections, and a
  cycle of them is an algebraic loop, reported;
* the other inputs (e.g. the thrust of the vertical dynamics, which only enters its state)
  take the source's value latched at t_a, the start of the step, and impose no order.

Thus a sensor samples the plant state of the same instant, an estimator fuses the sample of
that instant, and the loop through the plant is broken where the physics breaks it.

``master="jacobi"`` instead gives every input the value latched at the start of its
component's step, as the fixed-step masters of libcosim and ECOS do (all components step in
parallel, outputs are exchanged when a step ends). It is the reference those engines are
checked against (``altfusion.interop``): a feedthrough signal then arrives one base step late.

Recording: outputs as the components computed them, and inputs as the runner gave them to the
step that ended at the recorded time (a sample count an estimator saw, for ``altfusion
timing``).
"""

import copy
import graphlib
import math
import os
from dataclasses import dataclass, field
from operator import getitem
from pathlib import Path
from typing import Any

import numpy as np

from altfusion.cosim.instances import (
    FMI_TYPES,
    CoreInstance,
    CosimError,
    FmuInstance,
    fmu_info,
)
from altfusion.cosim.results import Results
from altfusion.errors import ParameterError
from altfusion.systems.spec import SystemSpec
from altfusion.timegrid import TickClock

__all__ = ["MASTERS", "CosimError", "RunInterruptedError", "Simulation", "recorded_columns",
           "recording_size", "simulate"]

MASTERS = ("ordered", "jacobi")
"""Master algorithms: ordered stepping (the default) and Jacobi (every input latched)."""


@dataclass
class _Link:
    """A resolved connection: source output cache slot -> destination input."""

    source: "_Stepped"
    kind: str
    slot: int
    end: str


@dataclass
class _Stepped:
    """Runtime data of one component."""

    name: str
    index: int
    instance: Any
    ratio: int
    parameters: dict[str, Any]
    output_names: dict[str, list[str]] = field(default_factory=dict)
    output_vrs: dict[str, list[int]] = field(default_factory=dict)
    linked_kinds: set[str] = field(default_factory=set)
    """Output types some connection reads (the others are only recorded)."""
    outputs: dict[str, Any] = field(default_factory=dict)
    feedthrough: list[tuple[str, int, _Link]] = field(default_factory=list)
    delayed: list[tuple[str, int, _Link]] = field(default_factory=list)

    def prepare_outputs(self) -> None:
        """Build the batched readers, one get call per type. Each reader fills one buffer
        that stays the same object, so the sources of inputs, latches and recordings are
        (buffer, slot) pairs resolved once."""
        self._linked_reads, self._recorded_reads = [], []
        for kind, vrs in self.output_vrs.items():
            read, self.outputs[kind] = self.instance.reader(kind, vrs)
            (self._linked_reads if kind in self.linked_kinds else self._recorded_reads).append(read)

    def prepare_inputs(self) -> None:
        """Build the batched writers, once every source's outputs are prepared, and the
        stepping function. Inputs are set in one call per type and source step: inputs from
        sources of one rate change together, so a slow sensor's held values are not sent
        again with a fast one's."""
        self._latch_sources = [link.source.source(link) for _, _, link in self.delayed]
        self._latched = [None] * len(self.delayed)
        inputs: dict[tuple[str, int], list[tuple[int, tuple[Any, int]]]] = {}
        latched_groups: set[tuple[str, int]] = set()
        for position, (kind, vr, link) in enumerate(self.delayed):
            inputs.setdefault((kind, link.source.ratio), []).append(
                (vr, (self._latched, position)))
            latched_groups.add((kind, link.source.ratio))
        for kind, vr, link in self.feedthrough:
            inputs.setdefault((kind, link.source.ratio), []).append(
                (vr, link.source.source(link)))
        self._writers = [(self.instance.writer(kind, [vr for vr, _ in entries]),
                          tuple(buffer for _, (buffer, _slot) in entries),
                          tuple(slot for _, (_buffer, slot) in entries))
                         for (kind, _ratio), entries in inputs.items()]
        self._writer_phases = self._phases([None if key in latched_groups else key[1]
                                            for key in inputs])
        self.step = self.instance.stepper()

    def _phases(self, source_ratios: list[int | None]) -> tuple[tuple[int, ...], ...]:
        """The writers worth checking at each of this component's steps, by phase
        ``(end // ratio) % len(phases)`` of the base tick ``end`` the step ends at.

        A writer fed straight by sources of ratio r (feedthrough) can only see new values if
        a source stepped since this component last set its inputs, in the base ticks
        (end - ratio, end]; otherwise its values are those already written, and comparing
        them again is skipped. A writer with latched inputs (None) is checked at every step.
        """
        period = math.lcm(self.ratio, *(r for r in source_ratios if r is not None))
        return tuple(
            tuple(index for index, r in enumerate(source_ratios)
                  if r is None or end // r != (end - self.ratio) // r)
            for end in range(0, period, self.ratio))

    def source(self, link: _Link) -> tuple[Any, int]:
        """The (buffer, slot) holding the output a link reads."""
        return self.outputs[link.kind], link.slot

    def input_source(self, path: str) -> tuple[Any, int] | None:
        """The (buffer, slot) holding the value input ``path`` was given in the last step:
        its latch, or its feedthrough source's output; None if no connection drives it."""
        for position, (_, _, link) in enumerate(self.delayed):
            if link.end == path:
                return self._latched, position
        for _, _, link in self.feedthrough:
            if link.end == path:
                return link.source.source(link)
        return None

    def refresh_outputs(self) -> None:
        """Read the outputs other components use (every step of this component)."""
        for read in self._linked_reads:
            read()

    def refresh_recorded(self) -> None:
        """Read the outputs that are only recorded (at output ticks)."""
        for read in self._recorded_reads:
            read()

    def latch(self) -> None:
        self._latched[:] = [buffer[slot] for buffer, slot in self._latch_sources]

    def apply_inputs(self) -> None:
        """Set the inputs, one call per writer; a writer whose values are all unchanged since
        the last call is not called again (an FMU keeps its inputs: fmi2Set* is only needed
        for a change, and sample-held sensor signals change at their own rate). The stepping
        loop does the same inline, checking only the writers of :meth:`_phases`."""
        written = self._written
        for index, (write, buffers, slots) in enumerate(self._writers):
            values = list(map(getitem, buffers, slots))
            if values != written[index]:
                write(values)
                written[index] = values

    def forget_inputs(self) -> None:
        """The instance was (re)initialized: its inputs are at their start values again."""
        self._written = [None] * len(self._writers)


class RunFailedError(CosimError):
    """A component failed during the run; ``results`` holds the rows recorded before."""

    def __init__(self, message: str, results: Results):
        super().__init__(message)
        self.results = results


class RunInterruptedError(RunFailedError):
    """The run was stopped by :meth:`Simulation.interrupt` (Ctrl-C); ``results`` holds the
    rows recorded before."""


class _InterruptRequestError(Exception):
    """Raised inside the stepping loop when an interruption was requested."""


class Simulation:
    """A system ready to run, repeatedly: instances are created once and reset between runs."""

    def __init__(self, system: SystemSpec, fmu_paths: dict[str, Path], backend: str = "fmu",
                 master: str = "ordered"):
        if backend not in ("fmu", "core"):
            raise ValueError(f"backend must be 'fmu' or 'core', not {backend!r}")
        if master not in MASTERS:
            raise ValueError(f"master must be one of {MASTERS}, not {master!r}")
        self.system = system
        self.backend = backend
        self.master = master
        self.base = TickClock(system.base_step, system.start_time, name="base_step")
        self._components: list[_Stepped] = []
        self._by_name: dict[str, _Stepped] = {}
        self._runs = 0
        self._interrupted = False
        instance_class = FmuInstance if backend == "fmu" else CoreInstance
        try:
            for index, spec in enumerate(system.components):
                info = fmu_info(fmu_paths[spec.fmu])
                ratio = self._ratio(spec.name, spec.step_size)
                stepped = _Stepped(spec.name, index, instance_class(spec.name, info), ratio,
                                   dict(spec.parameters))
                self._components.append(stepped)
                self._by_name[spec.name] = stepped
            self._recorded = self._resolve_recording()
            self._resolve_connections()
            self._order = self._step_order()
            if master == "jacobi":
                self._latch_every_input()
            for component in self._components:
                component.prepare_outputs()
            for component in self._components:
                component.prepare_inputs()
            self._record_sources = [self._record_source(path, stepped, kind, slot)
                                    for path, stepped, kind, slot, _ in self._recorded]
        except Exception:
            self.close()
            raise

    # ----------------------------------------------------------------- set-up
    def _ratio(self, name: str, step_size: float) -> int:
        try:
            return self.base.ticks_in(step_size, "step_size", allow_zero=False)
        except ParameterError:
            raise CosimError(
                f"component '{name}': step size {step_size!r} s is not a positive integer "
                f"multiple of the base step {self.system.base_step!r} s"
            ) from None

    def _variable(self, path: str):
        component, _, variable = path.partition(".")
        if component not in self._by_name:
            raise CosimError(f"'{path}': no component '{component}' in {self.system.name}")
        stepped = self._by_name[component]
        var = stepped.instance.info.variables.get(variable)
        if var is None:
            raise CosimError(f"'{path}': {stepped.instance.info.model_name} has no variable "
                             f"'{variable}'")
        return stepped, var

    def _output_slot(self, path: str) -> tuple[_Stepped, str, int]:
        stepped, var = self._variable(path)
        if var.causality != "output":
            raise CosimError(f"'{path}' is not an output")
        if var.type not in FMI_TYPES:
            raise CosimError(f"'{path}': {var.type} signals are not supported")
        names = stepped.output_names.setdefault(var.type, [])
        if var.name not in names:
            names.append(var.name)
            stepped.output_vrs.setdefault(var.type, []).append(var.value_reference)
        return stepped, var.type, names.index(var.name)

    def _resolve_recording(self) -> list[tuple[str, _Stepped, str, int, str]]:
        """(path, component, type, output slot, unit) of every recorded signal; an input's
        slot is -1 (its source is resolved with the connections: :meth:`_record_source`)."""
        paths = list(self.system.record)
        if not paths:
            paths = [f"{c.name}.{v.name}" for c in self._components
                     for v in c.instance.info.variables.values()
                     if v.causality == "output" and v.type in FMI_TYPES]
        recorded = []
        for path in paths:
            stepped, var = self._variable(path)
            if var.causality == "input":
                recorded.append((path, stepped, var.type, -1, var.unit or ""))
                continue
            stepped, kind, slot = self._output_slot(path)
            recorded.append((path, stepped, kind, slot, var.unit or ""))
        return recorded

    def _record_source(self, path: str, stepped: _Stepped, kind: str,
                       slot: int) -> tuple[Any, int]:
        """The (buffer, slot) a recorded signal is read from: an output's cache, or for an
        input the value the runner gives it (latched, or its feedthrough source's)."""
        if slot >= 0:
            return stepped.outputs[kind], slot
        source = stepped.input_source(path)
        if source is None:
            raise CosimError(f"'{path}': no connection drives this input; only connected "
                             f"inputs can be recorded")
        return source

    def _resolve_connections(self) -> None:
        driven: set[str] = set()
        for connection in self.system.connections:
            source, kind, slot = self._output_slot(connection.start)
            target, var = self._variable(connection.end)
            if var.causality != "input":
                raise CosimError(f"'{connection.end}' is not an input")
            if connection.end in driven:
                raise CosimError(f"input '{connection.end}' is driven by two connections")
            driven.add(connection.end)
            if var.type != kind:
                raise CosimError(f"cannot connect {kind} '{connection.start}' to {var.type} "
                                 f"'{connection.end}'")
            link = _Link(source, kind, slot, connection.end)
            source.linked_kinds.add(kind)
            entry = (var.type, var.value_reference, link)
            if var.name in target.instance.info.feedthrough_inputs:
                target.feedthrough.append(entry)
            else:
                target.delayed.append(entry)

    def _latch_every_input(self) -> None:
        """Jacobi: feedthrough inputs too take the value latched at the start of the step.

        Initialization keeps the upstream-first order: the engines iterate their connections
        in Initialization Mode until the initial values settle, which gives the same values."""
        for component in self._components:
            component.delayed += component.feedthrough
            component.feedthrough = []

    def _step_order(self) -> list[_Stepped]:
        graph = graphlib.TopologicalSorter()
        for component in self._components:
            graph.add(component.name, *{link.source.name for _, _, link in
                                        component.feedthrough})
        try:
            graph.prepare()
        except graphlib.CycleError as error:
            cycle = " -> ".join(error.args[1])
            raise CosimError(
                f"algebraic loop in {self.system.name}: {cycle} (each of these outputs depends "
                f"directly on the next one's; break the loop with a component whose outputs "
                f"do not depend on its inputs)"
            ) from None
        order = []
        while graph.is_active():
            ready = sorted(graph.get_ready(), key=lambda name: self._by_name[name].index)
            order += [self._by_name[name] for name in ready]
            graph.done(*ready)
        return order

    # ----------------------------------------------------------------- running
    def run(self, stop_time: float | None = None,
            parameters: dict[str, Any] | None = None) -> Results:
        """Simulate from the start time to ``stop_time`` (default: the system's)."""
        system = self.system
        stop = system.stop_time if stop_time is None else stop_time
        steps, every, rows = recording_size(system, stop, len(self._recorded))
        overrides = self._split_parameters(parameters or {})
        if self._runs:
            for component in self._components:
                component.instance.reset()
        for component in self._components:
            component.instance.warnings.clear()
        self._runs += 1
        self._initialize(stop, overrides)
        data = np.empty((rows, len(self._recorded)))
        times = np.full(rows, np.nan)
        self._record(data, times, 0, 0)
        try:
            self._loop(steps, every, data, times)
        except Exception as error:
            recorded = int(np.isfinite(times).sum())    # rows are recorded in order
            partial = self._results(times[:recorded], data[:recorded])
            if isinstance(error, _InterruptRequestError):
                self._interrupted = False
                raise RunInterruptedError(f"interrupted after t = {times[recorded - 1]:g} s",
                                          partial) from None
            raise RunFailedError(f"{error}", partial) from error
        for component in self._components:
            component.instance.terminate()
        return self._results(times, data)

    def interrupt(self) -> None:
        """Stop the run in progress (or the next one) after its current base step, as
        :class:`RunInterruptedError`: safe to call from a signal handler, unlike raising
        KeyboardInterrupt, which inside an FMU's Python code becomes its fmi2Fatal."""
        self._interrupted = True

    def _loop(self, steps: int, every: int, data: np.ndarray, times: np.ndarray) -> None:
        """The stepping loop of :meth:`run`, recording every ``every`` base steps.

        The same as, for each base tick: latch the delayed inputs of the components starting
        a step, then, upstream first, for each component ending a step at tick ``end``:
        :meth:`_Stepped.apply_inputs`, ``step``, :meth:`_Stepped.refresh_outputs`; with the
        calls inlined and only the writers whose sources may have changed compared."""
        tick_time = self.base.time
        t_previous = tick_time(0)
        latching = [(c.ratio, c.latch) for c in self._components if c.delayed]
        stepping = [(c.ratio, c._writer_phases, len(c._writer_phases), c._writers, c._written,
                     c.step, c._linked_reads) for c in self._order]
        recorded_only = [c.refresh_recorded for c in self._components if c._recorded_reads]
        for n in range(steps):
            if self._interrupted:
                raise _InterruptRequestError
            for ratio, latch in latching:
                if n % ratio == 0:
                    latch()
            end = n + 1
            t_end = tick_time(end)
            for ratio, phases, period, writers, written, step, linked_reads in stepping:
                if end % ratio:
                    continue
                for index in phases[end // ratio % period]:       # apply_inputs(), inlined
                    write, buffers, slots = writers[index]
                    values = list(map(getitem, buffers, slots))
                    if values != written[index]:
                        write(values)
                        written[index] = values
                t_start = t_previous if ratio == 1 else tick_time(end - ratio)
                step(t_start, t_end - t_start)
                for read in linked_reads:               # refresh_outputs(), inlined
                    read()
            t_previous = t_end
            if end % every == 0:
                for refresh_recorded in recorded_only:
                    refresh_recorded()
                self._record(data, times, end // every, end)

    def _results(self, times: np.ndarray, data: np.ndarray) -> Results:
        columns = {path: data[:, i] for i, (path, *_rest) in enumerate(self._recorded)}
        units = {path: unit for path, *_rest, unit in self._recorded}
        warnings = {c.name: copy.copy(c.instance.warnings) for c in self._components
                    if c.instance.warnings}
        return Results(times, columns, units, warnings)

    def _split_parameters(self, overrides: dict[str, Any]) -> dict[str, dict[str, Any]]:
        split: dict[str, dict[str, Any]] = {}
        for path, value in overrides.items():
            component, _, name = path.partition(".")
            if component not in self._by_name:
                raise CosimError(f"parameter '{path}': no component '{component}'")
            split.setdefault(component, {})[name] = value
        return split

    def _initialize(self, stop: float, overrides: dict[str, dict[str, Any]]) -> None:
        start = self.system.start_time
        for component in self._components:
            parameters = {**component.parameters, **overrides.get(component.name, {})}
            step = self.base.step_size * component.ratio
            component.instance.initialize(parameters, step, start, stop)
        for component in self._components:
            component.forget_inputs()
            component.refresh_outputs()
            component.refresh_recorded()
        # Upstream first: each component ends initialization with its inputs set from the
        # final initial outputs of its feedthrough sources.
        for component in self._order:
            component.latch()
            component.apply_inputs()
            component.instance.exit_initialization()
            component.refresh_outputs()
        for component in self._components:
            component.latch()

    def _record(self, data: np.ndarray, times: np.ndarray, row: int, tick: int) -> None:
        times[row] = self.base.time(tick)
        data[row] = [buffer[slot] for buffer, slot in self._record_sources]

    def close(self) -> None:
        """Free every FMU instance."""
        for component in self._components:
            component.instance.free()
        self._components.clear()

    def __enter__(self) -> "Simulation":
        return self

    def __exit__(self, *_exc) -> None:
        self.close()


def physical_memory() -> int:
    """This machine's memory in bytes (1 TiB where the system does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return 1 << 40


def _magnitude(count: int) -> str:
    """``count`` in three significant digits, however large (no float overflow)."""
    digits = str(count)
    return digits if len(digits) <= 4 else f"{digits[0]}.{digits[1:3]}e{len(digits) - 1}"


def recorded_columns(system: SystemSpec, fmu_paths: dict[str, Path]) -> int:
    """How many signals a run of ``system`` records: its ``record`` list, else every output
    (read from the modelDescriptions, no FMU instantiated)."""
    if system.record:
        return len(system.record)
    return sum(1 for c in system.components for v in fmu_info(fmu_paths[c.fmu]).variables.values()
               if v.causality == "output" and v.type in FMI_TYPES)


def recording_size(system: SystemSpec, stop: float, columns: int) -> tuple[int, int, int]:
    """``(base steps, base steps per recorded row, rows)`` of a run of ``system`` to ``stop``
    recording ``columns`` signals; a ParameterError naming ``stop_time`` when the table (the
    signals and the time, 8 bytes each) would exceed this machine's memory, before anything is
    allocated."""
    base = TickClock(system.base_step, system.start_time, name="base_step")
    steps = base.ticks_in(stop - system.start_time, "stop_time")
    every = base.ticks_in(system.output_interval or system.base_step, "output_interval",
                          allow_zero=False)
    rows = steps // every + 1
    size, memory = rows * (columns + 1) * 8, physical_memory()
    if size > memory:
        raise ParameterError("stop_time", stop, f"recording {_magnitude(rows)} rows of "
                             f"{columns} signals needs {_magnitude(size >> 30)} GiB, more "
                             f"than this machine's {memory >> 30} GiB of memory")
    return steps, every, rows


def simulate(system: SystemSpec, fmu_paths: dict[str, Path], backend: str = "fmu",
             stop_time: float | None = None, parameters: dict[str, Any] | None = None,
             master: str = "ordered") -> Results:
    """Build, run once and close a :class:`Simulation`."""
    with Simulation(system, fmu_paths, backend, master) as simulation:
        return simulation.run(stop_time, parameters)
