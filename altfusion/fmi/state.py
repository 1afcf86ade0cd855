"""Serialized FMU states: data, never code.

``fmi2SerializeFMUstate`` bytes are laid out so that a reader in any language can check them
before trusting a single byte of the body::

    magic            8 bytes  b"ALTFSTAT"
    format version   2 bytes  unsigned, big endian (FORMAT_VERSION)
    header length    4 bytes  unsigned, big endian
    header           UTF-8 JSON {"model": ..., "guid": ..., "core_version": ...}
    body CRC-32      4 bytes  unsigned, big endian (zlib.crc32 of the body)
    body             UTF-8 JSON: the state as a tagged tree (below)

The body is a JSON tree. ``None``, booleans, integers, floats (Python's JSON writes the
shortest repr, which reads back to the same double; NaN and infinities as JSON extensions),
strings and lists are themselves; anything else is an object with a ``"$t"`` tag: tuples,
dicts (as key/value pairs), sets, deques (with their ``maxlen``), fractions, numpy arrays and
scalars (dtype string, shape, base64 of the raw bytes; only numeric and boolean dtypes),
numpy ``Generator`` s (the name of the bit generator, one of numpy's five, and its state
dict), enum members of the core (by value), named tuples and plain objects of the core.
Objects, lists, dicts, sets, deques, arrays and generators carry an ``id``; a second
reference to the same one is ``{"$t": "ref"}``, so sharing (two sensors drawing from one
generator) survives a round trip.

Decoding calls no code chosen by the bytes: a class is found among the classes already
imported from the core packages (``CORE_PACKAGES``) or the FMU's own slave script, never
imported on demand; it must be a plain class, a dataclass, a named tuple or an enum (whose
member is looked up by its int or str value). Objects are rebuilt with ``object.__new__``
(or ``tuple.__new__``; a :class:`~altfusion.estimators.restorable.Restorable`, which may be a
class compiled by mypyc, with its own ``__new__``, which makes a blank instance) and their
fields written directly, without ``__init__``, ``__setstate__`` or any other method of
theirs. Bit generators are constructed
from numpy's own classes and given their state through numpy's setter. Anything else is a
:class:`StateError` naming the reason.
"""

import base64
import collections
import dataclasses
import enum
import fractions
import json
import struct
import sys
import zlib
from typing import Any

import numpy as np

from altfusion.estimators.restorable import Restorable

MAGIC = b"ALTFSTAT"
FORMAT_VERSION = 1
_PREFIX = struct.Struct(">8sHI")
_CRC = struct.Struct(">I")

_PACKAGE = __name__.split(".")[0]
"""The core's top-level package name (``altfusion``, or the name an FMU bundles it under)."""

CORE_PACKAGES = tuple(f"{_PACKAGE}.{name}" for name in (
    "component", "params", "timegrid", "physics.", "sensors.", "estimators.", "replay."))
"""Modules whose classes a state may contain (the core; never the FMI or host layers)."""

_BIT_GENERATORS = {cls.__name__: cls for cls in
                   (np.random.PCG64, np.random.PCG64DXSM, np.random.MT19937,
                    np.random.Philox, np.random.SFC64)}
_NATIVE_FIELDS = "__mypyc_attrs__"
"""The attribute of a class compiled by mypyc naming its instances' native attributes."""
_ARRAY_KINDS = "biufc"
"""numpy dtype kinds a state may hold: booleans, integers, floats, complex (never objects)."""


class StateError(ValueError):
    """A state that cannot be written, or bytes that are not a state this FMU accepts."""


@dataclasses.dataclass(frozen=True)
class StateHeader:
    """Who wrote a state: the FMU's model name, its GUID and the core version."""

    model: str
    guid: str
    core_version: str


@dataclasses.dataclass(frozen=True)
class RefusedState:
    """What deserializing bytes that are not an acceptable state gives: the reason (the native
    shim, :mod:`altfusion.fmi.shim`, reads the attribute ``reason`` of the deserialized
    object and returns fmi2Error with it)."""

    reason: str


# ----------------------------------------------------------------------------- container
def dump(header: StateHeader, state: Any, own_module: str = "") -> bytes:
    """The serialized bytes of ``state`` (StateError if it holds something not data);
    classes of ``own_module`` (the slave script) may appear besides the core's."""
    tree = _Encoder(own_module).encode(state)
    return assemble(header, json.dumps(tree, separators=(",", ":")).encode())


def assemble(header: StateHeader, body: bytes) -> bytes:
    """Magic, format version, ``header`` and the checksummed JSON ``body``."""
    head = json.dumps(dataclasses.asdict(header), sort_keys=True).encode()
    return (_PREFIX.pack(MAGIC, FORMAT_VERSION, len(head)) + head
            + _CRC.pack(zlib.crc32(body)) + body)


def read_header(data: bytes) -> tuple[StateHeader, bytes]:
    """The header and the checked body of ``data`` (StateError naming what is wrong)."""
    if len(data) < _PREFIX.size or data[:len(MAGIC)] != MAGIC:
        raise StateError("not an altfusion FMU state (bad magic; a pickle or other bytes?)")
    _, version, head_length = _PREFIX.unpack_from(data)
    if version != FORMAT_VERSION:
        raise StateError(f"state format version {version}, this FMU reads {FORMAT_VERSION}")
    body_start = _PREFIX.size + head_length + _CRC.size
    if len(data) < body_start:
        raise StateError("truncated state (header incomplete)")
    try:
        fields = json.loads(data[_PREFIX.size:_PREFIX.size + head_length])
        header = StateHeader(**{k: str(fields[k]) for k in ("model", "guid", "core_version")})
    except (ValueError, KeyError, TypeError) as error:
        raise StateError(f"corrupted state header ({error})") from None
    (crc,) = _CRC.unpack_from(data, body_start - _CRC.size)
    body = data[body_start:]
    if zlib.crc32(body) != crc:
        raise StateError("truncated or corrupted state (body checksum mismatch)")
    return header, body


def load(data: bytes, expected: StateHeader, own_module: str = "") -> Any:
    """The state in ``data`` if it was written by an FMU with the ``expected`` header (classes
    of the core or of ``own_module``, the slave script, only)."""
    header, body = read_header(data)
    for field in ("model", "guid", "core_version"):
        found, wanted = getattr(header, field), getattr(expected, field)
        if found != wanted:
            raise StateError(f"foreign state: written by {field} {found!r}, "
                             f"this FMU is {wanted!r}")
    try:
        tree = json.loads(body)
    except ValueError as error:
        raise StateError(f"corrupted state body ({error})") from None
    return _Decoder(own_module).decode(tree)


# ----------------------------------------------------------------------------- checking
def check_like(new: Any, current: Any, path: str = "state") -> None:
    """A StateError naming the first field of ``new`` whose type differs from the same field
    of ``current`` (the instance's state, which ``new`` is about to replace): objects of the
    same class with the same attributes, arrays of the same dtype kind and shape, square
    matrices (lists of as many rows of numbers) for square matrices, numbers for numbers
    (int or float), Booleans for Booleans, strings for strings, containers of the same kind
    whose items match (each against the current item at its index, else the last one; dicts
    by their common keys). None on either side is an unset optional field and matches
    anything. Checked before anything is replaced, so that a well-checksummed state with a
    wrongly typed field (``h_est: "x"``) is refused at fmi2SetFMUstate, not found at a later
    step."""
    _Checker().check(new, current, path)


def _kind(value: Any) -> str:
    """What a value is, for the messages of :func:`check_like`."""
    if isinstance(value, np.ndarray):
        return f"an array of {value.dtype} {list(value.shape)}"
    return f"a {type(value).__name__} ({value!r:.40})"


class _Checker:
    """:func:`check_like`'s walk, each pair of objects visited once (states share objects
    and may hold cycles)."""

    def __init__(self) -> None:
        self._seen: set[tuple[int, int]] = set()

    def check(self, new: Any, current: Any, path: str) -> None:
        if new is None or current is None:
            return
        if isinstance(current, (bool, np.bool_)) or isinstance(new, (bool, np.bool_)):
            same = isinstance(new, (bool, np.bool_)) and isinstance(current, (bool, np.bool_))
        elif isinstance(current, (int, float, np.integer, np.floating)):
            same = isinstance(new, (int, float, np.integer, np.floating))
        elif isinstance(current, np.ndarray):
            same = (isinstance(new, np.ndarray) and new.dtype.kind == current.dtype.kind
                    and new.shape == current.shape)
        else:
            same = type(new) is type(current)
        if not same:
            raise StateError(f"{path} is {_kind(new)} where this instance has "
                             f"{_kind(current)}")
        if (id(new), id(current)) in self._seen:
            return
        self._seen.add((id(new), id(current)))
        if isinstance(current, (list, tuple, collections.deque)):
            if _is_matrix(current) and not _is_matrix(new):
                raise StateError(f"{path} is not a square matrix as this instance's is: "
                                 f"{_kind(new)}")
            for index, item in enumerate(new):
                if len(current):
                    self.check(item, current[min(index, len(current) - 1)],
                               f"{path}[{index}]")
        elif isinstance(current, dict):
            for key in new.keys() & current.keys():
                self.check(new[key], current[key], f"{path}[{key!r}]")
        elif _is_data_object(current):
            new_fields, fields = _object_fields(new), _object_fields(current)
            if new_fields.keys() != fields.keys():
                missing = sorted(fields.keys() - new_fields.keys())
                extra = sorted(new_fields.keys() - fields.keys())
                raise StateError(f"{path} ({type(current).__name__}) lacks {missing} and "
                                 f"has {extra}")
            for name, value in new_fields.items():
                self.check(value, fields[name], f"{path}.{name}")
            _check_covariances(new, type(current), path)
        elif isinstance(current, np.random.Generator) and (
                type(new.bit_generator) is not type(current.bit_generator)):
            raise StateError(f"{path} draws from {type(new.bit_generator).__name__} where "
                             f"this instance has {type(current.bit_generator).__name__}")


def _check_covariances(new: Any, kind: type, path: str) -> None:
    """A StateError if a state vector of ``new`` and one of its covariances differ in size,
    as the class ``kind`` of the current object declares them (``state_covariances``: the
    vector's attribute -> its covariances' attributes, e.g. ``{"x": ("P",)}``): each may
    legitimately have another size than the current one's (YangFusionKF's follows its
    parameters), but not another than its partner's, or the filter fails at its next step."""
    for vector, covariances in getattr(kind, "state_covariances", {}).items():
        x = getattr(new, vector, None)
        for name in covariances:
            P = getattr(new, name, None)
            if x is not None and P is not None and len(x) != len(P):
                raise StateError(f"{path}.{vector} has {len(x)} states where its covariance "
                                 f"{path}.{name} is {len(P)} x {len(P)}")


def _is_matrix(value: Any) -> bool:
    """A non-empty list or tuple of as many rows of numbers (a covariance of the
    estimators' scalar arithmetic): a restored one must be square too, or the filter fails
    at its next step. Its size may differ from the current one's (YangFusionKF's follows its
    parameters, which the state brings along); lists of numbers alone may change length (a
    sensor's buffer of drawn noise)."""
    return isinstance(value, (list, tuple)) and bool(value) and all(
        isinstance(row, (list, tuple)) and len(row) == len(value)
        and all(isinstance(v, (int, float)) for v in row) for row in value)


def _is_data_object(value: Any) -> bool:
    """An object whose attributes a state holds (not a container, number or array)."""
    return not isinstance(value, (str, bytes, set, frozenset, enum.Enum, fractions.Fraction,
                                  np.generic, np.random.Generator)) and (
        hasattr(value, "__dict__") or hasattr(type(value), "__slots__")
        or hasattr(type(value), _NATIVE_FIELDS))


# ----------------------------------------------------------------------------- encoding
def _core_class(cls: type, own_module: str) -> bool:
    module = cls.__module__
    return module.startswith(CORE_PACKAGES) or module in CORE_PACKAGES or module == own_module


def _is_named_tuple(cls: type) -> bool:
    return issubclass(cls, tuple) and hasattr(cls, "_fields")


def _object_fields(obj: Any) -> dict[str, Any]:
    """An object's instance attributes: its ``__dict__``, any named slots and, for a class
    compiled by mypyc, its native attributes (those set)."""
    fields = dict(getattr(obj, "__dict__", {}))
    kind = type(obj)
    names = [name for klass in kind.__mro__ for name in klass.__dict__.get("__slots__", ())]
    for name in (*names, *getattr(kind, _NATIVE_FIELDS, ())):
        if name not in ("__dict__", "__weakref__") and hasattr(obj, name):
            fields[name] = getattr(obj, name)
    return fields


class _Encoder:
    """Turns a state into the tagged JSON tree (one instance per state)."""

    def __init__(self, own_module: str) -> None:
        self._own_module = own_module
        self._ids: dict[int, int] = {}
        self._alive: list[Any] = []          # keeps ids stable while encoding

    def _first(self, obj: Any) -> int | None:
        """The id of a shared object's first encoding, or None (and register it)."""
        if id(obj) in self._ids:
            return self._ids[id(obj)]
        self._ids[id(obj)] = len(self._ids)
        self._alive.append(obj)
        return None

    def encode(self, obj: Any) -> Any:
        if obj is None or type(obj) in (bool, int, float, str):
            return obj
        shared = type(obj) in (list, dict, set, collections.deque, np.ndarray,
                               np.random.Generator) or _core_class(type(obj),
                                                                   self._own_module)
        if shared and not (_is_named_tuple(type(obj)) or isinstance(obj, enum.Enum)):
            known = self._first(obj)
            if known is not None:
                return {"$t": "ref", "id": known}
            tree = self._encode_new(obj)
            tree["id"] = self._ids[id(obj)]
            return tree
        return self._encode_new(obj)

    def _encode_new(self, obj: Any) -> dict[str, Any]:
        kind = type(obj)
        if kind is list:
            return {"$t": "list", "v": [self.encode(v) for v in obj]}
        if kind is tuple:
            return {"$t": "tuple", "v": [self.encode(v) for v in obj]}
        if kind is dict:
            return {"$t": "dict", "v": [[self.encode(k), self.encode(v)] for k, v in obj.items()]}
        if kind in (set, frozenset):
            return {"$t": kind.__name__, "v": [self.encode(v) for v in obj]}
        if kind is collections.deque:
            return {"$t": "deque", "maxlen": obj.maxlen, "v": [self.encode(v) for v in obj]}
        if kind is fractions.Fraction:
            return {"$t": "fraction", "v": [obj.numerator, obj.denominator]}
        if kind is np.ndarray or isinstance(obj, np.generic):
            return self._encode_array(obj)
        if kind is np.random.Generator:
            bit_generator = obj.bit_generator
            name = type(bit_generator).__name__
            if _BIT_GENERATORS.get(name) is not type(bit_generator):
                raise StateError(f"cannot serialize bit generator {name}")
            return {"$t": "generator", "bit_generator": name,
                    "state": self.encode(bit_generator.state)}
        if _core_class(kind, self._own_module):
            name = f"{kind.__module__}:{kind.__qualname__}"
            if isinstance(obj, enum.Enum) and type(obj.value) in (int, str):
                return {"$t": "enum", "class": name, "v": obj.value}
            if _is_named_tuple(kind):
                return {"$t": "namedtuple", "class": name, "v": [self.encode(v) for v in obj]}
            fields = {k: self.encode(v) for k, v in _object_fields(obj).items()}
            return {"$t": "object", "class": name, "v": fields}
        raise StateError(f"cannot serialize a {kind.__module__}.{kind.__qualname__} "
                         "(not data of the core)")

    @staticmethod
    def _encode_array(obj: Any) -> dict[str, Any]:
        array = np.asarray(obj)
        if array.dtype.kind not in _ARRAY_KINDS:
            raise StateError(f"cannot serialize an array of dtype {array.dtype}")
        return {"$t": "ndarray" if type(obj) is np.ndarray else "scalar",
                "dtype": array.dtype.str, "shape": list(array.shape),
                "data": base64.b64encode(np.ascontiguousarray(array).tobytes()).decode()}


# ----------------------------------------------------------------------------- decoding
def _allowed_class(name: Any, own_module: str) -> type:
    """The core (or ``own_module``) class ``module:qualname``, if already imported and plain."""
    module_name, _, qualname = str(name).partition(":")
    module = sys.modules.get(module_name)
    cls: Any = module
    for part in qualname.split("."):
        cls = getattr(cls, part, None)
    if not (isinstance(cls, type) and _core_class(cls, own_module) and cls.__module__ == module_name
            and cls.__qualname__ == qualname):
        raise StateError(f"class {name!r} is not a core class of this FMU")
    if _is_named_tuple(cls) or issubclass(cls, enum.Enum):
        return cls
    if cls.__new__ is not object.__new__ and not issubclass(cls, Restorable):
        raise StateError(f"class {name!r} has its own __new__")
    return cls


class _Decoder:
    """Rebuilds a state from the tagged JSON tree, calling no code the bytes choose."""

    def __init__(self, own_module: str) -> None:
        self._own_module = own_module
        self._shared: dict[int, Any] = {}

    def decode(self, tree: Any) -> Any:
        if tree is None or type(tree) in (bool, int, float, str):
            return tree
        if type(tree) is not dict or not isinstance(tree.get("$t"), str):
            raise StateError("corrupted state body (untagged value)")
        try:
            return self._decode_tagged(tree)
        except StateError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as error:
            raise StateError(f"corrupted state body ({tree['$t']}: {error})") from None

    def _register(self, tree: dict, value: Any) -> Any:
        if "id" in tree:
            self._shared[int(tree["id"])] = value
        return value

    def _decode_tagged(self, tree: dict) -> Any:
        tag = tree["$t"]
        if tag == "ref":
            return self._shared[int(tree["id"])]
        if tag == "list":
            items = self._register(tree, [])
            items.extend(self.decode(v) for v in tree["v"])
            return items
        if tag == "tuple":
            return tuple(self.decode(v) for v in tree["v"])
        if tag == "dict":
            mapping = self._register(tree, {})
            mapping.update((self.decode(k), self.decode(v)) for k, v in tree["v"])
            return mapping
        if tag in ("set", "frozenset"):
            values = [self.decode(v) for v in tree["v"]]
            return self._register(tree, set(values) if tag == "set" else frozenset(values))
        if tag == "deque":
            maxlen = tree["maxlen"]
            queue = self._register(tree, collections.deque(
                maxlen=None if maxlen is None else int(maxlen)))
            queue.extend(self.decode(v) for v in tree["v"])
            return queue
        if tag == "fraction":
            numerator, denominator = (int(v) for v in tree["v"])
            return fractions.Fraction(numerator, denominator)
        if tag in ("ndarray", "scalar"):
            return self._register(tree, self._decode_array(tree))
        if tag == "generator":
            return self._register(tree, self._decode_generator(tree))
        if tag == "enum":
            cls = _allowed_class(tree["class"], self._own_module)
            if not issubclass(cls, enum.Enum) or type(tree["v"]) not in (int, str):
                raise StateError(f"corrupted state body (enum {tree['class']!r})")
            return cls(tree["v"])
        if tag == "namedtuple":
            cls = _allowed_class(tree["class"], self._own_module)
            return tuple.__new__(cls, [self.decode(v) for v in tree["v"]])
        if tag == "object":
            cls = _allowed_class(tree["class"], self._own_module)
            obj = self._register(tree, cls.__new__(cls))     # object's or Restorable's: blank
            for name, value in tree["v"].items():
                if name.startswith("__") and name.endswith("__"):
                    raise StateError(f"attribute {name!r} of {tree['class']!r} refused")
                try:
                    object.__setattr__(obj, str(name), self.decode(value))
                except (TypeError, AttributeError) as error:     # a native class's own check
                    raise StateError(f"field {name!r} of {tree['class']!r} refused: "
                                     f"{error}") from None
            return obj
        raise StateError(f"corrupted state body (unknown tag {tag!r})")

    @staticmethod
    def _decode_array(tree: dict) -> Any:
        dtype = np.dtype(str(tree["dtype"]))
        if dtype.kind not in _ARRAY_KINDS:
            raise StateError(f"array of dtype {dtype} refused")
        shape = tuple(int(n) for n in tree["shape"])
        array = np.frombuffer(base64.b64decode(tree["data"], validate=True),
                              dtype=dtype).reshape(shape).copy()
        return array if tree["$t"] == "ndarray" else array[()]

    def _decode_generator(self, tree: dict) -> np.random.Generator:
        cls = _BIT_GENERATORS.get(str(tree["bit_generator"]))
        if cls is None:
            raise StateError(f"unknown bit generator {tree['bit_generator']!r}")
        bit_generator = cls()
        bit_generator.state = self.decode(tree["state"])
        return np.random.Generator(bit_generator)
