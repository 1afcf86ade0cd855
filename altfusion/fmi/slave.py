"""The adapter base of every FMU: units, state, logging, errors and modelDescription extras.

A slave script in ``fmu_src/`` subclasses :class:`CoreSlave`, names its core class and declares
its inputs and outputs; the parameters are the fields of the core's ``Params`` dataclass (with
their units, descriptions and bounds) plus ``step_size``. Inputs, outputs and parameters map by
name onto the core object, which is rebuilt from the parameters when initialization ends.

FMI behaviour that pythonfmu 0.7.0 leaves to us:

* No exception escapes an FMI call. It is logged with its traceback at fmi2Error severity
  (``%`` escaped, since the host formats the message). ``doStep`` then returns fmi2Discard;
  pythonfmu maps any escaping exception to fmi2Fatal and gives Python code no other way to
  return an error status, so a failed initialization (a bad parameter) is logged and every
  later ``doStep`` returns fmi2Discard with the reason. The native shim
  (:mod:`altfusion.fmi.shim`) returns the worst status logged during a call, so with it
  such calls return fmi2Error. A refused request of the host's (a parameter value out of its
  bounds, a doStep not starting where the last one ended, a step not positive and finite or
  running more than :data:`~altfusion.timegrid.MAX_TICKS_PER_STEP` ticks) is logged by its
  message alone, without a traceback.
* Parameters are ``fixed``: the core is built from them when initialization ends, so setting
  one once the instance steps is refused (fmi2Error naming it and the value it keeps); a
  host's tuning would otherwise read back a value the core does not run on.
* The FMU state is the whole core object (filter state, random generators, tick clock), deep
  copied on get and set. Serialized, it is data, never code (:mod:`altfusion.fmi.state`): a
  header naming the model, GUID and core version, then a tagged JSON tree. pythonfmu turns
  any exception of ``_fmu_state_from_bytes`` or ``_set_fmu_state`` into fmi2Fatal and drops
  the instance's Python objects, so a refused state is not an exception: deserializing
  returns a :class:`~altfusion.fmi.state.RefusedState` carrying the reason, which the native
  shim (:mod:`altfusion.fmi.shim`) reads: it frees the state and returns fmi2Error with the
  reason. Setting one anyway (pythonfmu's win64 binary) logs the reason at fmi2Error severity
  and leaves the instance as it was.
* The GUID is a digest of the interface (:mod:`altfusion.fmi.guid`): every variable's value
  reference, name, type, causality, variability, unit, bounds and start value, the slave
  script's source and the core version.
* pythonfmu 0.7.0 re-executes the slave script at each instantiation, releases a reference
  to the module's dict it does not own and keeps a list referring to every class it finds;
  the metaclass :class:`~altfusion.fmi.reexec.ReusedSlaveClass` balances the release and
  hands back the existing class so that nothing new is kept (see that module).
* Any communication step is taken (``canHandleVariableCommunicationStepSize``): the core ticks
  on its own step, ``step_size`` (:mod:`altfusion.timegrid`), running every tick that falls
  within the host's step. ``step_size`` 0 (the default) adopts a tick at the first doStep:
  until then the core runs on the default experiment's step (initial outputs), and the first
  doStep rebuilds the not yet stepped core on the host's step if the parameters fit it (every
  sample period a multiple), else on the default step or the core's own natural step.
* The modelDescription gets UnitDefinitions, per-variable units and bounds, the outputs'
  dependencies (none: outputs change only in doStep), InitialUnknowns with the inputs each
  initial value follows, and a VendorAnnotation with the core version, the core class and the
  inputs read at the end of a step (its ``stepEndInputs``,
  :class:`~altfusion.fmi.variables.Output`).
* The native shim reads every variable (strings included) and sets the inputs itself while
  the instance steps, and calls :meth:`CoreSlave.do_step` without pythonfmu's bridge: each
  instance offers itself in the slot the shim leaves in ``sys`` (:data:`SHIM_SLOTS`) and
  names, by value reference, the attributes the shim may read and write
  (:meth:`CoreSlave._native_names`: the inputs, outputs and parameters, read as the accessors
  below read them; the inputs set).
* In Initialization Mode, outputs follow the parameters and inputs set so far: a set marks the
  core stale and the next get rebuilds it. Importers may set parameters after
  ``enterInitializationMode`` (ECOS applies the SSP parameter set there) and then iterate their
  connections (libcosim, ECOS) until the initial values settle.
"""

import contextlib
import copy
import sys
import threading
import traceback
from collections.abc import Callable
from dataclasses import replace
from operator import attrgetter
from pathlib import Path
from typing import Any, ClassVar
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Boolean, Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real, String
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Status

from altfusion.component import DEFAULT_STEP_SIZE, Component
from altfusion.errors import ParameterError, StepError
from altfusion.fmi import state as fmu_state
from altfusion.fmi.bundle import public_module
from altfusion.fmi.guid import interface_guid
from altfusion.fmi.reexec import ReusedSlaveClass, drop_repeated_path_entry
from altfusion.fmi.variables import Input, Output
from altfusion.params import ParamInfo, coerce, param_infos
from altfusion.units import BASE_UNITS
from altfusion.version import CORE_VERSION

VENDOR_TOOL = "altfusion"

ADOPT_FIRST_STEP = 0.0
"""``step_size`` value meaning: the step of the first doStep (see ``CoreSlave._adopt_step``)."""

MIN_ADOPTED_STEP = 1e-4
"""Shortest first doStep adopted as the tick, s: a shorter one (a host's tiny remainder step)
would make every later step run thousands of ticks."""

STEP_SIZE = ParamInfo(
    name="step_size",
    type=float,
    default=ADOPT_FIRST_STEP,
    unit="s",
    description="Internal step (tick) of this instance: samples, filter steps and outputs fall "
                "on its multiples, whatever the host's communication steps; 0 (default): the "
                "first doStep's step if the parameters fit it, else 0.01 s",
    min=0.0,
    max=None,
    positive=False,
)

_FMI_TYPES = {float: Real, int: Integer, bool: Boolean, str: String}
_PY_TYPES = {fmi: python for python, fmi in _FMI_TYPES.items()}

SHIM_SLOTS = "_altfusion_fmi2_shim_slaves_v1"
"""The dict in ``sys`` where the native shim leaves a slot (None, keyed by the thread) for the
slave object pythonfmu is making (``altfusion/fmi/shim/fmi2_shim.c``, "direct access")."""

_NATIVE_TYPES = (Real, Integer, Boolean, String)
"""The FMI types the native shim reads (and, but strings, writes) directly, in its order."""

_CORE, _PARAMETERS, _SLAVE = 0, 1, 2
"""Whose attribute a variable's value is (:meth:`CoreSlave._home`; the native shim's CORE,
PARAMETERS, SLAVE)."""

MAX_CACHED_BATCHES = 256
"""Accessors kept per instance for distinct lists of value references (then made anew)."""


def unit_definitions(units: set[str]) -> Element:
    """A <UnitDefinitions> element for the given unit names (KeyError if one is unknown)."""
    element = Element("UnitDefinitions")
    for name in sorted(units):
        unit = SubElement(element, "Unit", {"name": name})
        SubElement(unit, "BaseUnit", {k: str(v) for k, v in BASE_UNITS[name].items()})
    return element


def _value_getter(label: str, kind: type, fallback: Any) -> Callable[..., list]:
    """The slave's ``get_<type>`` method (pythonfmu calls it by name at every fmi2Get*): the
    values of a list of value references, read by the one accessor kept for that list; on an
    error ``fallback`` for each, logged as ``label``. A method of its own per type, not a
    call to a shared one: one Python frame less on the hottest path of an importer."""

    def get(self: "CoreSlave", vrs) -> list:
        if self._initializing and self._stale:
            self._refresh_initial_outputs()
        try:
            cache = self._readers[kind]
            read = cache.get(tuple(vrs)) or self._new_batch(cache, self._build_reader, kind, vrs)
            return read()
        except Exception:
            self._log_exception(label)
            return [fallback] * len(vrs)

    return get


def _value_setter(label: str, kind: type) -> Callable[..., None]:
    """The slave's ``set_<type>`` method, as :func:`_value_getter` (errors logged as
    ``label``)."""

    def set_values(self: "CoreSlave", vrs, values) -> None:
        try:
            cache = self._writers[kind]
            write = cache.get(tuple(vrs)) or self._new_batch(cache, self._build_writer, kind, vrs)
            write(values)
        except Exception:
            self._log_exception(label)

    return set_values


class CoreSlave(Fmi2Slave, metaclass=ReusedSlaveClass):
    """pythonfmu slave that exposes one core :class:`~altfusion.component.Component`."""

    core_class: ClassVar[type[Component]]
    variables: ClassVar[tuple[Input | Output, ...]] = ()
    author = "altfusion contributors"
    license = "MIT"
    version = CORE_VERSION

    def __init__(self, **kwargs: Any):
        super().__init__(**kwargs)
        drop_repeated_path_entry(self.resources)
        self.modelName = type(self).__name__
        self.description = " ".join((type(self).__doc__ or "").strip().split("\n\n")[0].split())
        self.default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=None, step_size=DEFAULT_STEP_SIZE
        )
        self._params = self.core_class.Params()
        self._step_size = ADOPT_FIRST_STEP
        self._start_time = 0.0
        self._failure: str | None = None
        self._initializing = False
        self._stale = False
        self._stepping = False
        self.core = self.core_class()
        for info in self.parameter_infos():
            self._register(info.name, info.type, Fmi2Causality.parameter, Fmi2Variability.fixed,
                           info.description, getter=self._getter(info.name),
                           setter=self._param_setter(info.name))
        for var in self.variables:
            causality = Fmi2Causality.input if isinstance(var, Input) else Fmi2Causality.output
            continuous = var.type is float
            variability = Fmi2Variability.continuous if continuous else Fmi2Variability.discrete
            setter = self._input_setter(var) if isinstance(var, Input) else None
            self._register(var.name, var.type, causality, variability, var.description,
                           getter=self._getter(var.name), setter=setter)
        self._getters, self._setters = {}, {}
        for kind in _FMI_TYPES.values():
            self._getters[kind], self._setters[kind] = self._accessors(kind)
        self._readers: dict[type, dict[tuple[int, ...], Any]] = {k: {} for k in self._getters}
        self._writers: dict[type, dict[tuple[int, ...], Any]] = {k: {} for k in self._getters}
        self.guid = self._class_guid()
        self._offer_to_shim()

    def _offer_to_shim(self) -> None:
        """Fill the slot the native shim left for this thread's new slave, if it left one."""
        slots = getattr(sys, SHIM_SLOTS, None)
        thread = threading.get_ident()
        if isinstance(slots, dict) and thread in slots and slots[thread] is None:
            slots[thread] = self

    def _native_names(self) -> tuple[tuple[tuple[tuple[int, str] | None, ...], ...], ...]:
        """For the native shim: per way (read, write) and FMI type (Real, Integer, Boolean,
        String), by value reference, where it may read or set the value directly
        (:meth:`_home`: the getters read every variable there), None for nowhere. Only inputs
        are set directly (parameters go through their checked setters, in Initialization
        Mode); the shim sets no strings."""
        size = max(self.vars, default=-1) + 1
        inputs = {v.name for v in self.variables if isinstance(v, Input)}

        def table(kind: type, write: bool) -> tuple[tuple[int, str] | None, ...]:
            homes: list[tuple[int, str] | None] = [None] * size
            for vr, var in self.vars.items():
                if isinstance(var, kind) and (not write or var.name in inputs):
                    homes[vr] = self._home(var.name)
            return tuple(homes)

        return tuple(tuple(table(kind, write) for kind in _NATIVE_TYPES)
                     for write in (False, True))

    def _class_guid(self) -> str:
        """The GUID of this FMU's interface, computed from the first (fresh) instance of the
        class and kept on the class: states are checked against it by class methods."""
        cls = type(self)
        if "_guid" not in cls.__dict__:
            units = self._declared_units_and_bounds()
            cls._guid = interface_guid(self.modelName, self.vars.values(), units,
                                       self._slave_script(), CORE_VERSION)
        return cls._guid

    def _slave_script(self) -> Path | None:
        """The file of the slave script: in an FMU, the copy in this instance's resources (the
        module pythonfmu imported may come from another, since deleted, extraction folder)."""
        name = f"{type(self).__module__.rpartition('.')[2]}.py"
        if self.resources and Path(self.resources, name).is_file():
            return Path(self.resources, name)
        path = getattr(sys.modules.get(type(self).__module__), "__file__", None)
        return Path(path) if path else None

    # ----------------------------------------------------------------- declarations
    @classmethod
    def parameter_infos(cls) -> list[ParamInfo]:
        """The FMU's parameters: the core's Params fields, then ``step_size``."""
        return [*param_infos(cls.core_class.Params), STEP_SIZE]

    def _register(self, name, value_type, causality, variability, description, getter, setter):
        fmi_type = _FMI_TYPES[value_type]
        self.register_variable(
            fmi_type(name, causality=causality, variability=variability, description=description,
                     getter=getter, setter=setter)
        )

    def _home(self, name: str) -> tuple[int, str]:
        """Where variable ``name``'s value lives, as (owner, attribute): an input or output on
        the core, ``step_size`` on this slave, another parameter in the parameter set."""
        if name == STEP_SIZE.name:
            return _SLAVE, "_step_size"
        if any(var.name == name for var in self.variables):
            return _CORE, name
        return _PARAMETERS, name

    def _owner(self, code: int) -> Any:
        """The object of :meth:`_home`'s owner ``code``."""
        return self.core if code == _CORE else self._params if code == _PARAMETERS else self

    def _getter(self, name: str):
        code, attribute = self._home(name)
        return lambda: getattr(self._owner(code), attribute)

    def _param_setter(self, name: str):
        """The setter of parameter ``name``: its value checked when initialization ends; once
        the instance steps, refused (variability fixed: the core was built from it)."""
        current = self._getter(name)

        def set_value(value: Any) -> None:
            if self._stepping:
                raise ParameterError(name, value, "fixed, it can be set before "
                                     "exitInitializationMode only; the instance keeps "
                                     f"{current()!r}")
            if name == STEP_SIZE.name:
                self._step_size = float(value)
            else:
                self._params = replace(self._params, **{name: coerce(type(self._params), name,
                                                                     value)})
            self._stale = self._initializing
        return set_value

    def _input_setter(self, var: Input):
        def set_value(value: Any) -> None:
            setattr(self.core, var.name, var.type(value))
            self._stale = self._initializing
        return set_value

    # ----------------------------------------------------------------- logging
    def _log(self, status: Fmi2Status, message: str) -> None:
        """Log to the host; '%' is escaped because hosts format the message printf-style."""
        self.log(message.replace("%", "%%"), status)

    def _log_exception(self, where: str) -> None:
        """Log the exception being handled at fmi2Error severity: a refused request of the
        host's (a bad parameter value, a step the component cannot take) by its message, any
        other with its traceback."""
        error = sys.exc_info()[1]
        if isinstance(error, ParameterError | StepError):
            self._log(Fmi2Status.error, f"{where} refused: {error}")
            return
        self._log(Fmi2Status.error, f"{where} failed: {type(error).__name__}: {error}\n"
                                    f"{traceback.format_exc()}")

    # ----------------------------------------------------------------- life cycle
    def _rebuild_core(self) -> None:
        """Construct the core from the current parameters, keeping the inputs already set
        (on the default experiment's step while ``step_size`` waits for the first doStep)."""
        if not self._step_size >= 0.0:
            raise ValueError(f"parameter 'step_size' = {self._step_size!r}: must be >= 0 "
                             "(0: the step of the first doStep)")
        inputs = {v.name: getattr(self.core, v.name) for v in self.variables
                  if isinstance(v, Input)}
        self.core = self.core_class(self._params,
                                    step_size=self._step_size or DEFAULT_STEP_SIZE,
                                    start_time=self._start_time, inputs=inputs,
                                    resources=self.resources)

    def _adopt_step(self, step_size: float) -> bool:
        """Choose the tick of a ``step_size`` 0 instance at its first doStep and rebuild the
        core on it: the host's step if the core takes it and it is at least
        ``MIN_ADOPTED_STEP``, else the default step, else the core's own
        :meth:`~altfusion.component.Component.natural_step` (False, with the reasons logged,
        if none fits the parameters)."""
        candidates = [step_size] if step_size >= MIN_ADOPTED_STEP else []
        candidates += [DEFAULT_STEP_SIZE, self.core_class.natural_step(self._params)]
        reasons = []
        for candidate in dict.fromkeys(c for c in candidates if c is not None):
            self._step_size = float(candidate)
            try:
                self._rebuild_core()
                return True
            except Exception as error:
                reasons.append(f"{candidate!r} s: {error}")
        self._step_size = ADOPT_FIRST_STEP
        self._failure = ("no internal step fits the parameters (tried the first doStep's "
                         f"step, the default and the core's own: {'; '.join(reasons)})")
        self._log(Fmi2Status.error, f"cannot step, {self._failure}")
        return False

    def setup_experiment(self, start_time: float, stop_time=None, tolerance=None) -> None:
        self._start_time = float(start_time)

    def enter_initialization_mode(self) -> None:
        # Errors are reported when initialization ends, once every parameter is set.
        self._initializing = True
        self._stepping = False
        self._refresh_initial_outputs(force=True)

    def _refresh_initial_outputs(self, force: bool = False) -> None:
        """In Initialization Mode, rebuild the core if a parameter or input changed."""
        if force or (self._initializing and self._stale):
            self._stale = False
            with contextlib.suppress(Exception):
                self._rebuild_core()

    def exit_initialization_mode(self) -> None:
        self._initializing = self._stale = False
        self._stepping = True
        try:
            self._rebuild_core()
            self._failure = None
        except Exception as error:
            self._failure = f"initialization failed: {error}"
            self._log(Fmi2Status.error, self._failure)

    def do_step(self, current_time: float, step_size: float) -> bool:
        if self._failure is not None:
            self._log(Fmi2Status.error, f"cannot step, {self._failure}")
            return False
        if self._step_size == ADOPT_FIRST_STEP and not self._adopt_step(step_size):
            return False
        core = self.core
        try:
            core.do_step(current_time, step_size)
        except Exception:
            self._log_exception(f"doStep(t = {current_time!r} s, h = {step_size!r} s)")
            return False
        for note in core.take_notes():
            self._log(Fmi2Status.warning, note)
        return True

    def terminate(self) -> None:
        pass

    # ----------------------------------------------------------------- value access
    def _accessors(self, kind: type) -> tuple[dict[int, Any], dict[int, Any]]:
        """Getters and setters of the variables of FMI type ``kind``, by value reference."""
        typed = {vr: var for vr, var in self.vars.items() if isinstance(var, kind)}
        return ({vr: v.getter for vr, v in typed.items()},
                {vr: v.setter for vr, v in typed.items() if v.setter is not None})

    @staticmethod
    def _new_batch(cache: dict, build, kind: type, vrs) -> Any:
        """Make and keep the accessor of the value references ``vrs`` (once per list of them:
        an importer asks for the same lists at every step)."""
        if len(cache) >= MAX_CACHED_BATCHES:
            cache.clear()
        batch = cache[tuple(vrs)] = build(kind, tuple(vrs))
        return batch

    def _core_names(self, kind: type, vrs: tuple[int, ...], inputs_only: bool) -> list | None:
        """The core attribute names of ``vrs`` if all are inputs (or outputs), else None."""
        declared = {v.name for v in self.variables
                    if not inputs_only or isinstance(v, Input)}
        names = [getattr(self.vars.get(vr), "name", None) for vr in vrs]
        kinds_match = all(isinstance(self.vars.get(vr), kind) for vr in vrs)
        return names if kinds_match and all(n in declared for n in names) else None

    def _build_reader(self, kind: type, vrs: tuple[int, ...]):
        """A function returning the values of ``vrs`` as a list of ``kind``'s Python type;
        inputs and outputs are read straight from the core (no per-variable getter)."""
        convert = _PY_TYPES[kind]
        names = self._core_names(kind, vrs, inputs_only=False)
        if names is None:
            getters = [self._getters[kind][vr] for vr in vrs]        # KeyError: logged
            return lambda: [convert(get()) for get in getters]
        if len(names) == 1:
            name = names[0]
            return lambda: [convert(getattr(self.core, name))]
        get_all = attrgetter(*names)
        return lambda: list(map(convert, get_all(self.core)))

    def _build_writer(self, kind: type, vrs: tuple[int, ...]):
        """A function setting ``vrs`` to a sequence of values; inputs are set straight on the
        core (parameters through their setters, which check them)."""
        names = self._core_names(kind, vrs, inputs_only=True)
        if names is None:
            setters = [self._setters[kind][vr] for vr in vrs]        # KeyError: logged

            def write(values) -> None:
                for set_value, value in zip(setters, values, strict=True):
                    set_value(value)
            return write
        # pythonfmu hands over Python floats, ints, bools or strs as the FMI type says: the
        # values need no conversion.
        if len(names) == 1:
            name = names[0]

            def write_input(values) -> None:
                (value,) = values
                setattr(self.core, name, value)
                self._stale = self._initializing
            return write_input

        def write_inputs(values) -> None:
            core = self.core
            for name, value in zip(names, values, strict=True):
                setattr(core, name, value)
            self._stale = self._initializing
        return write_inputs

    get_real = _value_getter("getReal", Real, float("nan"))
    get_integer = _value_getter("getInteger", Integer, 0)
    get_boolean = _value_getter("getBoolean", Boolean, False)
    get_string = _value_getter("getString", String, "")
    set_real = _value_setter("setReal", Real)
    set_integer = _value_setter("setInteger", Integer)
    set_boolean = _value_setter("setBoolean", Boolean)
    set_string = _value_setter("setString", String)

    # ----------------------------------------------------------------- FMU state
    def _current_state(self) -> dict[str, Any]:
        """The instance's state (not copied): what getFMUstate copies, setFMUstate replaces."""
        return {"core": self.core, "params": self._params, "step_size": self._step_size,
                "start_time": self._start_time, "failure": self._failure}

    def _get_fmu_state(self) -> dict[str, Any]:
        try:
            return copy.deepcopy(self._current_state())
        except Exception:
            self._log_exception("getFMUstate")
            return {}

    def _set_fmu_state(self, state: dict[str, Any] | fmu_state.RefusedState) -> None:
        if isinstance(state, fmu_state.RefusedState):
            self._log(Fmi2Status.error, f"setFMUstate refused the state: {state.reason}; "
                                        "the instance keeps its current state")
            return
        try:
            fmu_state.check_like(state, self._current_state())
        except fmu_state.StateError as error:
            self._log(Fmi2Status.error, f"setFMUstate refused the state: {error}; "
                                        "the instance keeps its current state")
            return
        try:
            restored = copy.deepcopy(state)
            self.core = restored["core"]
            self._params = restored["params"]
            self._step_size = restored["step_size"]
            self._start_time = restored["start_time"]
            self._failure = restored["failure"]
        except Exception:
            self._log_exception("setFMUstate")

    @classmethod
    def _state_header(cls) -> fmu_state.StateHeader:
        return fmu_state.StateHeader(model=cls.__name__, guid=cls._guid,
                                     core_version=CORE_VERSION)

    @classmethod
    def _fmu_state_to_bytes(cls, state: dict[str, Any]) -> bytes:
        return fmu_state.dump(cls._state_header(), state, own_module=cls.__module__)

    @classmethod
    def _fmu_state_from_bytes(cls, data: bytes) -> dict[str, Any] | fmu_state.RefusedState:
        """The state in ``data``, or a RefusedState saying why not (never an exception: see
        the module docstring)."""
        try:
            return fmu_state.load(bytes(data), cls._state_header(), own_module=cls.__module__)
        except fmu_state.StateError as error:
            return fmu_state.RefusedState(str(error))
        except Exception as error:      # a bug of ours must not become fmi2Fatal either
            return fmu_state.RefusedState(f"unreadable state ({type(error).__name__}: {error})")

    # ----------------------------------------------------------------- modelDescription
    def to_xml(self, model_options: dict[str, str] | None = None) -> Element:
        root = super().to_xml(model_options or {})
        specs = self._declared_units_and_bounds()
        units = {unit for unit, _, _ in specs.values() if unit}
        children = list(root)
        after_cosim = next(i for i, c in enumerate(children) if c.tag == "CoSimulation") + 1
        root.insert(after_cosim, unit_definitions(units))
        vendor = Element("VendorAnnotations")
        tool = SubElement(vendor, "Tool", {"name": VENDOR_TOOL})
        core = self.core_class
        SubElement(tool, "Core", {"version": CORE_VERSION,
                                  "class": f"{public_module(core.__module__)}:{core.__qualname__}",
                                  "stepEndInputs": " ".join(self._step_end_inputs())})
        model_variables = root.find("ModelVariables")
        root.insert(list(root).index(model_variables), vendor)
        index_of: dict[str, int] = {}
        for index, scalar in enumerate(model_variables, start=1):
            name = scalar.get("name")
            index_of[name] = index
            unit, low, high = specs.get(name, (None, None, None))
            real = scalar.find("Real")
            if real is not None and real.get("start") is not None:
                # pythonfmu writes 16 digits, which does not round-trip (9.80665 -> ...99999)
                value = self.get_real([int(scalar.get("valueReference"))])[0]
                real.set("start", repr(value))
            if real is not None:
                for key, value in (("unit", unit), ("min", low), ("max", high)):
                    if value is not None:
                        real.set(key, value if key == "unit" else f"{value:.16g}")
        root.remove(root.find("ModelStructure"))
        structure = SubElement(root, "ModelStructure")
        self._write_model_structure(structure, index_of)
        return root

    def _declared_units_and_bounds(self) -> dict[str, tuple[str | None, Any, Any]]:
        specs = {}
        for info in self.parameter_infos():
            if info.type is float:
                low = info.min
                specs[info.name] = (info.unit, low, info.max)
        for var in self.variables:
            if var.type is float:
                specs[var.name] = (var.unit, var.min, var.max)
        return specs

    def _write_model_structure(self, structure: Element, index_of: dict[str, int]) -> None:
        """Outputs with no direct dependency (they change only in doStep), InitialUnknowns
        with the inputs each initial value follows (``Output.initial_depends_on``)."""
        input_names = [v.name for v in self.variables if isinstance(v, Input)]
        outputs = [v for v in self.variables if isinstance(v, Output)]
        if not outputs:
            return
        for var in outputs:
            unknown = set(var.initial_depends_on) | set(var.reads_at_step_end or ())
            unknown -= set(input_names)
            if unknown:
                raise ValueError(f"output {var.name} names unknown inputs {unknown}")
        outputs_node = SubElement(structure, "Outputs")
        for var in outputs:
            SubElement(outputs_node, "Unknown", {"index": str(index_of[var.name]),
                                                 "dependencies": ""})
        initial = SubElement(structure, "InitialUnknowns")
        for var in outputs:
            SubElement(initial, "Unknown", {
                "index": str(index_of[var.name]),
                "dependencies": " ".join(str(index_of[n]) for n in var.initial_depends_on),
            })

    def _step_end_inputs(self) -> list[str]:
        """The inputs some output reads at the end of a step (``Output.reads_at_step_end``)."""
        inputs = [v.name for v in self.variables if isinstance(v, Input)]
        read = set()
        for var in self.variables:
            if isinstance(var, Output):
                read |= set(inputs if var.reads_at_step_end is None else var.reads_at_step_end)
        return [name for name in inputs if name in read]
