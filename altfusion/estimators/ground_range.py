"""The on-ground range: a laser's invalid frame read as the vehicle standing on the ground.

A laser rangefinder reads nothing below its minimum range: xu2016's module keeps sending
frames, reading 0 and flagged invalid (xu2016 Fig. 11; :mod:`altfusion.sensors.laser`). On
the ground, before take-off and after landing, the one sensor that would pin the height then
says nothing, and the estimate rests on the absolute sources: measured on xu2016_hover15
(AltitudeEKF told the sensors' noise), 2-6 m off at ``h_std`` 2 m in 7 runs of 10 for the
0.5-5 s before take-off, which made its 0.178 m RMS over the flight against XuSHAEKF's
0.042 m (XuSHAEKF starts from the ground, its equations' initial state).

PX4 EKF2 synthesises a range measurement at the expected on-ground value (EKF2_MIN_RNG,
0.1 m by default) while its land detector says the vehicle is on the ground and the
rangefinder keeps sending data that fails its checks (``range_height_control.cpp``). An
estimator of the vertical axis alone has no land detector (no thrust, no contact). It reads
an invalid laser frame as "the laser is between 0 and its minimum range m above the
terrain": z = m/2, a reading anywhere in [0, m], of variance s = (m/2)²: its half-width
taken as one standard deviation (the uniform's m/√12 put a vehicle standing at an end of
the interval, as the simulated ones do, 1.7 of it from the middle, and the estimate's
wander beyond two: |e| <= 2 ``h_std`` 60-80 % of the fault flight's time on the ground, 97 %
now). The vehicle stands at one height there, the same for every frame, so the readings do
not average (fused as independent at the laser's 100 Hz they made the height as certain as
a hundred readings: measured 0.05 m off at ``h_std`` 0.005 m). A reading is fused only while
the height above the terrain is less certain than s (its variance P > s), with the noise
variance R = P·s/(P - s) + R_laser that leaves it at s (P·R/(P + R) = s, R_laser aside),
and it moves every state but the accelerometer's bias (a Schmidt update,
:func:`~altfusion.estimators.kalman.update_scalar_of`: a vehicle jostled on the ground, within
[0, m] between readings, taught the bias its hops, and the take-off that followed ran 0.9 m
off at ``h_std`` 0.06 m, xu2016_hover15 told nothing), when

* the frame cannot mean "beyond the maximum range": the height above the terrain, plus
  ``gate_sigma`` times its standard deviation, is below the laser's maximum height (an
  invalid frame means out of range high as much as low; with the terrain unknown it means
  nothing);
* the reading passes the gate (``gate_sigma``, against P + s + R_laser: R, unbounded as P
  nears s, would pass any reading) and the vertical speed may be below
  :data:`LANDED_SPEED` (within one standard deviation of it: a filter just started knows
  its speed to metres per second): otherwise the ground is refuted (a flying vehicle whose
  laser drops out, a take-off or hop with a laser that does not read), and no frame is
  read so until the laser's next valid one. Measured with the laser's minimum range set
  above xu2016's hover (every frame invalid): the first hop refuted the ground, the flight
  that followed as without the readings (RMS 0.66 m against 0.77 m, |e| within 2.4
  ``h_std``), where readings fused whenever the speed allowed had held the height down and
  taught the accelerometer's bias the hops (1.5 m off at ``h_std`` 0.13 m in the climb).
  With 5 standard deviations allowed the hops were read as ground again: 0.86 m RMS.

Until the vehicle is seen to fly (the laser's first valid frame, or a reading refuted) it is
presumed on the ground, as PX4's land detector boots "landed": the reach is then judged at
:data:`PRESUMED_SIGMA` standard deviations rather than the gate's. A filter told nothing
knows its height to the baro offset's prior and the first GNSS pairs' bounds, 10 m, for
its first seconds: 5σ put the vehicle possibly beyond the 25 m reach for 0.3-1.8 s, the
height followed the first GNSS samples meanwhile, 0.16-1.42 m off (xu2016_hover15 told
nothing: 3.3x the RMS told the noise, where the ground was read from 0.2 s on). Started in
the air beyond the reach, the vehicle's frames are read as the ground only with its
estimate 2σ short of the truth (2.3 %; and the gate's 5σ stands); ``presumed`` False
(AltitudeEKF's ``starts_on_ground``) judges at the gate's from the start.

Deviations from PX4 EKF2: the reading is the middle of [0, m] with its half-width as σ, not
m with the range noise (a vehicle on its skids reads the laser's mounting height, anywhere
below m), fused only while it tells something; no land detector, its place taken by the
conditions above; without a gate (``gate_sigma`` 0) no reading, since nothing then tells the
ground from a dropout.
"""

import math
from typing import Final

from altfusion.estimators.restorable import Restorable

PRESUMED_SIGMA: Final = 2.0
"""Standard deviations of the height above the terrain that must stay within the laser's
reach while the vehicle is presumed on the ground (one-sided 97.7 %; the gate's otherwise)."""

LANDED_SPEED: Final = 0.5
"""Largest vertical speed of a vehicle that may stand on the ground, m/s (PX4's multicopter
land detector, LNDMC_Z_VEL_MAX's default)."""


class GroundRange(Restorable):
    """The on-ground reading of a laser of minimum range ``minimum`` and maximum height
    ``maximum`` (m), judged with the estimator's gate of ``gate`` standard deviations."""

    __slots__ = ("minimum", "maximum", "gate", "refuted", "presumed")

    def __init__(self, minimum: float, maximum: float, gate: float,
                 presumed: bool = True) -> None:
        self.minimum = minimum
        """The laser's minimum range, m: the ground reading lies in [0, it]."""
        self.maximum = maximum
        """The laser's maximum height, m: beyond it an invalid frame means out of range."""
        self.gate = gate
        self.refuted = False
        """A reading failed the gate, or the vehicle moved: no reading until the laser's
        next valid frame (:meth:`in_range`)."""
        self.presumed = presumed
        """The vehicle presumed on the ground: not yet seen to fly (a valid frame, a reading
        refuted); its reach then judged at :data:`PRESUMED_SIGMA`."""

    def spread(self) -> float:
        """s = (m/2)², the variance taken for a height anywhere in [0, m]."""
        return self.minimum * self.minimum / 4.0

    def reading(self) -> float:
        """The on-ground reading, m/2."""
        return 0.5 * self.minimum

    def noise(self, variance: float, noise_variance: float) -> float:
        """The reading's noise variance that leaves a height above the terrain of that
        ``variance`` (above :meth:`spread`) at the spread, the laser's ``noise_variance``
        added."""
        s = self.spread()
        return variance * s / (variance - s) + noise_variance

    def in_range(self) -> None:
        """The laser read a valid frame: the ground may be read again, and is no longer
        presumed."""
        self.refuted = self.presumed = False

    def tells(self, height: float, variance: float) -> bool:
        """Whether a reading tells anything about a ``height`` above the terrain of that
        ``variance``: the ground not refuted, the height less certain than :meth:`spread`
        and, with ``gate`` of its standard deviations (:data:`PRESUMED_SIGMA`, if fewer,
        while the ground is presumed), within the laser's reach."""
        sigmas = min(self.gate, PRESUMED_SIGMA) if self.presumed else self.gate
        return not self.refuted and variance > self.spread() \
            and height + sigmas * math.sqrt(variance) < self.maximum

    def judge(self, innovation: float, variance: float, noise_variance: float, speed: float,
              speed_sigma: float) -> bool:
        """Whether the reading is fused: its ``innovation`` within the gate of the height's
        ``variance`` plus :meth:`spread` and the laser's ``noise_variance``, and the vertical
        ``speed`` one a vehicle standing on the ground may have (within :data:`LANDED_SPEED`
        plus ``speed_sigma``, its standard deviation: a filter just started knows its speed
        to metres per second); if not, the ground is refuted."""
        gate = self.gate
        consistent = innovation * innovation <= gate * gate * (variance + self.spread()
                                                               + noise_variance)
        self.refuted = not (consistent and abs(speed) < LANDED_SPEED + speed_sigma)
        self.presumed = self.presumed and not self.refuted
        return not self.refuted
