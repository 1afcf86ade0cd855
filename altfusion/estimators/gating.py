"""Gating: each sample of a source through its gate, with an explicit verdict.

Test ratio y²/(g²·S) (PX4 EKF2), the sample fused or rejected on it; with ``fault_detection``
the fault layer (:mod:`~altfusion.estimators.fault_detection`) rejects a biased source, may
reset the state onto a rejected sample or re-reference an isolated source, and isolates a
source that stays rejected while another pins the height.
"""

from altfusion.estimators import fault_detection as faults
from altfusion.estimators.aid_source import AidSource, Verdict
from altfusion.estimators.gate import gate_sample, record_fused
from altfusion.estimators.health import NOISE_CHECKED, STEP_BITS
from altfusion.estimators.noise_check import ShownNoise


class Gating:
    """The gating half of :class:`~altfusion.estimators.base.Estimator` (a mixin: it uses
    the component's clock, parameters and notes, the estimator's ``started``, its height
    sources and :meth:`~altfusion.estimators.base.Estimator.reset_height` /
    :meth:`~altfusion.estimators.base.Estimator.reset_offset`)."""

    def gate(self, source: AidSource, innovation: float, variance: float, sigmas: float,
             aids_height: bool = True) -> Verdict:
        """The innovation gate of ``source``: test ratio y²/(g²·S) (PX4) with g = ``sigmas``
        standard deviations of the innovation variance S (``sigmas <= 0``: no gate, ratio 0;
        S times the noise the source's innovations show, :attr:`AidSource.shown`, while it is
        shown too small).
        ``aids_height`` false: the source calibrates another (its fusion does not keep
        ``h_valid`` true). With ``fault_detection`` a sample failing the bias test is
        rejected too (unless the source's noise is found too small:
        :attr:`AidSource.noisy`), and a rejected one may reset the state or re-reference its
        source (:func:`~.gate.gate_sample`, compiled)."""
        return gate_sample(self, self.health, source, innovation, variance, sigmas, aids_height,
                           self.clock.now)

    def attach_shown_noise(self) -> None:
        """With ``fault_detection``, unless the estimator checks its noises itself
        (:meth:`~altfusion.estimators.base.Estimator.checks_own_noise`), the fault layer's
        check of each :data:`~altfusion.estimators.health.NOISE_CHECKED` source on its
        innovations (:attr:`AidSource.shown`), but for the estimator's
        :attr:`~altfusion.estimators.base.Estimator.scatter_checked` sources."""
        if self.params.fault_detection and not self.checks_own_noise():
            for source in self.aid_sources:
                if source.name in NOISE_CHECKED and source.name not in self.scatter_checked:
                    source.shown = ShownNoise(source)

    def _show_noise(self) -> None:
        """The health's ``std_factor`` from the noise factors the sources' innovations show."""
        self.health.std_factor = max(source.shown.factor for source in self.aid_sources
                              if source.shown is not None)

    def restart_without(self, name: str) -> None:
        """Start the filter afresh without source ``name``, found stuck since before the
        filter started (a frozen sensor, an input left unconnected): everything the filter
        learnt rests on its repeated reading, and so does the fault layer's judgement of
        the other height sources, which is withdrawn (:meth:`AidSource.rejudge`). Without,
        a radio altimeter reading 0 from the start had YangFusionKF's bias test isolate the
        baro and the GNSS for good, the height 90 m off at an h_std of 1-3 m."""
        self.note(f"{name}: stuck since before the filter started: the filter starts afresh "
                  f"without it")
        for source in self.health.heights:
            if source.name != name:
                source.rejudge()
        self.started = False
        self.initialize_filter()

    def refuse_implausible(self, source: AidSource, value: float, bound: float) -> None:
        """Reject a sample of ``source`` whose value lies beyond its plausibility ``bound``
        (test ratio value²/bound²)."""
        ratio = value * value / (bound * bound)
        source.test_ratio = min(ratio, 1e300)
        if source.rejected_since is None:
            source.rejected_since = self.time
        self._reject(source, value, ratio, False)

    def _resolve(self, source: AidSource, innovation: float, variance: float,
                 ) -> Verdict | None:
        """The fault layer's verdict on a rejected sample: a height reset (no height source
        fused for ``reset_timeout``, nothing pinning the height tighter) or a velocity reset
        (the GNSS speed rejected that long), a re-reference of an isolated source with a
        constant offset (rejected for twice ``reset_timeout``), or None: rejected."""
        now, timeout, last_aiding = self.time, self.params.reset_timeout, self.health.last_aiding
        since = source.rejected_since
        if self.started and (
                (source.height and now - last_aiding >= timeout
                 and not self.contradicted(source, innovation))
                or (source.name == "gps_vz" and now - since >= timeout)):
            self.height_reset(source, innovation, variance,
                              f"no height source fused for {now - last_aiding:.3g} s")
            return Verdict.RESET
        if not (source.height and source.isolated and now - since >= 2.0 * timeout
                and source.window.one_sided(faults.BIAS_MIN_SAMPLES)
                and self.reset_offset(source.name, innovation, variance)):
            return None
        source.window.clear()
        source.biased = False
        self.note(f"{source.name}: isolated for {now - since:.3g} s with a constant offset; "
                  f"its offset state reset by {innovation:.4g} m and the source re-admitted")
        self.accept(source)
        return Verdict.REREFERENCED

    def _reject(self, source: AidSource, innovation: float, ratio: float,
                biased: bool) -> Verdict:
        """Count the rejection; with ``fault_detection`` isolate a source rejected for
        ``reset_timeout`` that is biased or contradicted by another source (not one whose
        noise is found too small: :attr:`AidSource.noisy`)."""
        source.refused()
        self.n_rejected += 1
        now = self.time
        if (self.params.fault_detection
                and now - source.rejected_since >= self.params.reset_timeout
                and (biased or self.contradicted(source, innovation))
                and not source.isolated and not source.noisy
                and not self.health.accelerometer_suspect()):
            source.isolate()
            self.note(f"{source.name}: rejected for {now - source.rejected_since:.3g} s while "
                      f"other sources are fused: isolated until a sample passes the gate")
        self.note(f"{source.name}: sample rejected (innovation {innovation:.4g}, test ratio "
                  f"{ratio:.3g}{', persistently biased' if biased else ''})",
                  f"{source.name} rejected")
        return Verdict.REJECTED

    def contradicted(self, source: AidSource, innovation: float) -> bool:
        """True if another height source pins the height tighter than ``innovation``, or
        ``source`` failed its bias test (:func:`.fault_detection.contradicted`; with
        ``fault_detection``, else False)."""
        return self.params.fault_detection and faults.contradicted(
            source, self.health.heights, self.time, self.params.reset_timeout, innovation)

    def height_reset(self, source: AidSource, innovation: float, variance: float,
                     reason: str) -> None:
        """PX4's height reset onto a sample of ``source`` (:meth:`reset_height`), counted in
        ``n_height_resets``, flagged in ``status`` for this step, noted with ``reason`` and
        the sample accepted."""
        self.reset_height(source.name, innovation, variance)
        self.n_height_resets += 1
        self.health.step_flags |= STEP_BITS.HEIGHT_RESET
        self.note(f"{source.name}: {reason}; height reset by {innovation:.4g} m to this source "
                  f"(reset {self.n_height_resets})")
        self.accept(source)

    def jump_variance(self, noise_variance: float, elapsed: float) -> float:
        """Variance of a height's jump from its last accepted sample, ``elapsed`` s after the
        source's previous sample (accepted or not: a failed sensor's step stays rejected),
        for an estimator without a speed state: twice the sample noise, plus the motion
        ``max_vz`` allows counted as one standard deviation."""
        return 2.0 * noise_variance + (self.params.max_vz * elapsed) ** 2

    def accept(self, source: AidSource, aids_height: bool = True) -> None:
        """Record that a sample of ``source`` is fused (a height source aids the height unless
        ``aids_height`` is false)."""
        record_fused(self.health, source, aids_height, self.clock.now)
