"""The samples arriving on an estimator's streams: counts, stamps, held samples, plausibility.

What :mod:`~altfusion.estimators.intake` documents, done at every step (compiled:
:data:`altfusion.compiled.COMPILED`): one :class:`StreamIntake` per stream keeps what the
stream delivered (its last count and stamp, a sample held until due), and :class:`Arrivals`
gives each step its due samples (:meth:`Arrivals.due`), with the counts and the held extra
inputs every stream shares. What a sample does to the estimator beyond it (a note, a
refusal charged to its aid source, an invalid frame shown to it) the estimator is told
through its own methods: ``note``, ``frame_invalid``, ``refuse_implausible``, ``aid``,
``n_rejected``. The estimator is passed to each call, never kept: a saved state holds the
arrivals as plain data.
"""

import math
from typing import Any, Final

from altfusion.estimators.floats import finite
from altfusion.estimators.health import STEP_BITS
from altfusion.estimators.restorable import Restorable

_HELD: Final = int(STEP_BITS.SAMPLE_HELD)
_REFUSED: Final = int(STEP_BITS.SAMPLE_REFUSED)


class StreamIntake(Restorable):
    """One stream's inputs (names, bounds) and what it delivered. The names and bounds are
    copies of its :class:`~altfusion.estimators.streams.Stream`'s, read at every step: a
    native field is read directly, a Stream's attribute through the interpreter's lookup."""

    __slots__ = ("prefix", "count_input", "time_input", "valid_input", "fields", "bounds",
                 "auxiliary", "last_count", "last_stamp", "held")

    def __init__(self, stream: Any, count: Any) -> None:
        self.prefix: str = stream.prefix
        self.count_input: str = stream.count
        self.time_input: str = stream.time
        self.valid_input: str = stream.valid or ""
        """The validity flag's input ("": none)."""
        self.fields: tuple[str, ...] = stream.fields
        self.bounds: tuple[tuple[str, str, float], ...] = stream.bounds
        self.auxiliary: tuple[tuple[str, float, float], ...] = stream.auxiliary
        self.last_count: Any = count
        """The count last seen (an input as given: int, or numpy's)."""
        self.last_stamp = -math.inf
        """The stamp of the last sample taken."""
        self.held: dict[str, float] | None = None
        """A sample stamped ahead of the clock, until due."""


class Arrivals(Restorable):
    """The intake of an estimator's streams (:meth:`due`) and extra inputs (:meth:`held`)."""

    __slots__ = ("streams", "seen", "n_ignored", "flags", "held_inputs", "bad_inputs")

    def __init__(self, owner: Any, streams: tuple[Any, ...], extra_inputs: tuple[str, ...],
                 ) -> None:
        """The present counts of ``owner``'s ``streams`` taken as seen, no sample held, the
        ``extra_inputs`` held as given (0 where not finite)."""
        self.streams = [StreamIntake(stream, getattr(owner, stream.count)) for stream in streams]
        self.seen = {s.prefix for s in self.streams if s.last_count > 0}
        """The prefixes of the streams that delivered a valid sample (or had one at the
        start)."""
        self.n_ignored = 0
        """Samples and values ignored so far (``n_ignored``)."""
        self.flags = 0
        """The status bits raised by the last :meth:`due` (``SAMPLE_HELD``,
        ``SAMPLE_REFUSED``)."""
        self.held_inputs: dict[str, float] = {}
        self.bad_inputs: set[str] = set()
        """The extra inputs and auxiliary values in a run of bad values (noted once)."""
        for name in extra_inputs:
            value = float(getattr(owner, name))
            self.held_inputs[name] = value if finite(value) else 0.0

    def due(self, owner: Any, streams: tuple[Any, ...], now: float, max_lead: float,
            max_delay: float) -> dict[Any, dict[str, float]]:
        """The samples of ``owner``'s ``streams`` (the estimator's constants, in the order
        this object was made with) to fuse at ``now``: the new ones not stamped ahead of the
        clock and the held ones now due, by stream. The inputs are read from ``owner``'s
        instance dict, where the FMU adapter sets them (a compiled ``getattr`` looks the
        name up on the class first)."""
        self.flags = 0
        inputs: dict[str, Any] = owner.__dict__
        samples: dict[Any, dict[str, float]] = {}
        due_by = now + 1e-9 * max(1.0, abs(now))       # not ahead of the clock (rounding aside)
        for index, intake in enumerate(self.streams):
            stream = streams[index]
            count = inputs[intake.count_input]
            if count != intake.last_count:
                sample = self._new_sample(owner, inputs, stream, intake, count, now, max_lead,
                                          max_delay)
                if sample is not None:
                    if sample[intake.time_input] <= due_by:   # the usual case: fused at once
                        intake.held = None
                        samples[stream] = sample
                    else:
                        intake.held = sample
                    continue
            held = intake.held
            if held is not None and held[intake.time_input] <= due_by:
                intake.held = None
                samples[stream] = held
        return samples

    def _new_sample(self, owner: Any, inputs: dict[str, Any], stream: Any,
                    intake: StreamIntake, count: Any, now: float, max_lead: float,
                    max_delay: float) -> dict[str, float] | None:
        """The sample of ``stream``, whose count changed to ``count``, if it is valid, finite,
        plausible and stamped in time for ``now``, else None (``inputs``: ``owner``'s)."""
        prefix = intake.prefix
        last = intake.last_count
        intake.last_count = count
        if count > last + 1:
            owner.note(f"{prefix}: {count - last - 1} sample(s) arrived between two "
                       f"estimator steps; only the latest is fused", f"{prefix} skipped")
        if intake.valid_input and not inputs[intake.valid_input]:
            owner.frame_invalid(stream)
            return None
        sample: dict[str, float] = {}
        all_finite = True
        for name in intake.fields:
            value = float(inputs[name])
            sample[name] = value
            if not finite(value):
                all_finite = False
        if not all_finite:
            bad = {name: value for name, value in sample.items() if not finite(value)}
            self.n_ignored += 1
            owner.note(f"{prefix}: non-finite sample ignored {bad}", f"{prefix} ignored")
            return None
        stamp = sample[intake.time_input]
        lead = stamp - now
        if lead > max_lead:
            self._refuse(owner, prefix, f"sample stamped {lead:.4g} s ahead of the clock "
                                        f"(more than max_sample_lead) refused")
            return None
        if -lead > max_delay:
            self._refuse(owner, prefix, f"sample stamped {-lead:.4g} s behind the clock "
                                        f"(more than max_sample_delay): stale, refused")
            return None
        if stamp < intake.last_stamp:
            self._refuse(owner, prefix, f"sample stamped {stamp!r} s, before the stream's "
                                        f"last sample ({intake.last_stamp!r} s): refused")
            return None
        for name, source, bound in intake.bounds:
            value = sample[name]
            if abs(value) > bound:
                owner.refuse_implausible(owner.aid[source], value, bound)
                return None
        for name, lowest, highest in intake.auxiliary:
            self._check_auxiliary(owner, sample, name, lowest, highest)
        if intake.held is not None:
            owner.note(f"{prefix}: a held sample was replaced before it was due",
                       f"{prefix} replaced")
        if lead > 0.0:
            self.flags |= _HELD
        self.seen.add(prefix)
        intake.last_stamp = stamp
        return sample

    def _check_auxiliary(self, owner: Any, sample: dict[str, float], name: str,
                         lowest: float, highest: float) -> None:
        """Leave the auxiliary value ``name`` out of ``sample`` if it lies outside
        [``lowest``, ``highest``]: counted in ``n_ignored``, the first of a run noted."""
        value = sample[name]
        if lowest <= value <= highest:
            self.bad_inputs.discard(name)
            return
        del sample[name]
        self.n_ignored += 1
        if name not in self.bad_inputs:
            self.bad_inputs.add(name)
            owner.note(f"{name}: {value!r} is outside its plausible {lowest:g}-{highest:g} "
                       f"(an input left unconnected?): the samples are fused without it "
                       f"while it stays there")

    def _refuse(self, owner: Any, prefix: str, message: str) -> None:
        """Refuse a sample of the stream ``prefix`` for its time stamp: counted in its
        source's rejections, flagged and noted."""
        owner.aid[prefix].refused()
        owner.n_rejected += 1
        self.flags |= _REFUSED
        owner.note(f"{prefix}: {message}", f"{prefix} refused")

    def held(self, owner: Any, name: str) -> float:
        """``owner``'s extra input ``name``, or its last finite value if it is not finite now
        (counted in ``n_ignored``; the first of a run of them noted)."""
        value = float(getattr(owner, name))
        held = self.held_inputs[name]
        if finite(value):
            self.held_inputs[name] = value
            self.bad_inputs.discard(name)
            return value
        self.n_ignored += 1
        if name not in self.bad_inputs:
            self.bad_inputs.add(name)
            owner.note(f"{name}: non-finite sample ignored ({value}); holding {held!r}")
        return held
