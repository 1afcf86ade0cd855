"""What every estimator shares: sensor streams, new-sample detection, guarded fusion, outputs.

A sensor stream is a group of inputs named by the signal contract: the held sample values,
``<prefix>_count`` and optionally a validity flag (``gps_fix``, ``radar_valid``...). A
measurement update happens exactly once per new sample, i.e. when the count changes, whatever
the estimator's own step; the time update runs at every step. A sample that is invalid or
not finite is ignored and noted (logged by the FMU), so nothing propagates into the state.
An estimator that needs the sample's time stamp uses the stream's :meth:`Stream.timed`
variant, whose samples carry ``<prefix>_time`` like any other value.

Inputs outside any stream (``extra_inputs``, e.g. ``wind_speed``) have no count: they are read
with :meth:`Estimator.held_input`, which holds the last finite value over non-finite ones.
"""

import math
from abc import abstractmethod
from dataclasses import dataclass
from functools import cached_property
from typing import ClassVar

from altfusion.component import Component


@dataclass(frozen=True, eq=False)
class Stream:
    """The inputs of one sensor stream.

    Streams are this module's constants and compare by identity: they key the per-step
    sample dicts, where the built-in identity hash costs nothing (a field hash would run
    Python code at every lookup)."""

    prefix: str
    values: tuple[str, ...]
    valid: str | None = None

    @cached_property
    def count(self) -> str:
        return f"{self.prefix}_count"

    @cached_property
    def time(self) -> str:
        return f"{self.prefix}_time"

    @cached_property
    def _timed(self) -> "Stream":
        return Stream(self.prefix, (*self.values, self.time), self.valid)

    def timed(self) -> "Stream":
        """This stream with the sample's time stamp ``<prefix>_time`` (s) among its values
        (one object per stream: streams compare by identity)."""
        return self if self.time in self.values else self._timed


BARO = Stream("baro", ("baro_h",))
BARO_T = Stream("baro", ("baro_h", "baro_T"))
BARO_P = Stream("baro", ("baro_h", "baro_p"))
GPS = Stream("gps", ("gps_h",), "gps_fix")
GPS_QUALITY = Stream("gps", ("gps_h", "gps_vdop", "gps_nsat"), "gps_fix")
GPS_VZ = Stream("gps", ("gps_h", "gps_vz"), "gps_fix")
ACC = Stream("acc", ("acc_z",))
RADAR = Stream("radar", ("radar_h",), "radar_valid")
LASER = Stream("laser", ("laser_h",), "laser_valid")
BARO_TIMED = BARO.timed()
GPS_VZ_TIMED = GPS_VZ.timed()
RADAR_TIMED = RADAR.timed()


def stream_inputs(streams: tuple[Stream, ...]) -> tuple[str, ...]:
    """The input names of ``streams`` in declaration order: values, count, validity flag."""
    names: list[str] = []
    for stream in streams:
        for name in (*stream.values, stream.count, *((stream.valid,) if stream.valid else ())):
            if name not in names:
                names.append(name)
    return tuple(names)


class Estimator(Component):
    """Base of the estimators: inputs from ``streams``, outputs ``h_est``, ``vz_est``, ``h_std``.

    Subclasses implement :meth:`propagate` (time update over one step) and :meth:`fuse` (one
    new sample of one stream) or :meth:`fuse_samples` (all new samples of a step together),
    and set ``h_est``, ``vz_est``, ``h_std`` and their diagnostics.
    """

    streams: ClassVar[tuple[Stream, ...]]
    extra_inputs: ClassVar[tuple[str, ...]] = ()
    """Real inputs outside any stream (no count), read with :meth:`held_input`."""

    def __init__(self, params=None, **kwargs):
        for name in self.extra_inputs:
            setattr(self, name, 0.0)
        for stream in self.streams:
            for name in stream.values:
                setattr(self, name, 0.0)
            setattr(self, stream.count, 0)
            if stream.valid:
                setattr(self, stream.valid, True)
        self.h_est = 0.0
        self.vz_est = 0.0
        self.h_std = 0.0
        self.n_rejected = 0
        self.n_ignored = 0
        super().__init__(params, **kwargs)

    def reset(self) -> None:
        self._last_count = {s.prefix: getattr(self, s.count) for s in self.streams}
        self._seen = {prefix for prefix, count in self._last_count.items() if count > 0}
        self.n_rejected = 0
        self.n_ignored = 0
        self._held_inputs: dict[str, float] = {}
        self._bad_inputs: set[str] = set()
        for name in self.extra_inputs:
            value = float(getattr(self, name))
            self._held_inputs[name] = value if math.isfinite(value) else 0.0
        self.initialize_filter()

    @abstractmethod
    def initialize_filter(self) -> None:
        """Set the filter's initial state and outputs from the parameters."""

    @abstractmethod
    def propagate(self, dt: float) -> None:
        """Time update over one step of ``dt`` seconds."""

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        """Measurement update with one new, valid, finite sample of ``stream``."""
        raise NotImplementedError(f"{type(self).__name__} must override fuse or fuse_samples")

    def fuse_samples(self, samples: dict[Stream, dict[str, float]]) -> None:
        """Fuse the new samples of this step; by default one by one in ``streams`` order."""
        for stream, sample in samples.items():
            self.fuse(stream, sample)

    def update(self) -> None:
        self.propagate(self.dt)
        samples = {}
        last_count = self._last_count
        for stream in self.streams:
            count = getattr(self, stream.count)
            if count != last_count[stream.prefix]:
                sample = self._new_sample(stream, count)
                if sample is not None:
                    samples[stream] = sample
        self.fuse_samples(samples)

    def _new_sample(self, stream: Stream, count: int) -> dict[str, float] | None:
        """The sample of ``stream``, whose count changed to ``count``, if it is valid and
        finite, else None."""
        last = self._last_count[stream.prefix]
        self._last_count[stream.prefix] = count
        if count > last + 1:
            self.note(f"{stream.prefix}: {count - last - 1} sample(s) arrived between two "
                      f"estimator steps; only the latest is fused")
        if stream.valid and not getattr(self, stream.valid):
            return None
        sample = {name: float(getattr(self, name)) for name in stream.values}
        if not all(map(math.isfinite, sample.values())):
            bad = {name: value for name, value in sample.items() if not math.isfinite(value)}
            self.n_ignored += 1
            self.note(f"{stream.prefix}: non-finite sample ignored {bad}")
            return None
        self._seen.add(stream.prefix)
        return sample

    def has_sample(self, prefix: str) -> bool:
        """True once the stream ``prefix`` has delivered a valid sample (or had one at the
        start): until then its input holds a placeholder, not a measurement."""
        return prefix in self._seen

    @classmethod
    def declared_inputs(cls) -> tuple[str, ...]:
        """Every input of the estimator: its streams' inputs, then its extra inputs."""
        names = stream_inputs(cls.streams)
        return names + tuple(n for n in cls.extra_inputs if n not in names)

    def held_input(self, name: str) -> float:
        """The extra input ``name``, or its last finite value if it is not finite now.

        A non-finite value counts in ``n_ignored``; the first of a run of them is noted."""
        value = float(getattr(self, name))
        held = self._held_inputs[name]
        if math.isfinite(value):
            self._held_inputs[name] = value
            self._bad_inputs.discard(name)
            return value
        self.n_ignored += 1
        if name not in self._bad_inputs:
            self._bad_inputs.add(name)
            self.note(f"{name}: non-finite sample ignored ({value}); holding {held!r}")
        return held

    def reject(self, stream: Stream, innovation: float, sigma: float) -> None:
        """Count and note a sample rejected by the innovation gate."""
        self.n_rejected += 1
        self.note(f"{stream.prefix}: sample rejected by the innovation gate "
                  f"(innovation {innovation:.4g} m, {abs(innovation) / sigma:.3g} sigma)")
