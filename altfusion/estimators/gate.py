"""One sample through its source's gate, and the health published at the end of a step.

The per-sample and per-step work of :mod:`~altfusion.estimators.gating` and
:class:`~altfusion.estimators.base.Estimator`, compiled (:data:`altfusion.compiled.COMPILED`):
:func:`gate_sample` (the test ratio, the bias test, the verdict of a sample that passes),
:func:`record_fused` and :func:`publish_health`. The estimator is passed to each call; what a
rejected sample does to it (the fault layer's verdict, the rejection counted and noted) is
its own methods' (``_resolve``, ``_reject``).
"""

import math
from typing import Any, Final

from altfusion.estimators import fault_detection as faults
from altfusion.estimators.aid_source import FUSED, AidSource, Verdict
from altfusion.estimators.health import STEP_BITS

_INITIALIZED: Final = int(STEP_BITS.INITIALIZED)
_DEAD_RECKONING: Final = int(STEP_BITS.DEAD_RECKONING)
_BAD_ACC_VERTICAL: Final = int(STEP_BITS.BAD_ACC_VERTICAL)


def gate_sample(owner: Any, source: AidSource, innovation: float, variance: float,
                sigmas: float, aids_height: bool) -> Verdict:
    """:meth:`~altfusion.estimators.gating.Gating.gate` (which documents it) of ``owner``,
    the estimator."""
    shown = source.shown
    if shown is not None:
        shown.gated(innovation, variance)
        if shown.factor != 1.0 or owner.std_factor != 1.0:
            variance *= shown.factor
            owner._show_noise()
    if sigmas > 0.0:
        ratio = innovation * innovation / (sigmas * sigmas * max(variance, 1e-300))
    else:
        ratio = 0.0
    source.test_ratio = min(ratio, 1e300)
    now: float = owner.clock.now
    params = owner.params
    source.innovation, source.variance, source.last_gated = innovation, variance, now
    fault_detection = bool(params.fault_detection)
    biased = sigmas > 0.0 and fault_detection and faults.bias_test(
        source, owner._heights, now, params.reset_timeout, innovation,
        variance, sigmas) and not source.noisy and not accelerometer_suspect(owner)
    if ratio <= 1.0 and not biased:
        if sigmas > 0.0:
            source.gate_width = sigmas * math.sqrt(max(variance, 0.0))
        record_fused(owner, source, aids_height, now)
        return FUSED
    if source.rejected_since is None:
        source.rejected_since = now
    if fault_detection:
        verdict = owner._resolve(source, innovation, variance)
        if verdict is not None:
            return verdict
    return owner._reject(source, innovation, ratio, biased)


def record_fused(owner: Any, source: AidSource, aids_height: bool, now: float) -> None:
    """A sample of ``source`` fused by ``owner`` at ``now`` (a height source aids the height
    unless ``aids_height`` is false): :meth:`~altfusion.estimators.gating.Gating.accept`."""
    source.fused(now, aids_height)
    if aids_height and source.height:
        owner._last_aiding = now


def accelerometer_suspect(owner: Any) -> bool:
    """True while ``owner``'s accelerometer check finds the prediction inconsistent with
    every height source (:mod:`~altfusion.estimators.accelerometer_check`): then the sources'
    disagreement is the prediction's fault, and no source is isolated for it."""
    check = owner.acc_check
    return check is not None and bool(check.suspect)


def publish_health(owner: Any) -> None:
    """``h_valid`` and ``status`` of ``owner``, the estimator, at the end of a step
    (:meth:`~altfusion.estimators.base.Estimator.update`)."""
    aid_sources: tuple[AidSource, ...] = owner.aid_sources
    flags: int = owner._step_flags
    started = bool(owner.started)
    now: float = owner.clock.now
    timeout: float = owner.params.aiding_timeout
    aided = now - owner._last_aiding <= timeout
    started_at: float = owner._started_at
    if started:
        flags |= _INITIALIZED
        if not aided:
            flags |= _DEAD_RECKONING
        started_at = min(started_at, now)
        owner._started_at = started_at
    valid = started and aided
    required = owner.required_sources
    if valid and required:
        aid = owner.aid
        for name in required:
            if not now - max(aid[name].last_fused, started_at) <= timeout:   # NaN: not valid
                valid = False
                break
    owner.h_valid = valid
    for source in aid_sources:
        flags |= source.bits
    check = owner.acc_check
    if check is not None and check.bad:
        flags |= _BAD_ACC_VERTICAL
    owner.status = flags
