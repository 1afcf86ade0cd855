"""Accelerometer: vertical specific force measured with bias and noise, gravity removed.

An accelerometer senses specific force, not acceleration: along the vertical (positive up)
f = az + g. The measurement (yang2020 eq. 4, xu2016 Section 1.2.1 and its eq. 1, whose
third row adds -g back) is

    f_m   = az + gravity + b + σ·n,      b = bias + bias_std·n₀ (n₀ drawn once per run)
    acc_z = f_m - nominal_gravity

so ``acc_z`` is the vertical acceleration with gravity removed, carrying the bias, the white
noise and any difference between the true and the nominal gravity. The default noise is seed
003 Section 4.2's 0.01 m/s² at 100 Hz; a calibrated MEMS accelerometer's residual bias is of
the order of 0.01-0.05 m/s² (set ``bias``/``bias_std``). Before the first sample acc_z = 0.
"""

from dataclasses import dataclass

from altfusion.constants import G0
from altfusion.params import param
from altfusion.sensors.sampling import Sample, SampledSensor, SamplingParams, require_finite


@dataclass(frozen=True)
class AccelerometerParams(SamplingParams):
    sample_period: float = param(0.01, "s", "Time between samples (100 Hz)", positive=True)
    noise_std: float = param(
        0.01, "m/s2", "White noise, 1 sigma (yang2020 Section 4.2: 0.01 m/s2). At most 150 m/s2: "
        "beyond 16 g a MEMS accelerometer's every sample is clipped", min=0.0, max=150.0,
    )
    bias: float = param(0.0, "m/s2", "Constant bias of the specific-force measurement")
    bias_std: float = param(
        0.0, "m/s2", "1 sigma of a turn-on bias drawn once per run from this seed", min=0.0
    )
    gravity: float = param(
        G0, "m/s2", "True gravity: the sensed specific force is az + gravity", positive=True
    )
    nominal_gravity: float = param(
        G0, "m/s2", "Gravity subtracted from the measured specific force", positive=True
    )


class Accelerometer(SampledSensor):
    """Input ``az``; outputs ``acc_z``, ``acc_count``, ``acc_time``."""

    Params = AccelerometerParams
    prefix = "acc"
    streams = ("noise", "turn_on_bias")
    normal_streams = ("noise",)

    def __init__(self, params: AccelerometerParams | None = None, **kwargs):
        self.az = 0.0
        super().__init__(params, **kwargs)

    def reset_sensor(self) -> None:
        p = self.params
        self.acc_z = 0.0
        self.total_bias = p.bias + p.bias_std * self.rng["turn_on_bias"].standard_normal()

    def measure(self) -> Sample:
        p = self.params
        specific_force = require_finite("az", self.az) + p.gravity
        measured = specific_force + self.total_bias + p.noise_std * (
            self.normal["noise"].draw())
        return Sample({"acc_z": measured - p.nominal_gravity})
