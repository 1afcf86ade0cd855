"""The base of the estimators' compiled machinery classes: made without ``__init__``.

The FMU state codec (:mod:`altfusion.fmi.state`) rebuilds a saved object without running its
``__init__``: it makes a blank instance of the class and writes the saved fields into it. A
class compiled by mypyc (:data:`altfusion.compiled.COMPILED`) is a native class whose
generated ``__new__`` runs ``__init__`` (with the arguments given: none, which fails for an
``__init__`` that needs some); one that defines ``__new__`` itself is made by it alone, as a
Python class is made by ``object.__new__``. Every class of a compiled module that an
estimator's state holds derives from :class:`Restorable`, so that the codec can make it blank
either way (compiled or run from its source).
"""

from typing import Any, TypeVar

_T = TypeVar("_T", bound="Restorable")


class Restorable:
    """A class whose instances can be made blank, ``cls.__new__(cls)``: no ``__init__`` run,
    no field set."""

    __slots__ = ()

    def __new__(cls: type[_T], *args: Any, **kwargs: Any) -> _T:
        """A blank instance (the arguments are ``__init__``'s, which Python calls next when
        the class itself is called)."""
        return super().__new__(cls)
