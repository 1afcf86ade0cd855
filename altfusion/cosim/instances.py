"""Component instances the runner steps: an FMU through fmpy, or the core object directly.

Both expose the same small interface (parameters, batched get/set by type, do_step, reset,
state), so the runner's orchestration is one piece of code and the direct backend gives the
reference result that the FMU run must reproduce.
"""

import atexit
import copy
import ctypes
import importlib
import itertools
import os
import shutil
import tempfile
import zipfile
from ctypes import byref
from dataclasses import dataclass, replace
from operator import attrgetter
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

import fmpy
from fmpy import calloc, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2Boolean,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2Integer,
    fmi2Real,
    fmi2ValueReference,
)

from altfusion.cosim.extraction import extracted_folder, file_sha256
from altfusion.cosim.results import Warnings
from altfusion.params import coerce
from altfusion.version import CORE_VERSION

FMI_TYPES = ("Real", "Integer", "Boolean")
_C_TYPES = {"Real": fmi2Real, "Integer": fmi2Integer, "Boolean": fmi2Boolean}
PY_TYPES = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
_GET_SET = ctypes.PYFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t,
                             ctypes.c_void_p)
"""fmi2Get*/fmi2Set*(component, value references, count, values) on addresses. The fast paths
call the FMU holding the GIL (PYFUNCTYPE): a pythonfmu FMU takes it at once anyway, and
releasing it to have it taken back costs a lock hand-over per call."""
_DO_STEP = ctypes.PYFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                             ctypes.c_int)
"""fmi2DoStep(component, current time, step, no-set-prior-state flag), holding the GIL."""


def _address(array: ctypes.Array) -> ctypes.c_void_p:
    """A pointer to ``array`` that keeps it alive (``cast`` holds a reference to it)."""
    return ctypes.cast(array, ctypes.c_void_p)


class CosimError(RuntimeError):
    """A co-simulation failure, naming the component and what it reported."""


@dataclass(frozen=True)
class Variable:
    name: str
    type: str
    causality: str
    value_reference: int
    unit: str | None


@dataclass(frozen=True)
class FmuInfo:
    """What the runner needs from one FMU file."""

    path: Path
    model_name: str
    guid: str
    core_version: str | None
    core_class: str | None
    variables: dict[str, Variable]
    feedthrough_inputs: frozenset[str]
    """Inputs read at the end of a step: our FMUs list them in their VendorAnnotation
    (``Core stepEndInputs``), another FMU's are the inputs its outputs depend on directly
    (ModelStructure dependencies)."""


_INFO_CACHE: dict[str, FmuInfo] = {}
"""By content (SHA-256), as FMUs are extracted (:mod:`altfusion.cosim.extraction`): one entry
per distinct FMU however many paths hold it (every campaign of an evaluation unpacks its own
copies: cached by path, a kept worker's cache grew by 0.22 MB per campaign), and an FMU
rebuilt at a path already read is read anew."""


def fmu_info(path: Path) -> FmuInfo:
    """Read (and cache) the modelDescription and our vendor annotation of an FMU."""
    path = Path(path).resolve()
    content = file_sha256(path)
    info = _INFO_CACHE.get(content)
    if info is None:
        info = _INFO_CACHE[content] = _read_info(path)
    return info if info.path == path else replace(info, path=path)


def _read_info(path: Path) -> FmuInfo:
    md = read_model_description(str(path))
    with zipfile.ZipFile(path) as archive:
        root = ET.fromstring(archive.read("modelDescription.xml"))
    core = root.find("VendorAnnotations/Tool[@name='altfusion']/Core")
    variables = {
        v.name: Variable(v.name, v.type, v.causality, v.valueReference, v.unit)
        for v in md.modelVariables
    }
    inputs = {v.name for v in md.modelVariables if v.causality == "input"}
    step_end = core.get("stepEndInputs") if core is not None else None
    if step_end is not None:
        feedthrough = set(step_end.split())
    else:
        feedthrough = set()
        for unknown in md.outputs:
            deps = unknown.dependencies
            feedthrough |= inputs if deps is None else {d.name for d in deps}
    return FmuInfo(
        path=path,
        model_name=md.modelName,
        guid=md.guid,
        core_version=core.get("version") if core is not None else md.version,
        core_class=core.get("class") if core is not None else None,
        variables=variables,
        feedthrough_inputs=frozenset(feedthrough & inputs),
    )


def check_core_version(info: FmuInfo) -> None:
    """Refuse to step an FMU's core in-process (:class:`CoreInstance`) when it was built from
    another core: this process's copy would run instead of the FMU's own."""
    if info.core_version != CORE_VERSION:
        raise CosimError(
            f"{info.path.name} was built from altfusion core {info.core_version}, but this "
            f"process runs core {CORE_VERSION}; stepping its core in-process would not run the "
            f"FMU's own code. Rebuild (python build_fmu.py) or run it through FMI"
        )


def _private_logger_proxy():
    """``addLoggerProxy`` of a private copy of fmpy's native logging library.

    fmpy's logger proxy (the C function that formats the variadic message before calling
    Python) keeps ONE Python callback per loaded library, and every ``fmpy.simulate_fmu`` or
    ``FMU2Slave`` with a logger replaces it, then lets its callback be freed: an instance of
    ours created earlier would log through a dangling pointer (a segfault when a user calls
    ``simulate_fmu`` between two runs of ours). A copy of the library loaded from a file of
    its own has its own static callback, which nobody else replaces (the file is removed once
    mapped, where the system allows it).
    """
    from fmpy import logging as fmpy_logging

    name = "logging" + fmpy.sharedLibraryExtension
    source = Path(fmpy_logging.library_dir) / fmpy.platform / name
    folder = tempfile.mkdtemp(prefix="altfusion-logger-")
    copy = Path(folder) / name
    shutil.copyfile(source, copy)
    library = ctypes.CDLL(str(copy))
    shutil.rmtree(folder, ignore_errors=True)
    add = library.addLoggerProxy
    add.argtypes, add.restype = [ctypes.c_void_p], None
    return add


class _LogRouter:
    """One FMI logger for the whole process, routing messages by instance name.

    Our logger proxy (:func:`_private_logger_proxy`) keeps a single Python callback, so
    per-instance callbacks would receive each other's messages.
    """

    def __init__(self):
        self.queues: dict[str, list[tuple[int, str]]] = {}
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._on_log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        _private_logger_proxy()(byref(self.callbacks))
        self._serial = itertools.count()

    def register(self, name: str) -> tuple[str, list[tuple[int, str]]]:
        """A unique instance name for ``name`` and the list its messages will go to."""
        unique = f"{name}#{next(self._serial)}"
        self.queues[unique] = []
        return unique, self.queues[unique]

    def _on_log(self, _env, instance, status, _category, message) -> None:
        queue = self.queues.get(instance.decode("utf-8", "replace"))
        if queue is not None:
            queue.append((int(status), message.decode("utf-8", "replace")))


_ROUTER: _LogRouter | None = None


def _router() -> _LogRouter:
    global _ROUTER
    if _ROUTER is None:
        _ROUTER = _LogRouter()
    return _ROUTER


_PYTHONFMU_LIBRARIES: dict[str, Any] = {}
"""The loaded pythonfmu libraries by the folder they were loaded from, whose Python state is
released at exit (see below)."""


def _release_pythonfmu_state() -> None:
    """Release pythonfmu's static Python state while the process is still intact.

    pythonfmu 0.7.0 keeps that state in a static ``std::shared_ptr``. At process exit the C++
    static destructors release it and then the library's unload hook assigns it again: a
    double release of freed memory, which now and then aborts the process ("corrupted
    double-linked list"). The hook's function, ``finalizePythonInterpreter``, is exported:
    calling it first, from a Python exit handler, releases the state once and leaves a null
    pointer, which both later releases handle. (In a Python host the state holds no
    interpreter: this only joins a finished thread.)
    """
    for library in _PYTHONFMU_LIBRARIES.values():
        library.finalizePythonInterpreter()
    _PYTHONFMU_LIBRARIES.clear()


def release_mapped_pythonfmu_state() -> None:
    """:func:`_release_pythonfmu_state` for every pythonfmu library mapped into this process,
    including those a third-party engine loaded itself (libcosim and ECOS open the FMUs'
    libraries without fmpy): each shared library in ``/proc/self/maps`` that exports
    ``finalizePythonInterpreter``. Register it with :mod:`atexit` in an engine's process."""
    _release_pythonfmu_state()
    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:                                   # not Linux: nothing to find this way
        return
    fields = (line.split(maxsplit=5) for line in maps.splitlines())
    for path in sorted({f[5] for f in fields if len(f) == 6 and f[5].endswith(".so")}):
        try:
            library = ctypes.CDLL(path, mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
        except OSError:
            continue
        finalize = getattr(library, "finalizePythonInterpreter", None)
        if finalize is not None:
            finalize()


def _track_library(folder: str, fmu: FMU2Slave) -> None:
    if folder in _PYTHONFMU_LIBRARIES or not hasattr(fmu.dll, "finalizePythonInterpreter"):
        return
    if not _PYTHONFMU_LIBRARIES:
        atexit.register(_release_pythonfmu_state)
    _PYTHONFMU_LIBRARIES[folder] = fmu.dll


class FmuInstance:
    """One FMU instance driven through fmpy's FMU2Slave, with its log messages collected."""

    def __init__(self, name: str, info: FmuInfo):
        self.name, self.info = name, info
        folder = extracted_folder(info.path)
        router = _router()
        self.instance_name, self.messages = router.register(name)
        self.warnings = Warnings()
        self.fmu = FMU2Slave(guid=info.guid, unzipDirectory=folder,
                             modelIdentifier=info.model_name, instanceName=self.instance_name)
        try:
            self.fmu.instantiate(callbacks=router.callbacks, loggingOn=True)
        except Exception as error:          # fmpy: "Failed to instantiate model"; the log why
            details = "\n".join(self.errors()) or str(error)
            router.queues.pop(self.instance_name, None)
            raise CosimError(f"component '{name}': {details}") from None
        self._component = ctypes.c_void_p(self.fmu.component)
        _track_library(folder, self.fmu)

    def errors(self) -> list[str]:
        """Messages logged at fmi2Error severity or worse since the last call; clears them.

        Warnings move to :attr:`warnings` (bounded to ``MAX_WARNINGS``)."""
        found = [m for s, m in self.messages if s >= 3]
        self.warnings.keep([m for s, m in self.messages if 0 < s < 3])
        self.messages.clear()
        return found

    def _call(self, what: str, function, *args) -> Any:
        try:
            result = function(*args)
        except FMICallException as error:
            details = "\n".join(self.errors()) or f"{what} failed: {error}"
            raise CosimError(f"component '{self.name}': {details}") from None
        if self.messages:
            self._raise_logged_errors(what)
        return result

    def _raise_logged_errors(self, what: str) -> None:
        errors = self.errors()
        if errors:
            raise CosimError(f"component '{self.name}' ({what}): " + "\n".join(errors))

    def _check_status(self, status: int, what: str) -> None:
        """Status handling of the fast paths (raw calls, no fmpy wrapper)."""
        if status > 1:
            details = "\n".join(self.errors()) or f"{what} failed with status {status}"
            raise CosimError(f"component '{self.name}': {details}")
        if self.messages:
            self._raise_logged_errors(what)

    def _raw(self, name: str, prototype):
        """The FMI function ``name`` of this FMU's library with our ``prototype`` instead of
        fmpy's, whose array arguments go through ``from_param`` at every call (the fast paths
        pass plain addresses of buffers that live as long as their closures)."""
        return prototype(ctypes.cast(getattr(self.fmu.dll, name), ctypes.c_void_p).value)

    def reader(self, kind: str, vrs: list[int]):
        """A function reading the current values of ``vrs`` into a reused ctypes buffer (and
        returning it), and that buffer."""
        function = self._raw(f"fmi2Get{kind}", _GET_SET)
        refs = (fmi2ValueReference * len(vrs))(*vrs)
        buffer = (_C_TYPES[kind] * len(vrs))()
        component, count, check = self._component, ctypes.c_size_t(len(vrs)), self._check_status
        refs_address, buffer_address = _address(refs), _address(buffer)
        messages = self.messages

        def read():
            status = function(component, refs_address, count, buffer_address)
            if status or messages:
                check(status, f"get{kind}")
            return buffer

        return read, buffer

    def writer(self, kind: str, vrs: list[int]):
        """A function setting ``vrs`` to a sequence of values (reused ctypes buffers)."""
        function = self._raw(f"fmi2Set{kind}", _GET_SET)
        refs = (fmi2ValueReference * len(vrs))(*vrs)
        buffer = (_C_TYPES[kind] * len(vrs))()
        component, count, check = self._component, ctypes.c_size_t(len(vrs)), self._check_status
        refs_address, buffer_address = _address(refs), _address(buffer)
        messages = self.messages

        def write(values):
            buffer[:] = values
            status = function(component, refs_address, count, buffer_address)
            if status or messages:
                check(status, f"set{kind}")

        return write

    def stepper(self):
        """A function doing fmi2DoStep(t, h) without fmpy's per-call bookkeeping."""
        function = self._raw("fmi2DoStep", _DO_STEP)
        component, check, messages = self._component, self._check_status, self.messages

        def step(time: float, step: float) -> None:
            status = function(component, time, step, 1)
            if status or messages:
                check(status, f"doStep(t = {time!r} s, h = {step!r} s)")

        return step

    def initialize(self, parameters: dict[str, Any], step_size: float, start_time: float,
                   stop_time: float) -> None:
        values = {**parameters, "step_size": step_size}
        self._call("setupExperiment", self.fmu.setupExperiment, None, start_time, stop_time)
        for name, value in values.items():
            var = self.info.variables.get(name)
            if var is None or var.causality != "parameter":
                raise CosimError(f"component '{self.name}' ({self.info.model_name}) has no "
                                 f"parameter '{name}'")
            self.set(var.type, [var.value_reference], [PY_TYPES[var.type](value)])
        self._call("enterInitializationMode", self.fmu.enterInitializationMode)

    def exit_initialization(self) -> None:
        self._call("exitInitializationMode", self.fmu.exitInitializationMode)

    def get(self, kind: str, vrs: list[int]) -> list[Any]:
        getter = {"Real": self.fmu.getReal, "Integer": self.fmu.getInteger,
                  "Boolean": self.fmu.getBoolean}[kind]
        return self._call(f"get{kind}", getter, vrs)

    def set(self, kind: str, vrs: list[int], values: list[Any]) -> None:
        setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                  "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[kind]
        self._call(f"set{kind}", setter, vrs, values)

    def do_step(self, time: float, step: float) -> None:
        self._call(f"doStep(t = {time!r} s, h = {step!r} s)", self.fmu.doStep, time, step)

    def reset(self) -> None:
        self._call("reset", self.fmu.reset)

    def get_state(self) -> Any:
        return self._call("getFMUstate", self.fmu.getFMUstate)

    def set_state(self, state: Any) -> None:
        self._call("setFMUstate", self.fmu.setFMUstate, state)

    def terminate(self) -> None:
        self._call("terminate", self.fmu.terminate)

    def free(self) -> None:
        """Free the instance but keep the shared library loaded: unloading pythonfmu's library
        tears down its embedded-Python state, and loading it again crashes the process."""
        self.fmu.fmi2FreeInstance(self.fmu.component)
        _router().queues.pop(self.instance_name, None)


class CoreInstance:
    """The core object behind an FMU, stepped directly in Python (no FMI)."""

    def __init__(self, name: str, info: FmuInfo):
        if info.core_class is None:
            raise CosimError(f"{info.path.name} names no altfusion core class")
        check_core_version(info)
        module, qualname = info.core_class.split(":")
        self.core_class = getattr(importlib.import_module(module), qualname)
        self.name, self.info = name, info
        self._by_ref = {v.value_reference: v for v in info.variables.values()}
        self.resources = str(Path(extracted_folder(info.path)) / "resources")
        self.core = self.core_class()
        self.warnings = Warnings()

    def initialize(self, parameters: dict[str, Any], step_size: float, start_time: float,
                   stop_time: float) -> None:
        params = self.core_class.Params()
        for key, value in parameters.items():
            try:
                params = replace(params, **{key: coerce(type(params), key, value)})
            except KeyError as error:
                raise CosimError(f"component '{self.name}': {error}") from None
        self._setup = (params, step_size, start_time)
        self.exit_initialization()

    def exit_initialization(self) -> None:
        """Rebuild the core from the parameters and the inputs set so far, as the FMU does."""
        params, step_size, start_time = self._setup
        inputs = {name: getattr(self.core, name) for name, v in self.info.variables.items()
                  if v.causality == "input"}
        try:
            self.core = self.core_class(params, step_size=step_size, start_time=start_time,
                                        inputs=inputs, resources=self.resources)
        except Exception as error:
            raise CosimError(f"component '{self.name}': initialization failed: {error}") from None

    def get(self, kind: str, vrs: list[int]) -> list[Any]:
        return [getattr(self.core, self._by_ref[vr].name) for vr in vrs]

    def set(self, kind: str, vrs: list[int], values: list[Any]) -> None:
        for vr, value in zip(vrs, values, strict=True):
            setattr(self.core, self._by_ref[vr].name, PY_TYPES[kind](value))

    def reader(self, kind: str, vrs: list[int]):
        """Like :meth:`FmuInstance.reader`; the buffer is a list."""
        names = [self._by_ref[vr].name for vr in vrs]
        buffer: list[Any] = [None] * len(names)
        values = attrgetter(*names) if len(names) > 1 else lambda core: (getattr(core, names[0]),)

        def read():
            buffer[:] = values(self.core)
            return buffer

        return read, buffer

    def writer(self, kind: str, vrs: list[int]):
        names = [self._by_ref[vr].name for vr in vrs]
        convert = PY_TYPES[kind]

        def write(values):
            core = self.core
            for name, value in zip(names, values, strict=True):
                setattr(core, name, convert(value))

        return write

    def stepper(self):
        return self.do_step

    def do_step(self, time: float, step: float) -> None:
        core = self.core
        try:
            core.do_step(time, step)
        except Exception as error:
            raise CosimError(f"component '{self.name}': doStep(t = {time!r} s) failed: "
                             f"{error}") from error
        notes = core.take_notes()
        if notes:
            self.warnings.keep(notes)

    def reset(self) -> None:
        self.core = self.core_class()

    def get_state(self) -> Any:
        return copy.deepcopy(self.core)

    def set_state(self, state: Any) -> None:
        self.core = copy.deepcopy(state)

    def terminate(self) -> None:
        pass

    def free(self) -> None:
        pass
