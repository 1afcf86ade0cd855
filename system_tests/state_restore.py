"""The one FMU state save/restore check of the system tests."""

from collections.abc import Callable
from typing import Any

from altfusion.cosim.instances import FmuInstance


def assert_restores_identically(instance: FmuInstance, continuation: Callable[[], Any]) -> None:
    """Save ``instance``'s FMU state (``fmi2GetFMUstate``) and its serialized bytes, run
    ``continuation``, then restore the state in memory and again from the bytes: each time
    ``continuation`` must return exactly what it returned first (bit-identical, ``==``).

    ``continuation`` steps the instance and returns what it observed; anything outside the FMU
    that it consumes (a test's random generator, counters) it must rewind itself."""
    state = instance.get_state()
    serialized = instance.fmu.serializeFMUstate(state)
    first = continuation()
    instance.set_state(state)
    assert continuation() == first
    instance.set_state(instance.fmu.deSerializeFMUstate(serialized))
    assert continuation() == first
