"""The bits of an estimator's ``status`` output and the sources they describe.

``status`` (an Integer output of every estimator, ``docs/estimator_health.md``): bits 0-7 are
the estimator's (:class:`Status`), then four bits per source, source i of :data:`SOURCES` at
bit 8 + 4·i (:class:`SourceBit`). This module holds only the masks, so that a consumer of the
output (the FMI variable declarations, the scores, the evaluation) reads them without the
estimator machinery.
"""

from enum import IntEnum, IntFlag
from types import SimpleNamespace

HEIGHT_SOURCES = ("baro", "gps", "radar", "laser")
"""The sources that aid the height (their fusion keeps ``h_valid`` true)."""

SOURCES = (*HEIGHT_SOURCES, "gps_vz", "acc")
"""Every source with a test ratio and a rejection count, in the order of their status bits."""

NOISE_CHECKED = (*HEIGHT_SOURCES, "gps_vz")
"""The sources whose stated noise is checked against their innovations
(:mod:`~altfusion.estimators.noise_check`): not the accelerometer, which has its own check
(:mod:`~altfusion.estimators.accelerometer_check`), and whose bit 3 would be bit 31, the sign
bit of an FMI Integer."""


UNKNOWN_STD = 1e5
"""``h_std`` of an estimator not yet initialized, m (with ``h_valid`` false): ±100 km, the
plausibility bound of any height. A finite maximum rather than infinity, so that every host
takes it as it takes any other value (an FMI Real, a CSV cell, a JSON number, a plot's
axis, a coverage test |e| <= 2 h_std), while no estimate can claim less certainty."""


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
    SAMPLE_REFUSED = 1 << 4
    """A sample was refused in this step for its time stamp: further ahead of the clock than
    ``max_sample_lead``, further behind than ``max_sample_delay``, or before its stream's
    last sample."""
    BAD_ACC_VERTICAL = 1 << 5
    """The accelerometer's noise in use is more than twice the stated: measured from its
    samples' scatter, or inferred from every height source disagreeing with the prediction
    (PX4 EKF2's ``bad_acc_vertical``; :mod:`~altfusion.estimators.accelerometer_check`)."""
    PROCESS_NOISE_ADAPTED = 1 << 6
    """The motion model's process noise is raised more than twofold above the stated one:
    every source found the prediction off, as in a manoeuvre the stated noise cannot follow
    (AltitudeEKF without an accelerometer; :mod:`~altfusion.estimators.process_noise`)."""
    RANGE_AID = 1 << 7
    """A rangefinder is used as the height: it is within its height limit and consistent
    with flat terrain, and the terrain under it is held (PX4 EKF2's conditional range aid;
    :mod:`~altfusion.estimators.range_aid`)."""


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
    """The source is declared faulty: a height source rejected for ``reset_timeout`` while
    another height source that pins the height tighter was fused, or (AltitudeEKF) any
    source whose reading is stuck (:mod:`~altfusion.estimators.stuck`)."""
    NOISE_INFLATED = 3
    """The source's stated noise is found too small for its innovations: AltitudeEKF's
    variance inflated more than fourfold, XuSHAEKF's nominal R (baro, laser) replaced beyond
    16 times; the other estimators (fault layer) show it more than twice too small, their
    gate and published ``h_std`` widened by it (the sources of :data:`NOISE_CHECKED` only;
    :mod:`~altfusion.estimators.noise_check`)."""


def source_bit(source: str, bit: SourceBit) -> int:
    """The ``status`` mask of ``bit`` of ``source``."""
    return 1 << (8 + 4 * SOURCES.index(source) + bit)


def status_bits() -> dict[str, int]:
    """Every documented ``status`` bit: name -> mask."""
    bits = {flag.name: int(flag) for flag in Status}
    bits.update({f"{source.upper()}_{bit.name}": source_bit(source, bit)
                 for source in SOURCES for bit in SourceBit if _applies(bit, source)})
    return bits


def _applies(bit: SourceBit, source: str) -> bool:
    """True if ``source`` can set ``bit``."""
    if bit is SourceBit.NOISE_INFLATED:
        return source in NOISE_CHECKED
    return True
