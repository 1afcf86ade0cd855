"""Run our SSP systems in third-party co-simulation engines; record them as our Results.

Engines (``ENGINES``):

* ``altfusion`` / ``altfusion-jacobi``: our runner, ordered stepping or Jacobi;
* ``libcosim``: the SSP through libcosimpy (``CosimExecution.from_ssp_file``); ``libcosim-osp``
  the exported ``OspSystemStructure.xml`` folder (:mod:`altfusion.interop.osp`);
* ``ecos``: the SSP through ecospy, in this process;
* ``ecos-proxy``: ECOS's command-line host (a C++ program with no Python of its own) with every
  FMU in its own ``proxyfmu`` process (:mod:`altfusion.interop.proxy`).

Stepping conventions (what makes the engines' trajectories differ from ours):

* libcosim and ECOS are Jacobi masters: every input holds the value its source had when the
  consumer's step started; our runner gives feedthrough inputs the source's value at the end
  of the step. ``altfusion-jacobi`` reproduces libcosim's convention exactly.
* A component slower than the base step is stepped at the start of its macro step by both
  engines. libcosim exchanges and observes its outputs when the macro step ends (as we do);
  ECOS exposes them at once, so between the slow component's steps ECOS shows (and feeds
  faster consumers) the values of the end of the current macro step. At multiples of the
  component's own step the values are the same.

Engines may unload and reload FMU libraries, which pythonfmu does not survive in one process:
:func:`run_in_subprocess` runs one engine in a fresh Python and reads back its CSV.
"""

import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from altfusion.cosim.instances import (
    FMI_TYPES,
    CoreInstance,
    CosimError,
    fmu_info,
    release_mapped_pythonfmu_state,
)
from altfusion.cosim.results import Results
from altfusion.cosim.runner import simulate
from altfusion.cosim.ssp import OSP_SSD, read_ssp
from altfusion.systems.spec import SystemSpec
from altfusion.timegrid import TickClock

ENGINES = ("altfusion", "altfusion-jacobi", "libcosim", "libcosim-osp", "ecos", "ecos-proxy")

SSP_PARAMETER_SET = "parameters"
"""Name of the parameter set our SSP writer binds to every component."""


class EngineError(RuntimeError):
    """A third-party engine refused the system or failed while running it."""


@dataclass(frozen=True)
class Signal:
    path: str
    component: str
    variable: str
    type: str
    unit: str


@dataclass(frozen=True)
class Recording:
    """What to record and when: the system's signals on its output grid."""

    signals: tuple[Signal, ...]
    every: int
    """Base steps between two recorded rows."""
    rows: int
    clock: TickClock

    @classmethod
    def of(cls, system: SystemSpec, fmu_paths: dict[str, Path],
           stop_time: float | None = None) -> "Recording":
        if system.start_time != 0.0:
            raise EngineError(f"{system.name}: third-party runs start at t = 0 s")
        infos = {c.name: fmu_info(fmu_paths[c.fmu]) for c in system.components}
        paths = list(system.record) or [
            f"{c.name}.{v.name}" for c in system.components
            for v in infos[c.name].variables.values()
            if v.causality == "output" and v.type in FMI_TYPES]
        signals = []
        for path in paths:
            component, _, variable = path.partition(".")
            var = infos[component].variables[variable]
            signals.append(Signal(path, component, variable, var.type, var.unit or ""))
        clock = TickClock(system.base_step, 0.0, name="base_step")
        stop = system.stop_time if stop_time is None else stop_time
        steps = clock.ticks_in(stop, "stop_time")
        every = clock.ticks_in(system.output_interval or system.base_step, "output_interval",
                               allow_zero=False)
        return cls(tuple(signals), every, steps // every + 1, clock)

    def results(self, rows: list[list[float]]) -> Results:
        data = np.asarray(rows, dtype=float)
        times = np.array([self.clock.time(n * self.every) for n in range(len(rows))])
        columns = {s.path: data[:, i] for i, s in enumerate(self.signals)}
        return Results(times, columns, {s.path: s.unit for s in self.signals})


# ---------------------------------------------------------------------------- our runner
def run_altfusion(ssp: Path, stop_time: float | None = None, master: str = "ordered") -> Results:
    loaded = read_ssp(ssp)
    return simulate(loaded.spec, loaded.fmu_paths, stop_time=stop_time, master=master)


# ---------------------------------------------------------------------------- libcosim
def _time_series(read, index: int, reference: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(step numbers, values) of the samples a time-series observer holds for a variable.

    libcosim reads a range of *steps* (a slower simulator has samples only at the steps it
    completes, and none at step 0), and libcosimpy 0.0.6 trims the result by counting step
    numbers equal to 0, which drops a genuine step-0 sample from a longer read: step 0 is read
    alone (a two-step range returns exactly it), then steps 1..steps."""
    _, first_step, first = read(index, reference, 0, 2)
    _, numbers, rest = read(index, reference, 1, steps)
    return (np.asarray([*first_step, *numbers], dtype=np.int64),
            np.asarray([*first, *rest], dtype=float))


def run_libcosim(source: Path, system: SystemSpec, fmu_paths: dict[str, Path],
                 stop_time: float | None = None) -> Results:
    """Run an ``.ssp`` archive or an OSP folder in libcosim, observing the recorded signals.

    Real and Integer signals come from a time-series observer (held between the steps of a
    slower simulator). It has no step-0 sample of a slower simulator: those initial values are
    read from a last-value observer after the first base step, which still shows the initial
    values of a simulator that has not completed a step. Boolean signals come from the
    last-value observer; for a simulator at the base step their t = 0 row is NaN.

    Parameters are checked first (:func:`reject_bad_parameters`): libcosim 0.0.6 aborts the
    process when an FMU's fmi2ExitInitializationMode returns fmi2Error."""
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level

    recording = Recording.of(system, fmu_paths, stop_time)
    reject_bad_parameters(system, fmu_paths)
    log_output_level(CosimLogLevel.WARNING)
    data = _libcosim_data(Path(source), system, recording)
    # The execution is gone (its instances freed while pythonfmu's state was whole); release
    # that state in the FMU libraries libcosim still maps before it may unload them
    # (release_mapped_pythonfmu_state). Released first, the instances freed afterwards kept
    # their Python objects: 8 slaves and ~3 MiB per execution of yang2020.
    release_mapped_pythonfmu_state()
    return recording.results(data)


def _libcosim_data(source: Path, system: SystemSpec, recording: Recording) -> list[list[float]]:
    """:func:`run_libcosim`'s recorded rows, from an execution that ends with this call."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver

    view = tempfile.TemporaryDirectory(prefix="altfusion_osp_view_")
    try:
        if source.is_dir() or source.suffix == ".xml":
            execution = CosimExecution.from_osp_config_file(str(source))
        else:
            ssd = osp_view(source, Path(view.name)) / "SystemStructure.ssd"
            execution = CosimExecution.from_ssp_file(str(ssd))
    except AssertionError as error:
        raise EngineError(f"libcosim cannot load {source}: {error}") from None
    # at least the one step that reads the initial values (a stop time within one output
    # interval records only t = 0; step(-1) would never return)
    steps = max((recording.rows - 1) * recording.every, 1)
    series = CosimObserver.create_time_series(buffer_size=steps + 1)
    last = CosimObserver.create_last_value()
    execution.add_observer(series)
    execution.add_observer(last)
    kinds = {"Real": CosimVariableType.REAL, "Integer": CosimVariableType.INTEGER,
             "Boolean": CosimVariableType.BOOLEAN}
    last_readers = {"Real": last.last_real_values, "Integer": last.last_integer_values,
                    "Boolean": last.last_boolean_values}
    slots = []
    for signal in recording.signals:
        index = execution.slave_index_from_instance_name(signal.component)
        if index is None:
            raise EngineError(f"libcosim: no simulator '{signal.component}' in {source}")
        var = {v.name.decode(): v for v in execution.slave_variables(index)}[signal.variable]
        if var.type != kinds[signal.type].value:
            raise EngineError(f"libcosim: {signal.path} is not of type {signal.type}")
        if signal.type != "Boolean":
            series.start_time_series(index, var.reference, kinds[signal.type])
        decimated = system.component(signal.component).step_size > system.base_step
        slots.append((signal.type, index, var.reference, decimated))

    def advance(count: int) -> None:
        if count and not execution.step(count):
            from libcosimpy._internal import get_last_error_message
            raise EngineError(f"libcosim step failed: {get_last_error_message()}")

    def last_value(kind: str, index: int, ref: int) -> float:
        return float(last_readers[kind](index, [ref])[0])

    data = np.full((recording.rows, len(slots)), np.nan)
    advance(1)
    initial = [last_value(kind, index, ref) if decimated else np.nan
               for kind, index, ref, decimated in slots]
    booleans = [i for i, slot in enumerate(slots) if slot[0] == "Boolean"]
    data[0, booleans] = [initial[i] for i in booleans]
    if booleans:
        advance(recording.every - 1)
        for row in range(1, recording.rows):
            data[row, booleans] = [last_value(*slots[i][:3]) for i in booleans]
            advance(recording.every if row < recording.rows - 1 else 0)
    else:
        advance(steps - 1)
    grid = np.arange(recording.rows) * recording.every
    readers = {"Real": series.time_series_real_samples,
               "Integer": series.time_series_integer_samples}
    for i, (kind, index, ref, decimated) in enumerate(slots):
        if kind == "Boolean":
            continue
        numbers, values = _time_series(readers[kind], index, ref, steps)
        if decimated and (numbers.size == 0 or numbers[0] != 0):
            numbers, values = np.insert(numbers, 0, 0), np.insert(values, 0, initial[i])
        if numbers[0] != 0 or np.any(np.diff(numbers) <= 0) or numbers[-1] > steps:
            raise EngineError(f"libcosim's time-series observer lost samples of "
                              f"{recording.signals[i].path}")
        data[:, i] = values[np.searchsorted(numbers, grid, side="right") - 1]
    return data.tolist()


# ---------------------------------------------------------------------------- ECOS
def osp_view(ssp: Path, folder: Path) -> Path:
    """``folder`` holding the archive ``ssp`` extracted, its OSP description (each
    component's step hint, :data:`~altfusion.cosim.ssp.OSP_SSD`) as ``SystemStructure.ssd``:
    from there libcosim and ECOS step each component at its own rate. Returns ``folder``."""
    with zipfile.ZipFile(ssp) as archive:
        archive.extractall(folder)
    (folder / OSP_SSD).replace(folder / "SystemStructure.ssd")
    return folder


def parameter_set_names(ssp: Path) -> set[str]:
    from lxml import etree

    with zipfile.ZipFile(ssp) as archive:
        root = etree.fromstring(archive.read("SystemStructure.ssd"))
    ssv = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    return {e.get("name") for e in root.iter(f"{{{ssv}}}ParameterSet")}


def reject_bad_parameters(system: SystemSpec, fmu_paths: dict[str, Path]) -> None:
    """Initialize every component's core object (no FMI) with its parameters; raise
    :class:`EngineError` naming the first one that refuses them.

    ECOS 0.7.2 ignores a doStep that returns fmi2Discard or fmi2Error: a component whose
    initialization failed would silently stop advancing; libcosim 0.0.6 aborts the process on
    the fmi2Error of its fmi2ExitInitializationMode. Components whose core class cannot
    be imported here (an FMU built from other sources) are not checked."""
    for spec in system.components:
        try:
            instance = CoreInstance(spec.name, fmu_info(fmu_paths[spec.fmu]))
        except (ImportError, AttributeError, CosimError):
            continue
        try:
            instance.initialize(dict(spec.parameters), spec.step_size, system.start_time,
                                system.stop_time)
        except CosimError as error:
            raise EngineError(str(error)) from None


def run_ecos(ssp: Path, system: SystemSpec, fmu_paths: dict[str, Path],
             stop_time: float | None = None) -> Results:
    """Run an ``.ssp`` archive in ECOS (ecospy), in this process (parameters are checked
    first: see :func:`reject_bad_parameters`)."""
    from ecospy import EcosLib, EcosSimulation

    recording = Recording.of(system, fmu_paths, stop_time)
    reject_bad_parameters(system, fmu_paths)
    EcosLib.set_log_level("warn")
    view = tempfile.TemporaryDirectory(prefix="altfusion_osp_view_")
    simulation = EcosSimulation(ssp_path=str(osp_view(ssp, Path(view.name))),
                                step_size=system.base_step)
    getters = {"Real": simulation.get_real, "Integer": simulation.get_integer,
               "Boolean": simulation.get_bool}
    slots = [(getters[s.type], f"{s.component}::{s.variable}") for s in recording.signals]
    try:
        names = parameter_set_names(ssp)
        if not simulation.init(
                parameter_set=SSP_PARAMETER_SET if SSP_PARAMETER_SET in names else None):
            raise EngineError(f"ECOS cannot initialize {ssp}: {EcosLib.get_last_error()}")

        def sample() -> list[float]:
            return [float(get(identifier)) for get, identifier in slots]

        rows = [sample()]
        for _ in range(recording.rows - 1):
            simulation.step(recording.every)
            rows.append(sample())
        simulation.terminate()
    finally:
        simulation.free()
        release_mapped_pythonfmu_state()        # after the instances, as in run_libcosim
    return recording.results(rows)


def ecos_divergent_components(system: SystemSpec) -> set[str]:
    """Components whose trajectories ECOS does not share with the Jacobi reference.

    ECOS hands a consumer the output of a slower component as soon as that component has
    stepped, i.e. its value at the end of the slow step under way; libcosim (and
    ``altfusion-jacobi``) hand it the value of the last completed slow step. Every component
    fed by such a slower-to-faster connection, directly or through other components, differs.
    """
    steps = {c.name: c.step_size for c in system.components}
    edges = [(c.start.partition(".")[0], c.end.partition(".")[0]) for c in system.connections]
    divergent = {target for source, target in edges if steps[source] > steps[target]}
    grown = True
    while grown:
        reached = {target for source, target in edges if source in divergent}
        grown = not reached <= divergent
        divergent |= reached
    return divergent


# ---------------------------------------------------------------------------- dispatch
def run_in_subprocess(engine: str, ssp: Path, stop_time: float | None = None,
                      osp: Path | None = None, timeout: float = 900.0) -> Results:
    """``run_engine`` of :mod:`altfusion.interop.__main__` in a fresh Python process (engines may
    unload FMU libraries)."""
    with tempfile.TemporaryDirectory(prefix="altfusion_engine_") as work:
        out = Path(work) / "results.csv"
        command = [sys.executable, "-m", "altfusion.interop", "run", "--engine", engine,
                   str(ssp), "--csv", str(out)]
        if stop_time is not None:
            command += ["--stop", repr(stop_time)]
        if osp is not None:
            command += ["--osp", str(osp)]
        completed = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        if completed.returncode != 0 or not out.exists():
            raise EngineError(f"{engine} run of {ssp} failed ({completed.returncode}):\n"
                              f"{completed.stdout[-3000:]}\n{completed.stderr[-3000:]}")
        return Results.from_csv(out)
