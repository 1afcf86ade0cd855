"""AirDataModule: static pressure, air temperature and the baro-height of the launch calibration.

One sample follows the air through the instrument (bao2017 eq. 1: the height error is the
sum of the principle error ε_p, the drift ε_d, the external disturbance ε_e and the sensor
error):

1. Static port (bao2017 eqs. 7-8): p_port = p_static - k·½ρv², the wind's dynamic pressure
   seen as a static-pressure drop. ρ is the actual density p_static/(R·T_air) of the air, or
   the fixed ``dynamic_pressure_density`` if that is > 0 (bao2017 eq. 7 uses 1.25 kg/m³).
2. Transducer offset: p_sensor = p_port + ``pressure_bias``.
3. Height-domain errors, applied through the launch calibration so that pressure and height
   stay consistent: h' = h_cal(p_sensor) + ε_d + v, with h_cal the barometric formula of
   whang2008 eq. (1) / bao2017 eq. (2) for the calibration (H0, P0, T0, lapse_rate), ε_d the
   drift (a random walk with a mean rate: bao2017 eq. 6 with w of mean ``drift_rate`` and
   spectral density ``drift_variance_rate``; by default about +10 m per hour as in bao2017
   Fig. 1) and v white noise; then p' = p_cal(h'), the same formula inverted.
4. ADC: ``baro_p`` = p' quantized to ``pressure_resolution`` (MS5611: 0.012 hPa, bao2017
   Table 1) and ``baro_h`` = h_cal(``baro_p``): the baro-height is always the calibrated height
   of the reported pressure.

With no other error, baro_h - h_cal(p_static) is the wind disturbance error, and it equals
bao2017 eq. (11) with its pressure argument read as the undisturbed static pressure (eq. 11
then gives the correction, true minus measured height: the negative of the error).

The principle error is not injected: it emerges because the weather drifts in ``Atmosphere``
while the calibration keeps its launch values, giving whang2008 eqs. (2)-(4) to first order
(with the physical signs; see ``docs/sensors.md``). The temperature output is the air
temperature with a bias, white noise and the MS5611 resolution of 0.01 K.

Defaults model a MEMS air-data module of the class used in bao2017 and xu2016; the papers'
simulations set their own values (whang2008 Section 3: 5 m and 1.5 K; yang2020 Section 4.2:
20 m, 10 ms).
"""

import math
from dataclasses import dataclass

from altfusion.constants import ISA_LAPSE_RATE, ISA_P0, ISA_T0, R_AIR
from altfusion.params import param
from altfusion.physics.barometric import BarometricFormula
from altfusion.sensors.sampling import Sample, SampledSensor, SamplingParams, require_finite
from altfusion.timegrid import TickClock

SECONDS_PER_HOUR = 3600.0


@dataclass(frozen=True)
class AirDataParams(SamplingParams):
    sample_period: float = param(
        0.2, "s", "Time between samples (whang2008 Section 3: 0.2 s)", positive=True
    )
    H0: float = param(0.0, "m", "Calibration: height (MSL) of the launch site")
    P0: float = param(ISA_P0, "Pa", "Calibration: static pressure at H0 at launch",
                      positive=True)
    T0: float = param(ISA_T0, "K", "Calibration: air temperature at H0 at launch", positive=True)
    lapse_rate: float = param(
        ISA_LAPSE_RATE, "K/m", "Calibration: nominal lapse rate dT/dh", min=-0.0342, max=0.01
    )
    height_noise_std: float = param(
        0.5, "m", "White noise of the baro-height, 1 sigma (MEMS barometer, xu2016 reading "
        "in docs/papers.md: 0.5-1 m; whang2008 simulates 5 m, yang2020 20 m). At most 1000 m: the "
        "calibration's formula has no pressure above H0 + T0/|lapse_rate| (44 km in the ISA, "
        "8 km at the steepest lapse rate), which noise of more than a few km reaches",
        min=0.0, max=1000.0,
    )
    pressure_bias: float = param(0.0, "Pa", "Constant offset of the pressure transducer")
    pressure_resolution: float = param(
        1.2, "Pa", "Quantization step of the pressure reading (MS5611: 0.012 hPa, bao2017 "
        "Table 1); 0: none", min=0.0,
    )
    drift_rate: float = param(
        10.0 / SECONDS_PER_HOUR, "m/s",
        "Mean rate of the baro-height drift (bao2017 Fig. 1: about +10 m per hour). At most "
        "0.1 m/s in size (360 m per hour): faster drifts leave the calibration's atmosphere "
        "within a day (see height_noise_std)", min=-0.1, max=0.1,
    )
    drift_variance_rate: float = param(
        0.0025, "m2/s", "Spectral density sigma^2 of the drift's white rate noise w (bao2017 "
        "eq. 6): the random part of the drift has variance sigma^2*t (3 m after 1 h). At most "
        "100 m2/s (600 m after 1 h): a drift of many km leaves the calibration's atmosphere "
        "(see height_noise_std)", min=0.0, max=100.0,
    )
    wind_coupling: float = param(
        1.0, "1", "Fraction of the dynamic pressure 0.5*rho*v^2 seen as a static-pressure drop "
        "(bao2017 eq. 8: 1)", min=0.0,
    )
    dynamic_pressure_density: float = param(
        0.0, "kg/m3", "Air density in the dynamic pressure; 0: the actual density "
        "p_static/(R*T_air) (bao2017 eq. 7 uses 1.25)", min=0.0,
    )
    temperature_noise_std: float = param(
        0.1, "K", "White noise of the temperature reading, 1 sigma (whang2008 simulates 1.5 K). "
        "At most 30 K: a reading of air at 288 K then stays above 0 K within 9 sigma",
        min=0.0, max=30.0,
    )
    temperature_bias: float = param(0.0, "K", "Constant offset of the temperature reading")
    temperature_resolution: float = param(
        0.01, "K", "Quantization step of the temperature reading (MS5611: 0.01 degC, bao2017 "
        "Table 1); 0: none", min=0.0,
    )


def quantize(value: float, step: float) -> float:
    """``value`` rounded to the nearest multiple of ``step`` (unchanged if step is 0)."""
    return math.floor(value / step + 0.5) * step if step > 0 else value


class AirDataModule(SampledSensor):
    """Barometer and thermometer: inputs ``p_static``, ``T_air``, ``wind_speed``; outputs
    ``baro_p``, ``baro_T``, ``baro_h``, ``baro_count``, ``baro_time`` and the diagnostic
    ``baro_drift`` (the drift ε_d contained in the delivered sample: the truth an estimator of
    the drift can be checked against).

    Before the first sample the outputs hold the calibration point (P0, T0, H0), drift 0.
    """

    Params = AirDataParams
    prefix = "baro"
    streams = ("height_noise", "drift", "temperature_noise")
    normal_streams = streams

    def __init__(self, params: AirDataParams | None = None, **kwargs):
        self.p_static = ISA_P0
        self.T_air = ISA_T0
        self.wind_speed = 0.0
        super().__init__(params, **kwargs)

    def configure_sensor(self, clock: TickClock) -> None:
        p = self.params
        self._calibration = BarometricFormula(p.P0, p.T0, p.lapse_rate, p.H0)

    def reset_sensor(self) -> None:
        p = self.params
        self.baro_p, self.baro_T, self.baro_h = p.P0, p.T0, p.H0
        self.drift = 0.0
        self.baro_drift = 0.0
        self._drift_tick = 0

    # ----------------------------------------------------------------- calibration
    def calibrated_height(self, pressure: float) -> float:
        """whang2008 eq. (1) / bao2017 eq. (2) with the launch calibration, m."""
        return self._calibration.height(pressure)

    def calibrated_pressure(self, height: float) -> float:
        """The inverse of :meth:`calibrated_height`, Pa."""
        return self._calibration.pressure(height)

    def dynamic_pressure(self, p_static: float, T_air: float, wind_speed: float) -> float:
        """bao2017 eq. (7): ½ρv², with the actual or the fixed air density, Pa."""
        rho = self.params.dynamic_pressure_density or p_static / (R_AIR * T_air)
        return 0.5 * rho * wind_speed**2

    # ----------------------------------------------------------------- sampling
    def measure(self) -> Sample:
        p = self.params
        p_static = require_finite("p_static", self.p_static)
        T_air = require_finite("T_air", self.T_air)
        wind = require_finite("wind_speed", self.wind_speed)
        if p_static <= 0 or T_air <= 0:
            raise ValueError(f"inputs p_static = {p_static!r} Pa, T_air = {T_air!r} K must "
                             f"be > 0")
        p_port = p_static - p.wind_coupling * self.dynamic_pressure(p_static, T_air, wind)
        p_sensor = p_port + p.pressure_bias
        if p_sensor <= 0:
            raise ValueError(f"sensed pressure {p_sensor!r} Pa <= 0 (wind_speed = {wind!r} "
                             f"m/s, pressure_bias = {p.pressure_bias!r} Pa)")
        self._advance_drift()
        normal = self.normal
        calibration = self._calibration
        noise = p.height_noise_std * normal["height_noise"].draw()
        height = calibration.height(p_sensor) + self.drift + noise
        if p.T0 + p.lapse_rate * (height - p.H0) <= 0:
            raise ValueError(f"baro-height {height:.6g} m (drift {self.drift:.6g} m, noise "
                             f"{noise:.6g} m) is beyond the calibration's atmosphere, whose "
                             f"temperature reaches 0 K: lower height_noise_std or the drift")
        baro_p = quantize(calibration.pressure(height), p.pressure_resolution)
        temperature_noise = p.temperature_noise_std * normal["temperature_noise"].draw()
        baro_T = quantize(T_air + p.temperature_bias + temperature_noise,
                          p.temperature_resolution)
        return Sample({"baro_p": baro_p, "baro_T": baro_T,
                       "baro_h": calibration.height(baro_p), "baro_drift": self.drift})

    def _advance_drift(self) -> None:
        """bao2017 eq. (6) over the time since the last sample: dε_d/dt = w, E[w] = drift_rate,
        so ε_d grows by drift_rate·Δt + N(0, σ²Δt)."""
        p = self.params
        clock = self.clock
        elapsed = (clock.ticks - self._drift_tick) * clock.step_size       # ticks_since()
        self._drift_tick = clock.ticks
        step = math.sqrt(p.drift_variance_rate * elapsed) * self.normal["drift"].draw()
        self.drift += p.drift_rate * elapsed + step
