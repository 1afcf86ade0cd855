"""HajiyevAdaptiveEstimator: maximum-likelihood baro/GPS fusion with adaptive gain (hajiyev).

Maximum-likelihood fusion of simultaneous baro and GPS altitudes (eqs. 11-19):

    ĥ(k) = h^B(k) + K(k) Δ(k),   Δ(k) = h^GPS(k) - h^B(k)              (15), (18)
    K(k) = R_B / (R_B + R_GPS),   P(k) = R_GPS K(k)                     (16), (17)

Adaptive filter-gain correction (eqs. 26-31): when the residual exceeds its theoretical
variance, Δ² ≥ R_GPS + R_B (condition 28), the baro noise is scaled by the adaptive factor

    S(k) = (Δ² - R_GPS) / R_B                                           (30)
    K(k) = S R_B / (S R_B + R_GPS),   P(k) = R_GPS K(k)                  (27), (31)

and S = 1 otherwise (docs/papers.md). This is the shared Kalman update of a prior h^B with
variance S·R_B by the measurement h^GPS with variance R_GPS. With ``adaptive`` false the
estimator is the paper's non-adaptive filter (S ≡ 1).

Multi-rate: the fusion runs when a new GPS sample arrives, with the latest baro sample;
between GPS samples the estimate follows each new baro sample with the last correction K·Δ
held. The algorithm estimates no vertical speed: ``vz_est`` is always 0.

With ``fault_detection`` false this is the estimator, with the deviations below:
:meth:`HajiyevAdaptiveEstimator.fuse` (h_B and Δ of eq. 18),
:meth:`~HajiyevAdaptiveEstimator._fuse_gps` (eqs. 15-19, 26-31, 34),
:meth:`~HajiyevAdaptiveEstimator._baro_sample`, :meth:`~HajiyevAdaptiveEstimator.propagate`
and the GPS gate :meth:`~HajiyevAdaptiveEstimator._gate_residual`; ``fuse`` is this module's
one test of ``fault_detection``, choosing the GPS gate.

Deviations from the paper:

* between GPS samples the variance grows by ``drift_psd`` per second, so that ``h_std`` stays
  honest through GPS outages;
* a baro sample between GPS samples moves the estimate h_B + K·Δ by its own noise, and the
  held correction K·Δ keeps the old h_B's noise with weight K: the variance is the fusion's
  P plus 2·K·R_B (with P = (1-K)²·S·R_B + K²·R_GPS of eq. 31, the error
  (1-K)·b + n_new + K·(n_GPS - n_old) for white baro noise n and the adaptive part b). The
  paper's variance P holds only at the GPS sample (its baro and GPS arrive together). On
  the fault flight, recorded between a 20 Hz baro's samples and the 10 Hz GPS fusions, P
  alone covered |e| <= 2 h_std 82 % of the time;
* GPS gate: a sample is gated on the innovation of its residual Δ (eq. 18) against a reference
  Δ̄ of accepted residuals, in standard deviations ``gate_sigma`` of P̄ + R_B + R_GPS (P̄ the
  reference's variance; R_B + R_GPS the variance of Δ, the threshold of condition 28). Without
  ``fault_detection`` Δ̄ is the last accepted residual (P̄ = R_B + R_GPS): a gate on Δ's jump
  (outliers are jumps, while the drift the adaptation follows is gradual; a gate on Δ itself
  would reject that drift). A jump gate cannot isolate a GPS step: the first stepped sample
  inside it (204 m with the fault flight's noises) becomes the reference and the innovations
  the bias test averages (estimators/base.py) are jumps again, zero-mean;
* baro gate: a baro sample that jumps from the last accepted one by more than ``gate_sigma``
  standard deviations of the jump (2 R_B and ``max_vz``) is rejected;
* GPS samples that arrive before the first baro sample are not fused (eq. 18 needs h_B; in a
  replayed log GPS may come first).

The fault layer (``fault_detection`` true), not in the paper: a GPS sample goes to
:meth:`~HajiyevAdaptiveEstimator._fault_layer_gps`, whose GPS gate
:meth:`~HajiyevAdaptiveEstimator._gate_residual_on_reference` replaces
:meth:`~HajiyevAdaptiveEstimator._gate_residual` and whose
:meth:`~HajiyevAdaptiveEstimator._follow_gps` is the GPS fallback;
:meth:`~HajiyevAdaptiveEstimator._fall_back` and
:meth:`~HajiyevAdaptiveEstimator.reset_height` (called by the fault layer of
estimators/gating.py only); both gates share
:meth:`~HajiyevAdaptiveEstimator._residual_passes` and
:meth:`~HajiyevAdaptiveEstimator._set_reference`:

* with ``fault_detection`` Δ̄ is the Kalman estimate of Δ's mean, modelled as the random walk
  of PSD ``drift_psd`` that the baro drift is (hajiyev: about 1 m/s, a walk of 1 m²/s at its
  1 s samples, error_models.HAJIYEV_DRIFT_RATE) measured with variance R_B + R_GPS. Its
  innovations are white with exactly the variance passed, as the bias test assumes; its
  steady-state gain is about √(drift_psd·T/(R_B + R_GPS)) at a GPS period T (0.06 at seed
  002's 1 s: time constant 16 s, so a 1 m/s ramp lags 15 m, one innovation standard
  deviation; 0.009 at the fault flight's 0.1 s). A step therefore stays in the innovations
  (a 100 m GPS step loses 0.9 m per fused sample) and is rejected by the bias test and
  isolated. A GPS back 50 m off after a 100 s outage is not: P̄ has grown by 100 m² (the
  baro may have drifted 10 m in the model, 100 m at the paper's 1 m/s), the first returning
  samples take 8 % of their innovation each, and 50 m is at most 50/√(P̄ + R/25) = 3.9
  standard deviations over the bias test's 2.5 s even against a frozen reference: not a
  fault that the residual between baro and GPS can tell from drift at hajiyev's rate. Told
  a flight's slower drift (the fault flight's 0.05 m²/s, ``systems.faults.BARO_BIAS_PSD``),
  P̄ grows by 5 m² and the returning GNSS is isolated 3 s after it is back;
* a GPS sample rejected while the GPS is isolated (with ``fault_detection``) sets the
  estimate to h_B + Δ̄, variance R_B + P̄: the held correction K·Δ of the last accepted
  sample (eq. 15) may carry the fault (the adaptive gain of eqs. 27, 30 is about 0.9 for a
  100 m residual), while Δ̄ is the baro's offset from the GPS level that the accepted
  samples give; a rejected outlier leaves the held correction;
* while the baro is isolated the estimate follows the GPS
  (:meth:`~HajiyevAdaptiveEstimator._follow_gps`): eqs. (27), (31) with the estimate itself
  as the prior, its variance grown by the motion ``max_vz`` allows since the previous GPS
  sample (a random-walk filter on the height), each GPS sample gated on its innovation. The
  last accepted h_B is frozen since the fault, so the residual against it is the vehicle's
  motion since, which Δ̄'s walk cannot follow: fused around it, the GPS would fail its gate
  in a descent and the estimate freeze until a height reset;
* health (estimators/base.py): a baro that stays off for ``reset_timeout`` while the GPS
  agrees is isolated, and so is a GPS whose innovations against Δ̄ stay biased (the
  estimate then stays h_B + Δ̄); with no source fused for that long the estimate resets
  (onto the GPS sample while the baro is isolated).
"""

import math
from collections.abc import Callable
from dataclasses import dataclass

from altfusion.estimators.base import Estimator, HealthParams, Verdict
from altfusion.estimators.kalman import update_one_state
from altfusion.estimators.streams import BARO, GPS, Stream
from altfusion.params import param


@dataclass(frozen=True)
class HajiyevParams(HealthParams):
    R_baro: float = param(81.0, "m2", "Baro altitude noise variance R_B (hajiyev: 9² m²)",
                          positive=True)
    R_gps: float = param(169.0, "m2", "GPS altitude noise variance R_GPS (hajiyev: 13² m²)",
                         positive=True)
    adaptive: bool = param(True, None, "Adaptive gain correction (eqs. 26-31); false: eqs. 15-19")
    gate_sigma: float = param(
        4.0, "1", "Outlier gate on the residual's innovation against its reference (the last "
        "accepted residual, variance 2 (R_B + R_GPS); with fault_detection a Kalman estimate "
        "of the residual's drifting mean), and on the jump of the baro height since its last "
        "accepted sample (2 R_B and max_vz); 0: off. Not in the paper: a gate on the residual "
        "itself would reject the drift the adaptation must follow", min=0.0)
    drift_psd: float = param(
        1.0, "m2/s", "Growth rate of the estimate's variance while no GPS sample arrives "
        "(the baro error the held correction no longer tracks), and with fault_detection the "
        "PSD of the random walk the residual reference follows (hajiyev's drift of about "
        "1 m/s at 1 s samples); not in the paper", min=0.0)


class HajiyevAdaptiveEstimator(Estimator):
    """Baro/GPS maximum-likelihood fusion with the adaptive factor S(k) of hajiyev."""

    Params = HajiyevParams
    streams = (BARO, GPS)
    stated_aliases = {"baro_bias_psd": "drift_psd"}

    def initialize_filter(self) -> None:
        self.baro = float(self.baro_h)
        self._baro_time = float(self.baro_time)
        self._gps_time = float(self.gps_time)
        """Stamp of the last GPS sample, accepted or not (fault layer: its jump gate)."""
        self.started = self.has_sample("baro")
        self.adaptive_factor = 1.0
        self.gain = 0.0
        self.residual = 0.0
        self.normalized_residual = 0.0
        self.correction = 0.0
        self.variance = self.params.R_baro
        self._fused_variance: float | None = None
        """P of the last GPS fusion while its correction K·Δ is held (None: no such)."""
        self._fused_time = 0.0
        self._reference: float | None = None
        self._reference_variance = 0.0
        self._reference_time = 0.0
        self._publish()

    def propagate(self, dt: float) -> None:
        """The fusion is static (eqs. 11-19); only the held correction ages."""
        self.variance += self.params.drift_psd * dt
        self._publish()

    def fuse(self, stream: Stream, sample: dict[str, float]) -> None:
        """A baro sample is h_B (eq. 18); a GPS sample is gated on its residual Δ by
        :meth:`_gate_residual` and fused (:meth:`_fuse_gps`), or with ``fault_detection`` (the
        one dispatch on it) goes to the fault layer's :meth:`_fault_layer_gps`."""
        if stream is BARO:
            self._baro_sample(sample["baro_h"], sample["baro_time"])
            return
        if not self.has_sample("baro"):
            self.note("gps: sample before the first baro sample not fused (no h_B for eq. 18)",
                      "gps before baro")
            return
        if self.params.fault_detection:
            self._fault_layer_gps(sample["gps_h"], sample["gps_time"])
        else:
            self._fuse_if_passes(sample["gps_h"], self._gate_residual)

    def _fuse_if_passes(self, h_gps: float, gate: Callable[[float], bool]) -> None:
        """Fuse h^GPS (:meth:`_fuse_gps`) if its residual Δ (eq. 18) passes ``gate``."""
        residual = h_gps - self.baro                                            # (18)
        if gate(residual):
            self._fuse_gps(h_gps, residual)

    def _fuse_gps(self, h_gps: float, residual: float) -> None:
        """Eqs. (15)-(19) with the adaptive factor of eqs. (26)-(31): the Kalman update of the
        prior h_B (variance S·R_B) by h^GPS (variance R_GPS); K·Δ held until the next fusion."""
        p = self.params
        factor = 1.0
        if p.adaptive and residual**2 >= p.R_gps + p.R_baro:                     # (28)
            factor = (residual**2 - p.R_gps) / p.R_baro                         # (30)
        self.adaptive_factor = factor
        self.residual = residual
        self.normalized_residual = residual / math.sqrt(p.R_baro + p.R_gps)     # (34)
        self._update_estimate(self.baro, factor * p.R_baro, h_gps)

    def _update_estimate(self, prior: float, variance: float, h_gps: float) -> None:
        """Eqs. (27), (31): the Kalman update of the height ``prior`` of variance
        ``variance`` by h^GPS (variance R_GPS); the correction from h_B held until the next
        fusion (eq. 15)."""
        h, P, self.gain = update_one_state(prior, variance, h_gps,
                                           self.params.R_gps)                   # (27), (31)
        self.correction = h - self.baro
        self.variance = self._fused_variance = P
        self._fused_time = self.time
        self._publish()

    def _baro_sample(self, h_baro: float, stamp: float) -> None:
        """h_B of eq. (18): the first baro sample starts the estimator; a later one whose jump
        from the last accepted exceeds the gate is rejected (an addition to the paper)."""
        p = self.params
        if not self.started:
            self.started = True
            self.accept(self.aid["baro"])
        else:
            elapsed, self._baro_time = stamp - self._baro_time, stamp
            verdict = self.gate(self.aid["baro"], h_baro - self.baro,
                                self.jump_variance(p.R_baro, elapsed), p.gate_sigma)
            if verdict is not Verdict.FUSED:
                return
        self._baro_time = stamp
        self.baro = h_baro
        if self._fused_variance is not None:      # h_B's noise anew, the held K·Δ's old one
            self.variance = (self._fused_variance + 2.0 * self.gain * p.R_baro
                             + p.drift_psd * (self.time - self._fused_time))
        self._publish()

    def _gate_residual(self, residual: float) -> bool:
        """The GPS gate (an addition to the paper): the innovation of the residual Δ against
        the last accepted residual Δ̄ (a gate on Δ's jump), variance P̄ + R_B + R_GPS with
        P̄ = R_B + R_GPS; an accepted Δ becomes Δ̄. True if the sample may be fused. The first
        residual, also the first after a height reset, is accepted and becomes Δ̄."""
        if self._reference is not None and not self._residual_passes(
                residual, self._reference_variance):
            return False
        self._set_reference(residual, self._residual_noise())
        return True

    # ------------------------------------------------------------------ fault layer
    def _fault_layer_gps(self, h_gps: float, stamp: float) -> None:
        """A GPS sample with ``fault_detection``: while the baro is isolated the estimate
        follows the GPS alone (:meth:`_follow_gps`), else the sample is gated on its residual
        against the reference Δ̄ (:meth:`_gate_residual_on_reference`) and fused."""
        elapsed, self._gps_time = stamp - self._gps_time, stamp
        if self.aid["baro"].isolated:
            self._follow_gps(h_gps, elapsed)
        else:
            self._fuse_if_passes(h_gps, self._gate_residual_on_reference)

    def _follow_gps(self, h_gps: float, elapsed: float) -> None:
        """The GPS fallback while the baro is isolated (PX4 EKF2 falling back to GNSS height):
        h_B is the last accepted baro sample, frozen since the fault and as stale as the
        vehicle has moved since, so it carries no information. Eqs. (27), (31) with the
        estimate itself as the prior instead of h_B: ĥ⁻ = ĥ with variance
        P⁻ = P + (max_vz·Δt)², the motion ``max_vz`` allows over the Δt = ``elapsed`` s since
        the GPS's previous sample counted as one standard deviation (as the baro's jump gate
        counts it), so K = P⁻/(P⁻ + R_GPS) and P = P⁻·R_GPS/(P⁻ + R_GPS): a random-walk
        filter on the height whose lag stays within its P for any speed up to ``max_vz``
        (steady state: σ ≈ 12 m for a 30 m GNSS at 10 Hz, the GNSS's own σ at 1 Hz or for a
        2 m one). The sample is gated on its innovation against P⁻ + R_GPS. Δ̄ is left
        frozen, its variance growing by ``drift_psd`` from its last update: once a baro
        sample passes its gate again, the next GPS sample is gated against it. Δ, S and eq.
        (34)'s residual keep the last fusion's values (Δ against the frozen h_B would be the
        vehicle's motion since the fault)."""
        p = self.params
        prior = self.variance + (p.max_vz * elapsed) ** 2
        if self.gate(self.aid["gps"], h_gps - self.h_est, prior + p.R_gps,
                     p.gate_sigma) is Verdict.FUSED:
            self._update_estimate(self.h_est, prior, h_gps)

    def _gate_residual_on_reference(self, residual: float) -> bool:
        """The GPS gate with ``fault_detection``: Δ̄ is the Kalman estimate of a random walk of
        PSD ``drift_psd`` measured by Δ with variance R_B + R_GPS (its innovations are white
        with exactly that variance, as the bias test assumes); the innovation of Δ against it
        is gated with variance P̄ + R_B + R_GPS (P̄ the walk's prior variance) and an accepted
        Δ updates Δ̄. True if the sample may be fused. The first residual, also the first
        after a height reset, is accepted and becomes Δ̄ (P̄ = R_B + R_GPS); a rejected one
        may make the estimate fall back (:meth:`_fall_back`)."""
        noise = self._residual_noise()
        if self._reference is None:
            self._set_reference(residual, noise)
            return True
        prior = self._reference_variance
        prior += self.params.drift_psd * (self.time - self._reference_time)
        if not self._residual_passes(residual, prior):
            self._fall_back(prior)
            return False
        gain = prior / (prior + noise)
        self._set_reference(self._reference + gain * (residual - self._reference),
                            gain * noise)
        return True

    def _fall_back(self, prior: float) -> None:
        """A GPS sample rejected while the GPS is isolated (which needs ``fault_detection``):
        the held correction of the last accepted sample may carry the fault, so the estimate
        falls back to h_B plus the reference Δ̄ (the GPS-minus-baro offset learnt from the
        accepted residuals), variance R_B + ``prior`` (P̄ now). A rejected outlier leaves the
        held correction, as if the sample had not arrived."""
        if not self.aid["gps"].isolated:
            return
        self.correction = self._reference
        self.variance = self.params.R_baro + prior
        self._fused_variance = None               # a new h_B: R_B anew, the same P̄
        self._publish()

    def reset_height(self, source: str, innovation: float, variance: float) -> None:
        """A baro reset takes the new baro level; a GPS reset while the baro is isolated
        moves the estimate onto the GPS sample (``variance`` its variance: the estimate
        follows the GPS alone, :meth:`_follow_gps`); any reset drops the residual reference,
        so that the next GPS sample fused with the baro is fused whatever its residual and
        starts a new one."""
        if source == "baro":
            self.baro += innovation
        elif self.aid["baro"].isolated:
            self.correction += innovation
            self.variance = self._fused_variance = variance
            self._fused_time = self.time
        self._reference = None
        self._publish()

    # ------------------------------------------------------------------ shared
    def _residual_noise(self) -> float:
        """R_B + R_GPS: the variance of the residual Δ (the threshold of condition 28)."""
        return self.params.R_baro + self.params.R_gps

    def _residual_passes(self, residual: float, prior: float) -> bool:
        """The GPS gate: Δ - Δ̄ against ``prior`` (P̄) + R_B + R_GPS in ``gate_sigma``."""
        return self.gate(self.aid["gps"], residual - self._reference,
                         prior + self._residual_noise(),
                         self.params.gate_sigma) is Verdict.FUSED

    def _set_reference(self, reference: float, variance: float) -> None:
        """The residual reference Δ̄ and its variance P̄ after an accepted residual, now."""
        self._reference, self._reference_variance = reference, variance
        self._reference_time = self.time

    def _publish(self) -> None:
        """ĥ = h_B + K·Δ (eq. 15, the correction K·Δ held between GPS fusions)."""
        self.h_est = self.baro + self.correction
        self.vz_est = 0.0
        self.h_std = math.sqrt(self.variance)
