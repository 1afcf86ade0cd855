"""A reading that repeats bit for bit: a stuck sensor, or an input left unconnected.

A sensor with noise does not deliver the same floating-point value many samples in a row:
two successive readings of noise σ quantized at q << σ coincide with a probability of about
q/(2σ√π) (a 5 mm laser read to the millimetre: 6 %; ten in a row: 10⁻¹²). A reading that
stays bit for bit the same is a frozen sensor, a replay stuck on one record, or, the common
case, one value of a stream whose input was left unconnected and reads its start value
while the stream's other values arrive (a GNSS receiver delivering heights but no vertical
speed: its ``gps_vz`` reads 0). Fused, such a reading is a perfect measurement of something
false: a speed of 0 pins the estimate's speed through a descent, and the height sources
that disagree look like the faulty ones (measured on hajiyev's 7 m/s descent, AltitudeEKF
told only the noises: RMS 1853 m, the baro and GNSS isolated).

A reading is *stuck* from its ``limit``-th repetition on (``limit`` + 1 identical samples)
until it changes; the estimator does not fuse it meanwhile. PX4 EKF2 has no such check on
values (it checks that samples arrive, by their timestamps); ArduPilot's EKF3 declares a
GPS stale on an unchanged time of week. Deviation: values, not timestamps, are compared,
since an unconnected value arrives with fresh stamps.
"""


class StuckCheck:
    """Whether one reading is stuck (:meth:`stuck`)."""

    __slots__ = ("limit", "last", "repeats")

    def __init__(self, limit: int) -> None:
        self.limit = limit
        """Repetitions from which the reading is stuck (0: never)."""
        self.last: float | None = None
        """The last reading."""
        self.repeats = 0
        """How many samples in a row repeated it."""

    def stuck(self, value: float) -> bool:
        """The next reading: True while it is stuck."""
        if value == self.last:
            self.repeats += 1
        else:
            self.last, self.repeats = value, 0
        return 0 < self.limit <= self.repeats
