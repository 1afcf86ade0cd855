"""One sample through its source's gate, and the health published at the end of a step.

The per-sample and per-step work of :mod:`~altfusion.estimators.gating` and
:class:`~altfusion.estimators.base.Estimator`, compiled (:data:`altfusion.compiled.COMPILED`):
:func:`gate_sample` (the test ratio, the bias test, the verdict of a sample that passes),
:func:`record_fused` and :meth:`EstimatorHealth.publish`, on the estimator's
:class:`EstimatorHealth`. What a rejected sample does to the estimator (the fault layer's
verdict, the rejection counted and noted) is its own methods' (``_resolve``, ``_reject``).
"""

import math
from typing import Any, Final

from altfusion.estimators import fault_detection as faults
from altfusion.estimators.accelerometer_check import AccelerometerCheck
from altfusion.estimators.aid_source import FUSED, AidSource, Verdict
from altfusion.estimators.health import STEP_BITS
from altfusion.estimators.restorable import Restorable

_INITIALIZED: Final = int(STEP_BITS.INITIALIZED)
_DEAD_RECKONING: Final = int(STEP_BITS.DEAD_RECKONING)
_BAD_ACC_VERTICAL: Final = int(STEP_BITS.BAD_ACC_VERTICAL)


class EstimatorHealth(Restorable):
    """The estimator's health beyond its sources' (PX4 EKF2's control and fault status): its
    aid sources, the status bits raised in the current step, when a height source last aided
    the height, when the filter started, the noise factor its sources' innovations show;
    :meth:`publish` gives ``h_valid`` and ``status`` at the end of a step. A native object
    (compiled), so that the per-sample and per-step work here reads native fields: read off
    the estimator, each would be a lookup in its ``__dict__`` through the interpreter."""

    __slots__ = ("sources", "heights", "required", "acc_check", "aiding_timeout",
                 "reset_timeout", "fault_detection", "step_flags", "last_aiding", "started_at",
                 "std_factor")

    def __init__(self, sources: tuple[AidSource, ...], required: tuple[AidSource, ...],
                 params: Any) -> None:
        self.sources = sources
        self.heights: tuple[AidSource, ...] = tuple(s for s in sources if s.height)
        """The height sources (their fusion keeps ``h_valid`` true; they can be isolated)."""
        self.required = required
        """The sources ``h_valid`` needs (:attr:`~.base.Estimator.required_sources`)."""
        self.acc_check: AccelerometerCheck | None = None
        """The estimator's accelerometer check (fault layer; None without)."""
        self.aiding_timeout = float(params.aiding_timeout)
        self.reset_timeout = float(params.reset_timeout)
        self.fault_detection = bool(params.fault_detection)
        self.step_flags = 0
        """The status bits raised in the current step (``SAMPLE_HELD``, ``HEIGHT_RESET``...)."""
        self.last_aiding = -math.inf
        """When a height source last aided the height."""
        self.started_at = math.inf
        """When the filter started (the first step it was started at the end of)."""
        self.std_factor = 1.0
        """The factor on the filter's variance of ``h`` in the published ``h_std``: the
        largest shown by the sources' :attr:`AidSource.shown` (1: as the filter computes)."""

    def accelerometer_suspect(self) -> bool:
        """True while the accelerometer check finds the prediction inconsistent with every
        height source (:mod:`~altfusion.estimators.accelerometer_check`): then the sources'
        disagreement is the prediction's fault, and no source is isolated for it."""
        check = self.acc_check
        return check is not None and check.suspect

    def publish(self, started: bool, now: float) -> tuple[bool, int]:
        """``h_valid`` and ``status`` at ``now``, the end of a step of an estimator whose
        filter is ``started`` or not; the step's bits are cleared for the next."""
        flags = self.step_flags
        self.step_flags = 0
        timeout = self.aiding_timeout
        aided = now - self.last_aiding <= timeout
        started_at = self.started_at
        if started:
            flags |= _INITIALIZED
            if not aided:
                flags |= _DEAD_RECKONING
            started_at = min(started_at, now)
            self.started_at = started_at
        valid = started and aided
        if valid:
            for source in self.required:
                if not now - max(source.last_fused, started_at) <= timeout:   # NaN: not valid
                    valid = False
                    break
        for source in self.sources:
            flags |= source.bits
        check = self.acc_check
        if check is not None and check.bad:
            flags |= _BAD_ACC_VERTICAL
        return valid, flags


def gate_sample(owner: Any, health: EstimatorHealth, source: AidSource, innovation: float,
                variance: float, sigmas: float, aids_height: bool, now: float) -> Verdict:
    """:meth:`~altfusion.estimators.gating.Gating.gate` (which documents it) of ``owner``,
    the estimator, whose health is ``health``, at ``now``."""
    shown = source.shown
    if shown is not None:
        shown.gated(innovation, variance)
        if shown.factor != 1.0 or health.std_factor != 1.0:
            variance *= shown.factor
            owner._show_noise()
    if sigmas > 0.0:
        ratio = innovation * innovation / (sigmas * sigmas * max(variance, 1e-300))
    else:
        ratio = 0.0
    source.test_ratio = min(ratio, 1e300)
    source.innovation, source.variance, source.last_gated = innovation, variance, now
    fault_detection = health.fault_detection
    biased = sigmas > 0.0 and fault_detection and faults.bias_test(
        source, health.heights, now, health.reset_timeout, innovation,
        variance, sigmas) and not source.noisy and not health.accelerometer_suspect()
    if ratio <= 1.0 and not biased:
        if sigmas > 0.0:
            source.gate_width = sigmas * math.sqrt(max(variance, 0.0))
        record_fused(health, source, aids_height, now)
        return FUSED
    if source.rejected_since is None:
        source.rejected_since = now
    if fault_detection:
        verdict = owner._resolve(source, innovation, variance)
        if verdict is not None:
            return verdict
    return owner._reject(source, innovation, ratio, biased)


def record_fused(health: EstimatorHealth, source: AidSource, aids_height: bool,
                 now: float) -> None:
    """A sample of ``source`` fused at ``now`` (a height source aids the height unless
    ``aids_height`` is false): :meth:`~altfusion.estimators.gating.Gating.accept`."""
    source.fused(now, aids_height)
    if aids_height and source.height:
        health.last_aiding = now
