"""The estimator's skeleton: sample intake, one aid source per sensor, gating, health.

A measurement update happens exactly once per new sample of a stream
(:mod:`~altfusion.estimators.streams`: when its count changes), whatever the estimator's own
step; the time update runs at every step. A sample that is invalid or not finite is ignored
and noted (logged by the FMU), so nothing propagates into the state; a value beyond its
plausibility bound is rejected as its source's.

Time stamps (:mod:`~altfusion.estimators.intake`): a sample stamped ahead of the clock is
held until due; one stamped further ahead than ``max_sample_lead``, further behind than
``max_sample_delay`` or before its stream's last sample is refused and counted in
``<prefix>_rejected``.

Each source (``baro``, ``gps``, ``radar``, ``laser``, ``gps_vz``, ``acc``) has an
:class:`~altfusion.estimators.aid_source.AidSource`; :meth:`Estimator.gate` gives each gated
sample a :class:`~altfusion.estimators.aid_source.Verdict`. Health outputs (the signal
contract's, PX4 EKF2's conventions):

* ``<source>_test_ratio``: y²/(g²·S) of the source's last sample, innovation y, its variance S
  and the gate g in standard deviations; > 1: rejected (0 while the gate is off);
* ``<source>_rejected``: that source's samples rejected so far (``n_rejected``: all sources);
* ``h_valid``: initialized and a height source fused within ``aiding_timeout`` (and each
  of :attr:`Estimator.required_sources` delivering);
* ``status``: the bits of :mod:`~altfusion.estimators.health`.

With ``fault_detection`` the fault layer (:mod:`~altfusion.estimators.fault_detection`:
bias test, isolation, resets, re-referencing) decides what becomes of a rejected sample.

Inputs outside any stream (``extra_inputs``, e.g. ``wind_speed``) have no count: they are read
with :meth:`Estimator.held_input`, which holds the last finite value over non-finite ones.
"""

import math
from abc import abstractmethod
from collections.abc import Mapping
from typing import ClassVar

from altfusion.component import Component
from altfusion.estimators.accelerometer_check import AccelerometerCheck
from altfusion.estimators.aid_source import AidSource, Verdict
from altfusion.estimators.gate import EstimatorHealth
from altfusion.estimators.gating import Gating
from altfusion.estimators.health import (
    HEIGHT_SOURCES,
    SourceBit,
    Status,
    source_bit,
    status_bits,
)
from altfusion.estimators.health_params import HealthParams
from altfusion.estimators.intake import SampleIntake
from altfusion.estimators.streams import Stream, stream_inputs, stream_sources

__all__ = ["HEIGHT_SOURCES", "MAX_DELAY", "AidSource", "Estimator", "HealthParams",
           "SourceBit", "Status", "Verdict", "source_bit", "status_bits"]

MAX_DELAY = 0.5
"""Longest sensor delay, s: the state is taken back along the model over the delay with its
process noise neglected (PX4 bounds its sensor delays at 0.3-0.5 s too)."""


def _source_output(index: int, field: str) -> property:
    """The output ``<source>_<field>`` of the estimator's aid source ``index``."""
    return property(lambda self: getattr(self.aid_sources[index], field),
                    doc=f"{field} of aid source {index}")


class Estimator(SampleIntake, Gating, Component):
    """Base of the estimators: inputs from ``streams``, outputs ``h_est``, ``vz_est``,
    ``h_std`` and the health outputs.

    Subclasses implement :meth:`propagate` (time update over one step) and :meth:`fuse` (one
    new sample of one stream) or :meth:`fuse_samples` (all new samples of a step together),
    set ``started`` when the filter starts, ``h_est``, ``vz_est``, ``h_std`` and their
    diagnostics; they pass each sample through :meth:`gate` (or :meth:`accept` for an
    ungated one) and implement :meth:`reset_height`.
    """

    acc_drives_prediction: ClassVar[bool] = True
    """The accelerometer is the prediction's input: the height sources' disagreement with the
    prediction judges it too (else only its scatter: :mod:`.accelerometer_check`)."""

    required_sources: ClassVar[dict[str, str]] = {}
    """Sources the algorithm cannot do without -> why (xu2016's accelerometer, its model's
    input): ``h_valid`` is false while one has delivered nothing for ``aiding_timeout``."""

    scatter_checked: ClassVar[tuple[str, ...]] = ()
    """Sources the estimator checks on their samples' scatter itself, not the fault layer on
    their innovations (:meth:`~altfusion.estimators.gating.Gating.attach_shown_noise`)."""

    stated_aliases: ClassVar[dict[str, str]] = {}
    """A sensor error model's stated name (``baro_bias_psd``... of
    :mod:`altfusion.systems.error_models`) -> this estimator's parameter of the same quantity
    and unit under another name (BaselineKF's ``bias_psd``)."""

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if "streams" in cls.__dict__:
            cls.gnss_speed_stream = next((s for s in cls.streams if s.gnss_speed), None)
            cls.baro_stream = next((s for s in cls.streams if s.prefix == "baro"), None)
            for index, source in enumerate(cls.sources()):
                setattr(cls, f"{source}_test_ratio", _source_output(index, "test_ratio"))
                setattr(cls, f"{source}_rejected", _source_output(index, "rejected"))

    def __init__(self, params=None, **kwargs):
        self.declare_inputs()
        self.h_est = 0.0
        self.vz_est = 0.0
        self.h_std = 0.0
        super().__init__(params, **kwargs)

    @property
    def h_std(self) -> float:
        """The published ``h_std``: the filter's, times √ of the health's ``std_factor``."""
        return self._h_std * math.sqrt(self.health.std_factor)

    @h_std.setter
    def h_std(self, value: float) -> None:
        self._h_std = value

    @classmethod
    def sources(cls) -> tuple[str, ...]:
        """The sources of this estimator's streams (test ratio and rejection count each)."""
        return stream_sources(cls.streams)

    @classmethod
    def declared_inputs(cls) -> tuple[str, ...]:
        """Every input of the estimator: its streams' inputs, then its extra inputs."""
        names = stream_inputs(cls.streams)
        return names + tuple(n for n in cls.extra_inputs if n not in names)

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
        self.reset_intake()
        self.n_rejected = 0
        self.n_height_resets = 0
        self.started = False
        self.aid_sources = tuple(AidSource(source) for source in self.sources())
        self.aid = {source.name: source for source in self.aid_sources}
        """The aid sources by name."""
        health = self.health = EstimatorHealth(
            self.aid_sources, tuple(self.aid[name] for name in self.required_sources),
            self.params)
        """The estimator's health beyond its sources' (:class:`~.gate.EstimatorHealth`)."""
        self.attach_shown_noise()
        noise = self.accelerometer_noise()
        judges = (*health.heights, *(s for s in self.aid_sources if s.name == "gps_vz")) \
            if self.acc_drives_prediction else ()
        self.acc_check = health.acc_check = AccelerometerCheck(
            noise, judges, self.accelerometer_noise_stated()) if (
            noise is not None and self.params.fault_detection) else None
        """PX4's bad_acc_vertical check of the accelerometer (fault layer; None without)."""
        self.initialize_filter()
        self.h_valid, self.status = health.publish(self.started, self.clock.now)

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

    def checks_own_noise(self) -> bool:
        """The estimator checks its sources' stated noise itself, with these parameters
        (AltitudeEKF's ``adaptive_noise``, XuSHAEKF's adaptive filter:
        :class:`~altfusion.estimators.noise_check.NoiseCheck`); else (the default), with
        ``fault_detection``, the fault layer checks them against the filter's innovations
        (:class:`~altfusion.estimators.noise_check.ShownNoise`)."""
        return False

    def accelerometer_noise(self) -> float | None:
        """The accelerometer's stated noise, 1σ per sample (m/s²), for an estimator that
        uses one (its noise is then checked and inflated while found bad:
        :mod:`~altfusion.estimators.accelerometer_check`); None (the default): none."""
        return None

    def accelerometer_noise_stated(self) -> bool:
        """The user stated :meth:`accelerometer_noise` (True, the default); False: it is a
        typical starting value, and the check measures the noise both ways."""
        return True

    def reset_offset(self, source: str, innovation: float, variance: float) -> bool:
        """Move the offset state of height source ``source`` by ``innovation`` onto a sample
        whose innovation variance is ``variance`` (that state's variance becomes it, its
        correlations zero) and return True; False (the default) if the estimator has no
        offset state for ``source``."""
        return False

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        """Measurement update with one new, valid, finite sample of ``stream``."""
        raise NotImplementedError(f"{type(self).__name__} must override fuse or fuse_samples")

    def fuse_samples(self, samples: dict[Stream, dict[str, float]]) -> None:
        """Fuse the new samples of this step; by default one by one in ``streams`` order."""
        for stream, sample in samples.items():
            self.fuse(stream, sample)

    def update(self) -> None:
        clock = self.clock
        self.propagate(clock.step_size)
        self.fuse_samples(self.due_samples())
        if self.acc_check is not None and self.started:
            self.acc_check.step(clock.now)
        self.h_valid, self.status = self.health.publish(self.started, clock.now)
