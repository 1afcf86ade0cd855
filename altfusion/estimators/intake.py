"""Sample intake: an estimator's stream inputs, new samples, held samples, plausibility.

A measurement update happens exactly once per new sample (its count changed). A frame
flagged invalid (its validity flag false: a rangefinder out of its range sends one every
period) is no sample: neither fused nor counted, only shown to
:meth:`SampleIntake.frame_invalid` (AltitudeEKF reads the laser's as the ground it may stand
on). A sample that is not finite is ignored and noted (``n_ignored``); a value beyond its
plausibility bound (:data:`~.streams.PLAUSIBLE_RANGE`) is rejected as its source's. With
``fault_detection`` a reading repeated bit for bit ``stuck_samples`` times in a row
(:mod:`~altfusion.estimators.stuck`) is left out of its sample (the sample dropped when none
of its measured values is left), its source refused and isolated, or, a GNSS reading while
the receiver may hold still (the baro shows no climb: :meth:`SampleIntake._gnss_at_rest`),
only held. An auxiliary value (the air temperature beside the baro height) outside its
plausible interval (:data:`~.streams.PLAUSIBLE_AUXILIARY`) is left out of the sample, which
is fused without it (the estimator reads it with ``sample.get``); each counts in
``n_ignored``, the first of a run is noted.

Time stamps. A sample stamped ahead of the estimator's clock is held until due: an engine
that steps slow components first (ECOS) shows the estimator a 10 Hz GPS sample of t = 0.10 s
at t = 0.01 s, and every engine then fuses it at the same instant up to one estimator step.
A sample whose stamp cannot be the present one is refused, counted in ``<prefix>_rejected``
(and ``n_rejected``), noted and flagged in ``status`` (``SAMPLE_REFUSED``) for the step:

* from the future: stamped more than ``max_sample_lead`` ahead of the clock;
* stale: stamped more than ``max_sample_delay`` behind the clock (a GNSS sample 10 s old
  fused as if current would move the height by 10 s of climb);
* out of order: stamped before the last sample taken from the same stream.

Inputs outside any stream (``extra_inputs``) are read with :meth:`SampleIntake.held_input`.

The work of every step is :mod:`~altfusion.estimators.arrivals`' (one
:class:`~altfusion.estimators.arrivals.StreamIntake` per stream, compiled); this mixin
connects it to the estimator and holds the stuck check's use of the estimator's sources.
"""

import math
from functools import partial
from typing import ClassVar

from altfusion.estimators.arrivals import Arrivals
from altfusion.estimators.streams import GNSS, Stream
from altfusion.estimators.stuck import StuckCheck, StuckReadings, refuse_stuck


class SampleIntake:
    """The intake half of :class:`~altfusion.estimators.base.Estimator` (a mixin: it uses
    the component's clock, parameters, notes and the estimator's aid sources)."""

    streams: ClassVar[tuple[Stream, ...]]
    extra_inputs: ClassVar[tuple[str, ...]] = ()
    """Real inputs outside any stream (no count), read with :meth:`held_input`."""
    gnss_speed_stream: ClassVar[Stream | None] = None
    """The stream carrying the GNSS's heights and vertical speed, if any (set with
    ``streams``: a class attribute, never part of a saved state)."""
    baro_stream: ClassVar[Stream | None] = None
    """The baro's stream, if any (set with ``streams``): its heights tell whether the vehicle
    climbs while a GNSS reading repeats."""

    def declare_inputs(self) -> None:
        """Every stream input and extra input at its default (before any is given)."""
        for name in self.extra_inputs:
            setattr(self, name, 0.0)
        for stream in self.streams:
            for name in stream.values:
                setattr(self, name, 0.0)
            setattr(self, stream.count, 0)
            setattr(self, stream.time, 0.0)
            if stream.valid:
                setattr(self, stream.valid, True)

    def reset_intake(self) -> None:
        """Take the present counts as seen; no sample held; extra inputs held as given."""
        self.arrivals = Arrivals(self, self.streams, self.extra_inputs)
        """What the streams delivered (:mod:`~altfusion.estimators.arrivals`)."""
        params = self.params
        self.stuck = StuckReadings(self.sources(), params.stuck_samples) if (
            params.fault_detection and params.stuck_samples > 0) else None
        """The stuck check of the readings (fault layer; None without)."""

    @property
    def n_ignored(self) -> int:
        """Samples and values ignored so far (the output ``n_ignored``)."""
        return self.arrivals.n_ignored

    def due_samples(self) -> dict[Stream, dict[str, float]]:
        """The samples to fuse in this step: the new ones not stamped ahead of the clock and
        the held ones now due, by stream (:meth:`~.arrivals.Arrivals.due`)."""
        params = self.params
        arrivals = self.arrivals
        samples = arrivals.due(self, self.streams, self.clock.now, params.max_sample_lead,
                               params.max_sample_delay)
        if arrivals.flags:
            self.health.step_flags |= arrivals.flags
        if self.stuck is not None:
            if samples:
                return self._without_stuck(samples)
            self.stuck.found = ()
        return samples

    def _without_stuck(self, samples: dict[Stream, dict[str, float]],
                       ) -> dict[Stream, dict[str, float]]:
        """``samples`` without their stuck readings (:func:`~.stuck.refuse_stuck`): each
        left out of its sample, a sample left without a measured value dropped; a GNSS
        reading repeated while the receiver holds still (:meth:`_gnss_at_rest`) only held."""
        stuck = self.stuck
        found = stuck.find(samples, self.clock.now)
        gnss = samples.get(self.gnss_speed_stream) if self.gnss_speed_stream else None
        if gnss is not None:
            self._watch_receiver(gnss)
        if stuck.baro_followed():
            self._follow_baro(samples)
        if not found:
            stuck.found = ()
            return samples
        stuck.found = tuple(source for _, _, source in found)
        samples = dict(samples)
        checks = stuck.checks
        for stream, name, source in found:
            sample = samples[stream]
            check = checks[source]
            at_rest = partial(self._gnss_at_rest, sample, check) if source in GNSS else None
            if refuse_stuck(check, self.aid[source], sample[name], self.note, at_rest) and \
                    self.started and check.since <= self.health.started_at:
                self.restart_without(source)
            remaining = {key: value for key, value in sample.items() if key != name}
            if any(value in remaining for value, _ in stream.checked):
                samples[stream] = remaining
            else:
                del samples[stream]
        return samples

    def _follow_baro(self, samples: dict[Stream, dict[str, float]]) -> None:
        """Follow the baro's heights while a GNSS reading repeats (:meth:`_gnss_at_rest`;
        :meth:`~.stuck.StuckReadings.baro_followed`, which forgets them when the GNSS's
        readings change); a stuck baro shows nothing."""
        stuck = self.stuck
        baro = samples.get(self.baro_stream)
        if baro is None or stuck.checks["baro"].repeats >= stuck.checks["baro"].limit:
            return
        stuck.baro_run.follow(baro["baro_time"], baro["baro_h"], self.baro_height_sigma,
                              self.params.gate_sigma)

    def _watch_receiver(self, gnss: dict[str, float]) -> None:
        """Follow the GNSS receiver's heights while its vertical speed reads exactly 0,
        restarted when it reads other than 0."""
        run = self.stuck.gnss_still
        if gnss["gps_vz"] != 0.0:
            if run.n:
                run.restart()
            return
        run.follow(gnss["gps_time"], gnss["gps_h"], partial(self.gnss_height_sigma, gnss),
                   self.params.gate_sigma)

    def _gnss_at_rest(self, sample: dict[str, float], check: StuckCheck) -> bool:
        """The GNSS receiver of this ``sample``, whose reading (judged by ``check``) repeats,
        holds still: the baro's heights show no climb or descent (judged with
        :meth:`baro_height_sigma`); and, with the vertical speed, the receiver's heights
        since it last read other than 0 show none either (judged with
        :meth:`gnss_height_sigma`): :meth:`~.stuck.HeightSlope.moving`. A receiver in static
        hold repeats its height only while the vehicle does not move; one that repeats it
        under a climb is stuck, or its input unconnected. A climb that has moved the height
        less than the receiver's resolution since the reading's first repetition
        (:meth:`~.stuck.StuckCheck.hold`) does not count: a receiver read to 0.1 m holds a
        reading for seconds in a slow climb. Never without a gate."""
        gate = self.params.gate_sigma
        if gate <= 0.0:
            return False
        span, hold = self.clock.now - check.since, check.hold()
        runs = [(self.stuck.baro_run, self.baro_height_sigma())]
        if self.gnss_speed_stream is not None:
            runs.append((self.stuck.gnss_still, self.gnss_height_sigma(sample)))
        return not any(run.moving(sigma, gate) and run.moved(span) > hold
                       for run, sigma in runs)

    def baro_height_sigma(self) -> float:
        """The noise (1σ, m) the estimator takes for a baro height: √R_baro."""
        return math.sqrt(self.params.R_baro)

    def gnss_height_sigma(self, sample: dict[str, float]) -> float:
        """The noise (1σ, m) the estimator takes for this GNSS ``sample``'s height: the
        static-hold test judges the heights' slope with it. Only asked of an estimator whose
        GNSS stream carries the vertical speed."""
        raise NotImplementedError(f"{type(self).__name__} reads the GNSS vertical speed and "
                                  f"must give gnss_height_sigma")

    def frame_invalid(self, stream: Stream) -> None:
        """A new frame of ``stream`` arrived flagged invalid (a rangefinder out of its
        range): no sample; an estimator that reads something into it overrides this."""

    def has_sample(self, prefix: str) -> bool:
        """True once the stream ``prefix`` has delivered a valid sample (or had one at the
        start): until then its input holds a placeholder, not a measurement."""
        return prefix in self.arrivals.seen

    def held_input(self, name: str) -> float:
        """The extra input ``name``, or its last finite value if it is not finite now.

        A non-finite value counts in ``n_ignored``; the first of a run of them is noted."""
        return self.arrivals.held(self, name)
