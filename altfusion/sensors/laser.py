"""LaserRangefinder: height above the terrain, valid from 0.1 m to 25 m.

xu2016 Section 1.2.4 and eq. (6): h_l = (h - terrain_h) + ω_l, a 905 nm phase-ranging module
measuring 0.1-25 m with an accuracy of ±5 mm at 100 Hz; ±5 mm is taken as the 1σ of the white
noise ω_l (conservative: a datasheet "±" is often a 2σ or 3σ bound).

Outside [min_range, max_range] the module still sends a frame every period, reading 0 (xu2016
Fig. 11: "the output of laser ranging module is 0"): ``laser_h`` = 0, ``laser_valid`` false,
and the frame counts as a new sample (``laser_count`` increments, ``laser_time`` moves), so a
consumer sees each frame and must not fuse the invalid ones. Before the first frame
laser_h = 0 and laser_valid is false.
"""

from dataclasses import dataclass

from altfusion.errors import ParameterError
from altfusion.params import param
from altfusion.sensors.sampling import Sample, SampledSensor, SamplingParams, require_finite
from altfusion.timegrid import TickClock


@dataclass(frozen=True)
class LaserRangefinderParams(SamplingParams):
    sample_period: float = param(
        0.01, "s", "Time between frames (xu2016 Section 1.2.4: 100 Hz)", positive=True
    )
    noise_std: float = param(
        0.005, "m", "White noise, 1 sigma (xu2016 Section 1.2.4: +-5 mm). At most 100 m: a "
        "rangefinder's noise beyond its range is no measurement", min=0.0, max=100.0,
    )
    min_range: float = param(
        0.1, "m", "Shortest valid range (xu2016 Section 1.2.4)", min=0.0
    )
    max_range: float = param(
        25.0, "m", "Longest valid range (xu2016 Section 1.2.4)", positive=True
    )


class LaserRangefinder(SampledSensor):
    """Inputs ``h``, ``terrain_h``; outputs ``laser_h``, ``laser_valid``, ``laser_count``,
    ``laser_time``."""

    Params = LaserRangefinderParams
    prefix = "laser"
    streams = ("noise",)
    normal_streams = streams

    def __init__(self, params: LaserRangefinderParams | None = None, **kwargs):
        self.h = 0.0
        self.terrain_h = 0.0
        super().__init__(params, **kwargs)

    def configure_sensor(self, clock: TickClock) -> None:
        p = self.params
        if p.min_range >= p.max_range:
            raise ParameterError("min_range", p.min_range,
                                 f"must be below max_range = {p.max_range}")

    def reset_sensor(self) -> None:
        self.laser_h = 0.0
        self.laser_valid = False

    def measure(self) -> Sample:
        p = self.params
        height = require_finite("h", self.h) - require_finite("terrain_h", self.terrain_h)
        noise = p.noise_std * self.normal["noise"].draw()
        if not p.min_range <= height <= p.max_range:
            return Sample({"laser_h": 0.0, "laser_valid": False})
        return Sample({"laser_h": height + noise, "laser_valid": True})
