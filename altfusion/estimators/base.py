"""What every estimator shares: sensor streams, new-sample detection, guarded fusion, health.

A sensor stream is a group of inputs named by the signal contract: the held sample values,
``<prefix>_count``, ``<prefix>_time`` (the sample's time stamp) and optionally a validity flag
(``gps_fix``, ``radar_valid``...). A measurement update happens exactly once per new sample,
i.e. when the count changes, whatever the estimator's own step; the time update runs at every
step. A sample that is invalid or not finite is ignored and noted (logged by the FMU), so
nothing propagates into the state. Every sample carries its stamp ``<prefix>_time`` among its
values.

Time stamps. An engine that steps slow components first (ECOS) shows the estimator a sample
stamped ahead of its clock (a 10 Hz GPS sample of t = 0.10 s at t = 0.01 s). Such a sample is
held until the estimator's clock reaches its stamp and fused then, so every engine fuses it at
the same instant up to one estimator step. A stamp further ahead than ``max_sample_lead``, or
not finite, is absurd: the sample is refused (counted in ``n_ignored`` and noted).

Health (the signal contract's common outputs, PX4 EKF2's conventions):

* ``<source>_test_ratio``: y²/(g²·S) of the source's last sample, innovation y, its variance S
  and the gate g in standard deviations; > 1: rejected (0 while the gate is off);
* ``<source>_rejected``: that source's samples rejected so far (``n_rejected``: all sources);
* ``h_valid``: initialized and a height source fused within ``aiding_timeout``;
* ``status``: the bits of :class:`Status` and, per source, those of :func:`source_bit`.

Height reset (PX4's height reset, with ``fault_detection``): when a height sample is rejected
and no height sample at all was fused for ``reset_timeout`` (every source disagrees with the
prediction), the estimator resets its height to that sample (:meth:`Estimator.reset_height`)
and counts it in ``n_height_resets``; a GPS vertical speed rejected for ``reset_timeout``
resets the speed the same way (PX4's velocity reset). A source whose samples stay rejected for
``reset_timeout`` while another source is fused is marked isolated in ``status`` until one of
its samples passes the gate again.

Bias test (with ``fault_detection``): a height source whose innovations average beyond the
gate over the last ``reset_timeout`` (a step smaller than one sample's gate but persistent),
and as far from those of another fused source closer to the prediction, is rejected, and
isolated after ``reset_timeout`` of it (:meth:`Estimator._biased`).

Re-referencing (with ``fault_detection``): an isolated height source with an offset state
(:meth:`Estimator.reset_offset`) whose innovations stay on one side is re-admitted with
that state reset onto it (:meth:`Estimator._rereference`).

Inputs outside any stream (``extra_inputs``, e.g. ``wind_speed``) have no count: they are read
with :meth:`Estimator.held_input`, which holds the last finite value over non-finite ones.
"""

import math
from abc import abstractmethod
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from enum import IntEnum, IntFlag
from functools import cached_property
from types import SimpleNamespace
from typing import ClassVar

from altfusion.component import Component
from altfusion.params import param


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
    def fields(self) -> tuple[str, ...]:
        """The inputs a sample carries: the values, then the time stamp."""
        return (*self.values, self.time)

    @cached_property
    def bounds(self) -> tuple[tuple[str, str, float], ...]:
        """(input, source charged, bound) of each value with a :data:`PLAUSIBLE_RANGE`."""
        return tuple((name, *PLAUSIBLE_RANGE[name]) for name in self.fields
                     if name in PLAUSIBLE_RANGE)


BARO = Stream("baro", ("baro_h",))
BARO_T = Stream("baro", ("baro_h", "baro_T"))
BARO_P = Stream("baro", ("baro_h", "baro_p"))
GPS = Stream("gps", ("gps_h",), "gps_fix")
GPS_QUALITY = Stream("gps", ("gps_h", "gps_vdop", "gps_nsat"), "gps_fix")
GPS_VZ = Stream("gps", ("gps_h", "gps_vz"), "gps_fix")
ACC = Stream("acc", ("acc_z",))
RADAR = Stream("radar", ("radar_h",), "radar_valid")
LASER = Stream("laser", ("laser_h",), "laser_valid")
BARO_ALL = Stream("baro", ("baro_h", "baro_p", "baro_T"))
GPS_ALL = Stream("gps", ("gps_h", "gps_vz", "gps_vdop", "gps_nsat"), "gps_fix")

HEIGHT_SOURCES = ("baro", "gps", "radar", "laser")
"""The sources that aid the height (their fusion keeps ``h_valid`` true)."""

SOURCES = (*HEIGHT_SOURCES, "gps_vz", "acc")
"""Every source with a test ratio and a rejection count, in the order of their status bits."""

ACC_CLIP = 0.95 * 16.0 * 9.80665
"""A vertical acceleration beyond 95 % of ±16 g (the full scale of common MEMS
accelerometers) is a clipped reading (PX4's PX4Accelerometer counts a raw sample beyond 95 %
of the range as clipping): the true acceleration lies somewhere beyond it, so the reading is
no measurement of it."""

PLAUSIBLE_RANGE = {"acc_z": ("acc", ACC_CLIP), "gps_vz": ("gps_vz", 1000.0),
                   **{f"{source}_h": (source, 1e5) for source in HEIGHT_SOURCES}}
"""Plausibility bounds of the sample values (source charged, largest magnitude): the
accelerometer's clipping level :data:`ACC_CLIP`; 1000 m/s, about Mach 3; ±100 km of height,
the Kármán line. A value beyond its bound cannot be a measurement: the sample is rejected as
that source's (test ratio value²/bound²) and takes no part in the step."""


BIAS_MIN_SAMPLES = 5
"""Fewest samples in a source's window before its bias test can reject it."""

BIAS_SIGMAS = 5.0
"""Widest threshold of the bias test, in standard deviations of a window's mean: a
consistent source's mean lies beyond it once in 1.7 million windows. An estimator whose
single-sample gate is wider (XuSHAEKF's 6, for its adaptive noise) keeps that gate for single
samples, not for the mean of many (at 6 a GNSS back 50 m off under a 37 m innovation spread
went unnoticed in 7 of 20 runs of the fault suite's gnss_outage_return_off)."""


READMIT_SIGMAS = 2.0
"""An isolated height source is re-admitted when the mean of its innovations over
``reset_timeout`` lies within this many standard deviations of that mean (95 % of the time
for a consistent source)."""

MAX_WINDOW_VALUE = 1e100
"""Innovations and variances entering a bias window are clipped to this magnitude, so that
its running sums stay finite."""


class InnovationWindow:
    """A height source's innovations y and their variances S over a span of time, with
    running sums: the mean ȳ = Σy/n and its variance ΣS/n² (independent samples)."""

    def __init__(self) -> None:
        self.samples: deque[tuple[float, float, float]] = deque()
        self.sum_y = 0.0
        self.sum_S = 0.0
        self.sigmas = BIAS_SIGMAS
        """The bias test's threshold for this source: its gate, :data:`BIAS_SIGMAS` at most."""

    @property
    def n(self) -> int:
        return len(self.samples)

    def add(self, now: float, y: float, S: float, span: float) -> None:
        """Add the sample (y, S) of time ``now`` and drop those older than ``span``."""
        y = min(max(y, -MAX_WINDOW_VALUE), MAX_WINDOW_VALUE)
        S = min(max(S, 0.0), MAX_WINDOW_VALUE)
        self.samples.append((now, y, S))
        self.sum_y += y
        self.sum_S += S
        while now - self.samples[0][0] > span:
            _, old_y, old_S = self.samples.popleft()
            self.sum_y -= old_y
            self.sum_S -= old_S

    def mean(self) -> float:
        return self.sum_y / self.n

    def mean_variance(self) -> float:
        return max(self.sum_S, 0.0) / (self.n * self.n)


class Status(IntFlag):
    """The estimator-wide bits of the ``status`` output (bits 0-7)."""

    INITIALIZED = 1 << 0
    """The filter has started (from its first usable sample)."""
    DEAD_RECKONING = 1 << 1
    """Initialized, but no height sample fused for ``aiding_timeout``: ``h_valid`` false."""
    HEIGHT_RESET = 1 << 2
    """The height was reset to a source in this step."""
    SAMPLE_HELD = 1 << 3
    """A sample stamped ahead of the estimator's clock waits until due."""


STEP_BITS = SimpleNamespace(**{flag.name: int(flag) for flag in Status})
"""The :class:`Status` masks as plain ints (set at every step: IntFlag arithmetic is slow)."""


class SourceBit(IntEnum):
    """Per-source bits of ``status``: bit 8 + 4·i + this, i the source's index in
    :data:`SOURCES`."""

    FUSED = 0
    """The source's last sample was fused."""
    REJECTED = 1
    """The source's last sample was rejected by its gate."""
    ISOLATED = 2
    """The height source is declared faulty: rejected for ``reset_timeout`` while another
    height source that pins the height tighter was fused (height sources only)."""


def source_bit(source: str, bit: SourceBit) -> int:
    """The ``status`` mask of ``bit`` of ``source``."""
    return _SOURCE_BITS[source, bit]


_SOURCE_BITS = {(source, bit): 1 << (8 + 4 * index + bit)
                for index, source in enumerate(SOURCES) for bit in SourceBit}
"""Every source's ``status`` masks, computed once (:func:`source_bit` runs at every sample)."""


def status_bits() -> dict[str, int]:
    """Every documented ``status`` bit: name -> mask."""
    bits = {flag.name: int(flag) for flag in Status}
    bits.update({f"{source.upper()}_{bit.name}": source_bit(source, bit)
                 for source in SOURCES for bit in SourceBit
                 if bit is not SourceBit.ISOLATED or source in HEIGHT_SOURCES})
    return bits


@dataclass(frozen=True)
class HealthParams:
    """The parameters every estimator shares (health and sample timing); each estimator's
    parameters extend these."""

    aiding_timeout: float = param(5.0, "s", "h_valid turns false when no height sample was "
                                            "fused for this long (PX4 EKF2: 5 s)", positive=True)
    fault_detection: bool = param(True, None, "Height reset when every height source "
                                              "disagrees and the isolation flags; false: the "
                                              "paper's algorithm")
    reset_timeout: float = param(2.5, "s", "A height source rejected this long while no "
                                           "source is fused resets the height; rejected this "
                                           "long while another is fused, it is isolated",
                                 positive=True)
    max_vz: float = param(50.0, "m/s", "Largest plausible vertical speed: bounds the jump of a "
                                       "height between two samples where the estimator has "
                                       "no speed state to predict it", positive=True)
    max_sample_lead: float = param(1.0, "s", "A sample stamped at most this far ahead of the "
                                             "estimator's clock is held until due; further: "
                                             "refused", min=0.0)


MAX_DELAY = 0.5
"""Longest sensor delay, s: the state is taken back along the model over the delay with its
process noise neglected (PX4 bounds its sensor delays at 0.3-0.5 s too)."""


def stream_inputs(streams: tuple[Stream, ...]) -> tuple[str, ...]:
    """The input names of ``streams`` in declaration order: values, count, time stamp,
    validity flag."""
    names: list[str] = []
    for stream in streams:
        for name in (*stream.values, stream.count, stream.time,
                     *((stream.valid,) if stream.valid else ())):
            if name not in names:
                names.append(name)
    return tuple(names)


def stream_sources(streams: tuple[Stream, ...]) -> tuple[str, ...]:
    """The sources of ``streams`` in :data:`SOURCES` order: each stream's prefix, and
    ``gps_vz`` for a stream carrying the GPS vertical speed."""
    present = {s.prefix for s in streams} | {"gps_vz" for s in streams if "gps_vz" in s.values}
    return tuple(source for source in SOURCES if source in present)


class Estimator(Component):
    """Base of the estimators: inputs from ``streams``, outputs ``h_est``, ``vz_est``,
    ``h_std`` and the health outputs.

    Subclasses implement :meth:`propagate` (time update over one step) and :meth:`fuse` (one
    new sample of one stream) or :meth:`fuse_samples` (all new samples of a step together),
    set ``started`` when the filter starts, ``h_est``, ``vz_est``, ``h_std`` and their
    diagnostics; they pass each sample through :meth:`gate` (or :meth:`accept` for an
    ungated one) and implement :meth:`reset_height`.
    """

    streams: ClassVar[tuple[Stream, ...]]
    extra_inputs: ClassVar[tuple[str, ...]] = ()
    """Real inputs outside any stream (no count), read with :meth:`held_input`."""
    stated_aliases: ClassVar[dict[str, str]] = {}
    """A sensor error model's stated name (``baro_bias_psd``... of
    :mod:`altfusion.systems.error_models`) -> this estimator's parameter of the same quantity
    and unit under another name (BaselineKF's ``bias_psd``)."""

    def __init__(self, params=None, **kwargs):
        for name in self.extra_inputs:
            setattr(self, name, 0.0)
        for stream in self.streams:
            for name in stream.values:
                setattr(self, name, 0.0)
            setattr(self, stream.count, 0)
            setattr(self, stream.time, 0.0)
            if stream.valid:
                setattr(self, stream.valid, True)
        self.h_est = 0.0
        self.vz_est = 0.0
        self.h_std = 0.0
        super().__init__(params, **kwargs)

    @classmethod
    def sources(cls) -> tuple[str, ...]:
        """The sources of this estimator's streams (test ratio and rejection count each)."""
        return stream_sources(cls.streams)

    @classmethod
    def stated_parameters(cls, stated: Mapping[str, float]) -> dict[str, float]:
        """The parameter values that tell this estimator the sensor error models ``stated``
        (stated name -> value in that name's unit): the parameter of the stated name, else
        its alias (:attr:`stated_aliases`); a model it has no parameter for is left out."""
        fields = cls.Params.__dataclass_fields__
        values = {}
        for name, value in stated.items():
            target = name if name in fields else cls.stated_aliases.get(name)
            if target is not None:
                values[target] = value
        return values

    def reset(self) -> None:
        self._last_count = {s.prefix: getattr(self, s.count) for s in self.streams}
        self._seen = {prefix for prefix, count in self._last_count.items() if count > 0}
        self._held: dict[str, dict[str, float]] = {}
        """Samples stamped ahead of the clock, by stream prefix (a key of plain data: a
        saved and restored state holds copies of the Stream constants, never the same ones)."""
        self.n_rejected = 0
        self.n_ignored = 0
        self.n_height_resets = 0
        self.started = False
        for source in self.sources():
            setattr(self, f"{source}_test_ratio", 0.0)
            setattr(self, f"{source}_rejected", 0)
        self._source_status = 0
        self._rejected_since: dict[str, float] = {}
        self._last_aiding = -math.inf
        self._last_fused: dict[str, float] = {}
        self._gate_width: dict[str, float] = {}
        self._innovations: dict[str, InnovationWindow] = {}
        self._disagrees: dict[str, bool] = {}
        self._step_flags = 0
        self._held_inputs: dict[str, float] = {}
        self._bad_inputs: set[str] = set()
        for name in self.extra_inputs:
            value = float(getattr(self, name))
            self._held_inputs[name] = value if math.isfinite(value) else 0.0
        self.initialize_filter()
        self._publish_health()

    @abstractmethod
    def initialize_filter(self) -> None:
        """Set the filter's initial state and outputs from the parameters."""

    @abstractmethod
    def propagate(self, dt: float) -> None:
        """Time update over one step of ``dt`` seconds."""

    @abstractmethod
    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """Move the height estimate by ``innovation`` onto a sample of ``source`` whose
        variance is ``variance`` (PX4's height reset): the height's variance becomes the
        sample's, its correlations with the other states zero."""

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        """Measurement update with one new, valid, finite sample of ``stream``."""
        raise NotImplementedError(f"{type(self).__name__} must override fuse or fuse_samples")

    def fuse_samples(self, samples: dict[Stream, dict[str, float]]) -> None:
        """Fuse the new samples of this step; by default one by one in ``streams`` order."""
        for stream, sample in samples.items():
            self.fuse(stream, sample)

    def update(self) -> None:
        self._step_flags = 0
        self.propagate(self.dt)
        samples = {}
        last_count = self._last_count
        for stream in self.streams:
            count = getattr(self, stream.count)
            if count != last_count[stream.prefix]:
                sample = self._new_sample(stream, count)
                if sample is not None:
                    self._held[stream.prefix] = sample
            sample = self._held.get(stream.prefix)
            if sample is not None and self._due(sample[stream.time]):
                del self._held[stream.prefix]
                samples[stream] = sample
        self.fuse_samples(samples)
        self._publish_health()

    def _due(self, stamp: float) -> bool:
        """True if a sample stamped ``stamp`` is not ahead of the clock (rounding aside)."""
        now = self.time
        return stamp <= now + 1e-9 * max(1.0, abs(now))

    def _new_sample(self, stream: Stream, count: int) -> dict[str, float] | None:
        """The sample of ``stream``, whose count changed to ``count``, if it is valid, finite,
        plausible and stamped at most ``max_sample_lead`` ahead, else None."""
        last = self._last_count[stream.prefix]
        self._last_count[stream.prefix] = count
        if count > last + 1:
            self.note(f"{stream.prefix}: {count - last - 1} sample(s) arrived between two "
                      f"estimator steps; only the latest is fused")
        if stream.valid and not getattr(self, stream.valid):
            return None
        sample = {name: float(getattr(self, name)) for name in stream.fields}
        if not all(map(math.isfinite, sample.values())):
            bad = {name: value for name, value in sample.items() if not math.isfinite(value)}
            self._ignore(stream, f"non-finite sample ignored {bad}")
            return None
        lead = sample[stream.time] - self.time
        if lead > self.params.max_sample_lead:
            self._ignore(stream, f"sample stamped {lead:.4g} s ahead of the clock (more than "
                                 f"max_sample_lead) refused")
            return None
        for name, source, bound in stream.bounds:
            value = sample[name]
            if abs(value) > bound:
                self.gate(source, value, 1.0, 0.0, bound)
                return None
        if stream.prefix in self._held:
            self.note(f"{stream.prefix}: a held sample was replaced before it was due")
        if lead > 0.0:
            self._step_flags |= STEP_BITS.SAMPLE_HELD
        self._seen.add(stream.prefix)
        return sample

    def _ignore(self, stream: Stream, message: str) -> None:
        self.n_ignored += 1
        self.note(f"{stream.prefix}: {message}")

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

    # ------------------------------------------------------------------ health
    def gate(self, source: str, innovation: float, variance: float, sigmas: float,
             bound: float | None = None, aids_height: bool = True) -> bool:
        """The innovation gate of ``source``: True if the sample may be fused.

        test ratio = y²/(g²·S) (PX4), with g = ``sigmas`` standard deviations of the
        innovation variance S (``sigmas <= 0``: no gate, ratio 0), or y²/``bound``² for a
        plausibility bound on the value itself. A height sample rejected by its gate (never by
        a bound) resets the height instead when no height source was fused for
        ``reset_timeout`` (every source disagrees; with ``fault_detection``): then the sample
        is consumed and False returned.
        ``aids_height`` false: the source calibrates another (its fusion does not keep
        ``h_valid`` true).
        """
        if bound is not None:
            ratio = innovation * innovation / (bound * bound)
        elif sigmas > 0.0:
            ratio = innovation * innovation / (sigmas * sigmas * max(variance, 1e-300))
        else:
            ratio = 0.0
        setattr(self, f"{source}_test_ratio", min(ratio, 1e300))
        biased = bound is None and sigmas > 0.0 and self._biased(source, innovation,
                                                                 variance, sigmas)
        if ratio <= 1.0 and not biased:
            if bound is None and sigmas > 0.0:
                self._gate_width[source] = sigmas * math.sqrt(max(variance, 0.0))
            self.accept(source, aids_height)
            return True
        now, p = self.time, self.params
        since = self._rejected_since.setdefault(source, now)
        if bound is None and p.fault_detection and self.started and (
                (source in HEIGHT_SOURCES and now - self._last_aiding >= p.reset_timeout
                 and not self.contradicted(source, innovation))
                or (source == "gps_vz" and now - since >= p.reset_timeout)):
            self.height_reset(source, innovation, variance,
                              f"no height source fused for {now - self._last_aiding:.3g} s")
            return False
        if bound is None and self._rereference(source, innovation, variance, since):
            return False
        setattr(self, f"{source}_rejected", getattr(self, f"{source}_rejected") + 1)
        self.n_rejected += 1
        self._mark(source, SourceBit.REJECTED)
        if (now - since >= p.reset_timeout
                and (biased or self.contradicted(source, innovation))
                and not self.isolated(source)):
            self._source_status |= source_bit(source, SourceBit.ISOLATED)
            self.note(f"{source}: rejected for {now - since:.3g} s while other sources are "
                      f"fused: isolated until a sample passes the gate")
        self.note(f"{source}: sample rejected (innovation {innovation:.4g}, test ratio "
                  f"{ratio:.3g}{', persistently biased' if biased else ''})")
        return False

    def _rereference(self, source: str, innovation: float, variance: float,
                     since: float) -> bool:
        """Re-admit an isolated height source as a relative sensor (with ``fault_detection``):
        True if ``source`` has been rejected for twice ``reset_timeout`` (isolated for at
        least one), every innovation of its bias window has the same sign (a constant offset,
        not noise) and the estimator has an offset state for it
        (:meth:`reset_offset`), which then moves onto this sample; the sample is consumed
        and the source's window restarts. PX4's baro bias estimator re-learns a baro offset
        the same way while GNSS holds the height; a source without an offset state (the
        height reference) stays isolated."""
        p, now = self.params, self.time
        window = self._innovations.get(source)
        if not (p.fault_detection and source in HEIGHT_SOURCES
                and self.isolated(source)
                and now - since >= 2.0 * p.reset_timeout
                and window is not None and window.n >= BIAS_MIN_SAMPLES
                and (all(y > 0.0 for _, y, _ in window.samples)
                     or all(y < 0.0 for _, y, _ in window.samples))
                and self.reset_offset(source, innovation, variance)):
            return False
        del self._innovations[source]
        self._disagrees.pop(source, None)
        self.note(f"{source}: isolated for {now - since:.3g} s with a constant offset; its "
                  f"offset state reset by {innovation:.4g} m and the source re-admitted")
        self.accept(source)
        return True

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """Move the offset state of height source ``source`` by ``innovation`` onto a sample
        whose innovation variance is ``variance`` (that state's variance becomes it, its
        correlations zero) and return True; False (the default) if the estimator has no
        offset state for ``source``."""
        return False

    def _biased(self, source: str, innovation: float, variance: float, sigmas: float) -> bool:
        """The bias test of height source ``source`` (with ``fault_detection``): True if over
        the last ``reset_timeout`` (at least :data:`BIAS_MIN_SAMPLES` samples) the mean ȳ of
        its innovations is beyond ``sigmas`` (:data:`BIAS_SIGMAS` at most) standard
        deviations of that mean, √(S̄/n), and beyond as many from the mean of another height
        source fused within ``reset_timeout`` that lies closer to the prediction
        (:meth:`_agrees`): the source disagrees with a source that agrees better with the
        prediction.

        A step smaller than the gate of one sample (a 100 m GNSS step under a 30 m noise)
        passes every single-sample gate but not this one: for consistent white innovations
        ȳ/√(S̄/n) is a standard normal variable, beyond 5 once in 1.7 million. A prediction
        that lags every source alike (an overconfident filter in a climb) moves every mean
        alike and isolates none. Every sample enters the window, fused or not, clipped to
        the gate (one wild sample cannot bias the mean: it moves it by at most one gate
        half-width over n). An isolated source stays rejected while its own mean lies beyond
        :data:`READMIT_SIGMAS` standard deviations, whatever the other sources do (PX4: a GNSS
        back 50 m off is not re-admitted; the margin keeps a 50 m offset under a 30 m noise
        from slipping back in on a few low samples); it is re-admitted once its biased
        samples have left the window. A source found biased but not yet isolated stays biased
        on the same margin (hysteresis): a mean hovering about the threshold would otherwise
        let a sample in now and then, restart the ``reset_timeout`` to isolation and move
        the estimate onto the offset sample by sample (WhangGAEstimator's baro bias took a
        GNSS back 50 m off that way in 2 of 20 evaluation runs)."""
        if not (self.params.fault_detection and source in HEIGHT_SOURCES):
            return False
        now, timeout = self.time, self.params.reset_timeout
        window = self._innovations.setdefault(source, InnovationWindow())
        half_width = sigmas * math.sqrt(max(variance, 0.0))
        window.add(now, min(max(innovation, -half_width), half_width), variance, timeout)
        window.sigmas = threshold = min(sigmas, BIAS_SIGMAS)
        mean, spread = window.mean(), math.sqrt(window.mean_variance())
        if self.isolated(source):
            biased = window.n >= BIAS_MIN_SAMPLES and abs(mean) > READMIT_SIGMAS * spread
        else:
            level = READMIT_SIGMAS if self._disagrees.get(source, False) else threshold
            biased = window.n >= BIAS_MIN_SAMPLES and abs(mean) > level * spread and any(
                other != source and now - fused <= timeout
                and self._agrees(other, level, mean, spread)
                for other, fused in self._last_fused.items())
        self._disagrees[source] = biased
        return biased

    def _agrees(self, other: str, sigmas: float, mean: float, spread: float) -> bool:
        """True if height source ``other``'s innovation mean lies closer to the prediction
        than ``mean`` (spread ``spread``), each in its own standard deviations, and more than
        ``sigmas`` combined standard deviations from ``mean``: of two sources that disagree,
        the one further from the prediction is off. A source never gated (no window) counts
        as agreeing, with mean 0 known exactly.

        The other's mean need not pass the bias test itself: a prediction that is off too
        (BaoDriftEstimator holds the last accepted baro sample, 20 m noise and all) moves
        the means of both sources, and a GNSS 28 m from it (4.7 of its standard deviations)
        still tells a baro 130 m from it (31) to be the failed one."""
        window = self._innovations.get(other)
        if window is None or window.n == 0:
            return abs(mean) > sigmas * spread
        other_mean, other_variance = window.mean(), window.mean_variance()
        return (abs(other_mean) * spread < abs(mean) * math.sqrt(other_variance)
                and abs(mean - other_mean) > sigmas * math.sqrt(spread**2 + other_variance))

    def height_reset(self, source: str, innovation: float, variance: float,
                     reason: str) -> None:
        """PX4's height reset onto a sample of ``source`` (:meth:`reset_height`), counted in
        ``n_height_resets``, flagged in ``status`` for this step, noted with ``reason`` and
        the sample accepted."""
        self.reset_height(source, innovation, variance)
        self.n_height_resets += 1
        self._step_flags |= STEP_BITS.HEIGHT_RESET
        self.note(f"{source}: {reason}; height reset by {innovation:.4g} m to this source "
                  f"(reset {self.n_height_resets})")
        self.accept(source)

    def jump_variance(self, noise_variance: float, elapsed: float) -> float:
        """Variance of a height's jump from its last accepted sample, ``elapsed`` s after the
        source's previous sample (accepted or not: a failed sensor's step stays rejected),
        for an estimator without a speed state: twice the sample noise, plus the motion
        ``max_vz`` allows counted as one standard deviation."""
        return 2.0 * noise_variance + (self.params.max_vz * elapsed) ** 2

    def accept(self, source: str, aids_height: bool = True) -> None:
        """Record that a sample of ``source`` is fused (a height source aids the height unless
        ``aids_height`` is false)."""
        self._rejected_since.pop(source, None)
        self._source_status &= ~source_bit(source, SourceBit.ISOLATED)
        self._mark(source, SourceBit.FUSED)
        if aids_height and source in HEIGHT_SOURCES:
            self._last_aiding = self.time
            self._last_fused[source] = self.time

    def isolated(self, source: str) -> bool:
        """True while height source ``source`` is isolated (its ISOLATED bit in ``status``)."""
        return bool(self._source_status & source_bit(source, SourceBit.ISOLATED))

    def contradicted(self, source: str, innovation: float) -> bool:
        """True if another height source, fused within ``reset_timeout`` and passing its
        own gate since, pins the height tighter than ``innovation`` (:meth:`_pin`: its gate
        half-width or the reach of its bias window's mean), or if ``source`` failed its
        last bias test (:meth:`_biased`: persistently off while another source agrees): then
        a sample of ``source`` that far from the prediction is the faulty one (with
        ``fault_detection``; else False). A source too coarse to tell (a 3 m GPS against a
        2 m terrain step under the laser) contradicts nothing."""
        if not (self.params.fault_detection and source in HEIGHT_SOURCES):
            return False
        if self._disagrees.get(source, False):
            return True
        now, timeout = self.time, self.params.reset_timeout
        return any(other != source and now - fused <= timeout
                   and abs(innovation) > self._pin(other)
                   for other, fused in self._last_fused.items())

    def _pin(self, source: str) -> float:
        """How far from the prediction height source ``source`` lets the height be: its
        last gate half-width or, tighter, the mean of its bias window plus that window's
        threshold (:data:`BIAS_SIGMAS` at most) in standard deviations of the mean (a 30 m
        GNSS at 10 Hz pins the height to 30 m over 2.5 s, not to one sample's 150 m gate)."""
        pin = self._gate_width.get(source, math.inf)
        window = self._innovations.get(source)
        if window is not None and window.n >= BIAS_MIN_SAMPLES:
            pin = min(pin, abs(window.mean()) + window.sigmas * math.sqrt(window.mean_variance()))
        return pin

    def _mark(self, source: str, bit: SourceBit) -> None:
        """Set ``bit`` (FUSED or REJECTED) of ``source`` and clear the other."""
        fused = source_bit(source, SourceBit.FUSED)
        rejected = source_bit(source, SourceBit.REJECTED)
        self._source_status &= ~(fused | rejected)
        self._source_status |= fused if bit is SourceBit.FUSED else rejected

    def _publish_health(self) -> None:
        """``h_valid`` and ``status`` at the end of a step."""
        flags = self._step_flags
        aided = self.time - self._last_aiding <= self.params.aiding_timeout
        if self.started:
            flags |= STEP_BITS.INITIALIZED
            if not aided:
                flags |= STEP_BITS.DEAD_RECKONING
        self.h_valid = bool(self.started and aided)
        self.status = flags | self._source_status
