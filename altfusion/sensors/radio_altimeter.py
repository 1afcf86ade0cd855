"""RadioAltimeter: height above the terrain with white noise, up to a maximum range.

yang2020 eq. (3): h_ra = (h - terrain_h) + δ_ra, δ_ra white with σ_ra (Section 4.2: 10 m,
sampled every 200 ms). The Gaussian error model is kept as the paper writes it, also close to
the ground (a reading may be negative there).

Beyond ``max_range`` (or below the terrain) there is no measurement: ``radar_valid`` turns
false while ``radar_h``, ``radar_count`` and ``radar_time`` hold (the signal contract's
convention for invalid measurements); the time stamp thus tells the age of the last valid
reading. Before the first sample radar_h = 0 and radar_valid is false.
"""

from dataclasses import dataclass

from altfusion.params import param
from altfusion.sensors.sampling import Sample, SampledSensor, SamplingParams, require_finite


@dataclass(frozen=True)
class RadioAltimeterParams(SamplingParams):
    sample_period: float = param(
        0.2, "s", "Time between samples (yang2020 Section 4.2: 200 ms)", positive=True
    )
    noise_std: float = param(
        10.0, "m", "White noise, 1 sigma (yang2020 Section 4.2: 10 m). At most 1000 m: a radio "
        "altimeter's noise beyond its range is no measurement", min=0.0, max=1000.0,
    )
    max_range: float = param(
        1500.0, "m", "Largest measurable height above the terrain (covers yang2020's 1440 m "
        "cruise)", positive=True,
    )


class RadioAltimeter(SampledSensor):
    """Inputs ``h``, ``terrain_h``; outputs ``radar_h``, ``radar_valid``, ``radar_count``,
    ``radar_time``."""

    Params = RadioAltimeterParams
    prefix = "radar"
    streams = ("noise",)
    normal_streams = streams

    def __init__(self, params: RadioAltimeterParams | None = None, **kwargs):
        self.h = 0.0
        self.terrain_h = 0.0
        super().__init__(params, **kwargs)

    def reset_sensor(self) -> None:
        self.radar_h = 0.0
        self.radar_valid = False

    def measure(self) -> Sample:
        p = self.params
        height = require_finite("h", self.h) - require_finite("terrain_h", self.terrain_h)
        noise = p.noise_std * self.normal["noise"].draw()
        if not 0.0 <= height <= p.max_range:
            return Sample({"radar_valid": False}, new=False)
        return Sample({"radar_h": height + noise, "radar_valid": True})
