"""Surviving pythonfmu 0.7.0's re-execution of the slave script at every instantiation.

For each ``fmi2Instantiate`` pythonfmu imports the slave module (cached after the first
time), compiles the script's source again and executes it in the module's namespace to find
the slave class. Two faults of its native code follow from each execution:

* It releases one reference to the module's ``__dict__`` that it never owned (a borrowed
  reference from ``PyModule_GetDict``). Left alone, the dict is freed while the module still
  uses it and the host crashes later, typically in the garbage collector.
* While looking for the class it walks every class in the namespace and keeps a list of its
  MRO and, for each entry, its repr and the repr's UTF-8 bytes, none of which it releases.
  A class statement run again makes a new class, so each instantiation kept a whole slave
  class alive (its methods, its variable declarations, its abc caches): 7-12 kB per
  instantiate/free cycle.
* It inserts the resource folder at the front of ``sys.path`` again, keeping one more entry.

:class:`ReusedSlaveClass`, the metaclass of the adapter base, answers both: every execution
of a class statement pins one reference to the module's dict (balancing the stray release;
one list slot, 8 bytes), and a class statement executed again from the same code in the same
module namespace returns the class made the first time instead of a new one, so what
pythonfmu keeps refers to a class that lives anyway. A changed script (``importlib.reload``,
a different build) compiles to different code and gets a new class. The repr of such a
class is made once (pythonfmu keeps a reference to it instead of a new string), and
:func:`drop_repeated_path_entry` removes the repeated ``sys.path`` entry. What pythonfmu
still keeps per instantiation (its MRO lists, the repr bytes, the reprs of the classes
outside ours, the path string) is measured by ``benchmarks/instantiate_leak.py``.
"""

import sys
from abc import ABCMeta
from typing import Any

_PINNED_MODULE_DICTS: list[dict[str, Any]] = []
"""One reference to a slave module's dict per execution of its class statement."""

_CLASSES_KEY = "__altfusion_slave_classes__"
"""Module-namespace entry: qualified class name -> (module code, class)."""


class ReusedSlaveClass(ABCMeta):
    """Metaclass returning the existing slave class when its statement runs again unchanged."""

    def __new__(mcs, name: str, bases: tuple[type, ...], namespace: dict[str, Any],
                **kwargs: Any):
        module_globals = sys._getframe(1).f_globals
        module_code = sys._getframe(1).f_code
        _PINNED_MODULE_DICTS.append(module_globals)
        made = module_globals.setdefault(_CLASSES_KEY, {})
        qualname = namespace.get("__qualname__", name)
        earlier = made.get(qualname)
        if earlier is not None and earlier[0] == module_code:
            return earlier[1]
        cls = super().__new__(mcs, name, bases, namespace, **kwargs)
        made[qualname] = (module_code, cls)
        return cls

    def __repr__(cls) -> str:
        text = cls.__dict__.get("_class_repr")
        if text is None:
            text = f"<class '{cls.__module__}.{cls.__qualname__}'>"
            type.__setattr__(cls, "_class_repr", text)
        return text


def drop_repeated_path_entry(folder: str) -> None:
    """Remove ``sys.path[0]`` if it is ``folder`` and ``folder`` comes again later (pythonfmu
    inserts the resource folder at every instantiation; imports resolve the same)."""
    if sys.path and sys.path[0] == folder and folder in sys.path[1:]:
        del sys.path[0]
