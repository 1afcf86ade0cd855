"""Sensor streams: the inputs one sensor's samples arrive on, and the bounds of plausibility.

A sensor stream is a group of inputs named by the signal contract: the held sample values,
``<prefix>_count``, ``<prefix>_time`` (the sample's time stamp) and optionally a validity flag
(``gps_fix``, ``radar_valid``...). A new sample is one whose count changed.
"""

from dataclasses import dataclass, field
from functools import partial
from operator import attrgetter

from altfusion.estimators.health import HEIGHT_SOURCES, SOURCES

ACC_CLIP = 0.95 * 16.0 * 9.80665
"""A vertical acceleration beyond 95 % of ±16 g (the full scale of common MEMS
accelerometers) is a clipped reading (PX4's PX4Accelerometer counts a raw sample beyond 95 %
of the range as clipping): the true acceleration lies somewhere beyond it, so the reading is
no measurement of it."""

GNSS = ("gps", "gps_vz")
"""The GNSS receiver's sources: a repeated reading of theirs may be a receiver holding still
(:mod:`~altfusion.estimators.stuck`)."""

PLAUSIBLE_RANGE = {"acc_z": ("acc", ACC_CLIP), "gps_vz": ("gps_vz", 1000.0),
                   **{f"{source}_h": (source, 1e5) for source in HEIGHT_SOURCES}}
"""Plausibility bounds of the sample values (source charged, largest magnitude): the
accelerometer's clipping level :data:`ACC_CLIP`; 1000 m/s, about Mach 3; ±100 km of height,
the Kármán line. A value beyond its bound cannot be a measurement: the sample is rejected as
that source's (test ratio value²/bound²) and takes no part in the step."""

PLAUSIBLE_AUXILIARY = {"baro_T": (150.0, 400.0)}
"""Plausible intervals of the values a sample carries beside its measurement (an auxiliary
value: no source of its own). The air temperature lies within 150-400 K: the atmosphere's
coldest, the mesopause near 86 km, is ~187 K in the ISA, the coldest air measured at the
surface 184 K and the hottest 330 K; 0 K, below, is the input's start value, read when it is
left unconnected (WhangGAEstimator took it for a 288 K cold snap: its scale factor went to
~1 and its height ran 460 m off, ``h_valid`` true). A value outside is left out of the
sample (the estimator fuses the rest without it) and noted."""


@dataclass(frozen=True, eq=False)
class Stream:
    """The inputs of one sensor stream.

    Streams are this module's constants and compare by identity: they key the per-step
    sample dicts, where the built-in identity hash costs nothing (a field hash would run
    Python code at every lookup). The names derived from the fields are plain attributes,
    set once (read at every sample: a plain attribute is read faster than a cached
    property)."""

    prefix: str
    values: tuple[str, ...]
    valid: str | None = None
    count: str = field(init=False)
    """``<prefix>_count``."""
    time: str = field(init=False)
    """``<prefix>_time``."""
    fields: tuple[str, ...] = field(init=False)
    """The inputs a sample carries: the values, then the time stamp."""
    read: attrgetter = field(init=False, repr=False)
    """The getter of a sample's :attr:`fields` from an object: a tuple of their values."""
    bounds: tuple[tuple[str, str, float], ...] = field(init=False, repr=False)
    """(input, source charged, bound) of each value with a :data:`PLAUSIBLE_RANGE`."""
    auxiliary: tuple[tuple[str, float, float], ...] = field(init=False, repr=False)
    """(input, lowest, highest) of each value with a :data:`PLAUSIBLE_AUXILIARY` interval."""
    checked: tuple[tuple[str, str], ...] = field(init=False, repr=False)
    """(input, source) of each measured value the stuck check watches
    (:mod:`~altfusion.estimators.stuck`): every one with a plausibility bound."""
    gnss_speed: bool = field(init=False, repr=False)
    """The stream carries the GNSS vertical speed (``gps_vz``)."""

    def __post_init__(self) -> None:
        set_once = partial(object.__setattr__, self)          # frozen: derived once, here
        set_once("count", f"{self.prefix}_count")
        set_once("time", f"{self.prefix}_time")
        set_once("fields", (*self.values, self.time))
        set_once("read", attrgetter(*self.fields))
        set_once("bounds", tuple((name, *PLAUSIBLE_RANGE[name]) for name in self.fields
                                 if name in PLAUSIBLE_RANGE))
        set_once("auxiliary", tuple((name, *PLAUSIBLE_AUXILIARY[name]) for name in self.values
                                    if name in PLAUSIBLE_AUXILIARY))
        set_once("gnss_speed", "gps_vz" in self.values)
        set_once("checked", tuple((name, source) for name, source, _ in self.bounds))


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
