"""The base of every core model: parameters, an exact tick clock, inputs and outputs.

A component is a discrete-time system on a fixed step, its tick. Its inputs and outputs are plain
attributes named as in the signal contract (``docs/signals.md``); the FMU adapter
and the runner's direct (no-FMI) backend both map variables onto these attributes by name.
Subclasses give their inputs default values before calling ``Component.__init__``, which
applies any ``inputs`` given, validates the parameters and sets the initial state: a component
that exists is always valid. ``do_step`` takes any communication step: it checks the requested
time against where the last step ended and calls :meth:`update`, which advances exactly one
tick, for each tick within the step (inputs held over the step).
"""

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Any, ClassVar

from altfusion.params import check_params
from altfusion.timegrid import TickClock

DEFAULT_STEP_SIZE = 0.01
"""Default communication step of every component, s."""

MAX_PENDING_NOTES = 1000
"""Notes kept until a host drains them; older ones are dropped and counted."""

NOTE_INTERVAL = 1.0
"""Simulated seconds between two notes of one kind (a source's rejected samples, a stream's
non-finite ones...): those in between are counted, and the next one logged says how many.
A sensor failed for an hour then fills a host's log with one line per second, not one per
sample."""


class Component(ABC):
    """Base class of core models; subclasses set ``Params`` and implement ``reset``/``update``."""

    Params: ClassVar[type]

    def __init__(
        self,
        params: Any = None,
        step_size: float = DEFAULT_STEP_SIZE,
        start_time: float = 0.0,
        inputs: dict[str, Any] | None = None,
        resources: str | None = None,
    ):
        self.params = params if params is not None else self.Params()
        self.resources = resources
        """Folder where relative file parameters are looked up (the FMU's resources)."""
        check_params(self.params)
        for name, value in (inputs or {}).items():
            setattr(self, name, value)
        self.clock = TickClock(step_size, start_time)
        self._notes: list[str] = []
        self.dropped_notes = 0
        self._note_kinds: dict[str, tuple[float, int]] = {}
        """Each kind of note: when one was last recorded, and how many were held back since."""
        self.configure(self.clock)
        self.reset()

    @property
    def time(self) -> float:
        """Current time of this component, s (exact: from the tick count)."""
        return self.clock.now

    @property
    def dt(self) -> float:
        """Step size, s."""
        return self.clock.step_size

    def configure(self, clock: TickClock) -> None:
        """Check parameters against the step and derive step-dependent constants.

        Periods, offsets and latencies must be whole multiples of the step: raise
        :class:`~altfusion.errors.ParameterError` naming the parameter otherwise.
        The default has nothing to check.
        """
        return None

    @classmethod
    def natural_step(cls, params: Any) -> float | None:
        """The longest tick that fits ``params`` (a sensor's sample period, offset and
        latency), for an FMU whose host step does not; None: no such constraint."""
        return None

    @abstractmethod
    def reset(self) -> None:
        """Set the initial state and outputs from the parameters (t = start time)."""

    @abstractmethod
    def update(self) -> None:
        """Advance one step; ``self.time`` is already the end of the step."""

    def do_step(self, current_time: float, step_size: float) -> None:
        """Advance from ``current_time`` by any positive ``step_size``: :meth:`update` once
        for each tick of the component's step that falls within it (none for a step shorter
        than what is left of the current tick; see :mod:`altfusion.timegrid`)."""
        clock = self.clock
        due = clock.due(current_time, step_size)
        if due == 1:                            # the usual request: the fast path
            clock.tick()
            self.update()
            return
        for _ in range(due):
            clock.tick()
            self.update()

    def note(self, message: str, kind: str | None = None) -> None:
        """Record a warning (an ignored sample, a rejected outlier...) for the host to log.

        A note of a ``kind`` (one that can come at every sample) is held back and counted if
        another of that kind was recorded less than :data:`NOTE_INTERVAL` before; the next one
        recorded says how many were held back."""
        if kind is not None:
            now = self.time
            last, held = self._note_kinds.get(kind, (None, 0))
            if last is not None and 0.0 <= now - last < NOTE_INTERVAL - 1e-9:   # (rounding)
                self._note_kinds[kind] = (last, held + 1)
                return
            if held:
                message += f" ({held} more since t = {last!r} s not logged)"
            self._note_kinds[kind] = (now, 0)
        if len(self._notes) >= MAX_PENDING_NOTES:
            self._notes.pop(0)
            self.dropped_notes += 1
        self._notes.append(f"t = {self.time!r} s: {message}")

    def take_notes(self) -> Sequence[str]:
        """The notes recorded since the last call (the FMU adapter logs them as warnings)."""
        if not self._notes:
            return ()                       # the usual case, at every step: nothing to hand
        notes, self._notes = self._notes, []
        return notes
