"""AirDataModule: error statistics, the wind disturbance of bao2017 eq. (11) and Table 3,
the drift of bao2017 eq. (6)/Fig. 1, and the principle error of whang2008 eqs. (2)-(4)
emerging from a drifting atmosphere."""

import math

import numpy as np
import pytest
from sensor_runs import Z999, mean_tolerance, run, std_tolerance

from altfusion.constants import G0, ISA_LAPSE_RATE, ISA_P0, ISA_T0, R_AIR
from altfusion.errors import ParameterError
from altfusion.physics.atmosphere import Atmosphere, AtmosphereParams
from altfusion.physics.barometric import height_from_pressure, pressure_at, temperature_at
from altfusion.sensors import AirDataModule, AirDataParams

QUIET = {"height_noise_std": 0.0, "pressure_resolution": 0.0, "drift_rate": 0.0,
         "drift_variance_rate": 0.0, "temperature_noise_std": 0.0,
         "temperature_resolution": 0.0}
"""Every error source off: the module reports the calibrated height of the static pressure."""

OUTPUTS = ("baro_p", "baro_T", "baro_h", "baro_drift", "baro_count")


def air_data(step: float = 0.2, **params) -> AirDataModule:
    return AirDataModule(AirDataParams(**{"sample_period": step, **params}), step_size=step)


def isa_air(h: float) -> dict[str, float]:
    """The ISA static pressure and temperature at height h: the calibration's own atmosphere."""
    return {"p_static": pressure_at(h, ISA_P0, ISA_T0, ISA_LAPSE_RATE),
            "T_air": temperature_at(h, ISA_T0, ISA_LAPSE_RATE)}


def climbing(t: float) -> dict[str, float]:
    """A vehicle oscillating between 0 and 2000 m."""
    return isa_air(1000.0 - 1000.0 * math.cos(2 * math.pi * t / 600.0))


def true_height(t: np.ndarray) -> np.ndarray:
    return 1000.0 - 1000.0 * np.cos(2 * np.pi * t / 600.0)


def test_with_every_error_off_the_baro_height_is_the_true_height():
    series = run(air_data(**QUIET), 3000, OUTPUTS, climbing)
    assert np.max(np.abs(series["baro_h"] - true_height(series["time"]))) < 1e-9
    assert series["baro_count"][-1] == 3000


def test_before_the_first_sample_the_outputs_hold_the_calibration_point():
    sensor = air_data(step=0.01, H0=120.0, P0=99900.0, T0=290.0)
    assert (sensor.baro_h, sensor.baro_p, sensor.baro_T, sensor.baro_count) == (
        120.0, 99900.0, 290.0, 0)


def test_height_noise_has_the_stated_sigma_and_zero_mean():
    sigma, n = 0.8, 20000
    series = run(air_data(**{**QUIET, "height_noise_std": sigma}, seed=1), n, OUTPUTS,
                 climbing)
    error = series["baro_h"] - true_height(series["time"])
    assert abs(error.mean()) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)
    # the reported pressure is consistent with the reported height
    baro_h = [height_from_pressure(p, ISA_P0, ISA_T0, ISA_LAPSE_RATE) for p in series["baro_p"]]
    assert np.max(np.abs(series["baro_h"] - baro_h)) < 1e-9


def test_temperature_has_the_stated_bias_and_sigma():
    sigma, bias, n = 1.5, 0.4, 20000
    series = run(air_data(**{**QUIET, "temperature_noise_std": sigma,
                             "temperature_bias": bias}, seed=2), n, OUTPUTS, climbing)
    truth = temperature_at(true_height(series["time"]), ISA_T0, ISA_LAPSE_RATE)
    error = series["baro_T"] - truth
    assert abs(error.mean() - bias) < mean_tolerance(sigma, n)
    assert abs(error.std(ddof=1) - sigma) < std_tolerance(sigma, n)


def test_pressure_bias_offsets_the_reported_pressure_exactly():
    """Without noise, drift or quantization the offset is exact up to rounding: the round trip
    through the calibration's height (1e5 Pa × a few ε ≈ 1e-10 Pa; bound 1e-6 Pa)."""
    series = run(air_data(**{**QUIET, "pressure_bias": 35.0}), 500, OUTPUTS, climbing)
    truth = [isa_air(h)["p_static"] for h in true_height(series["time"])]
    assert np.allclose(series["baro_p"] - truth, 35.0, rtol=0, atol=1e-6)


def test_pressure_is_quantized_to_the_resolution_with_a_uniform_error():
    """MS5611 (bao2017 Table 1): 0.012 hPa. The quantization error of a slowly varying
    pressure is uniform on ±q/2: variance q²/12; its sample variance over N samples has
    standard deviation q²·√((1/80 - 1/144)/N) (fourth moment of the uniform: q⁴/80)."""
    q, n = 1.2, 20000
    series = run(air_data(**{**QUIET, "pressure_resolution": q}), n, OUTPUTS, climbing)
    steps = series["baro_p"] / q
    assert np.max(np.abs(steps - np.round(steps))) < 1e-9
    truth = np.array([isa_air(h)["p_static"] for h in true_height(series["time"])])
    error = series["baro_p"] - truth
    assert np.max(np.abs(error)) <= q / 2 + 1e-9
    assert abs(error.var() - q * q / 12) < Z999 * q**2 * math.sqrt((1 / 80 - 1 / 144) / n)


def test_drift_increments_have_the_stated_mean_rate_and_spectral_density():
    """bao2017 eq. (6) with w of mean μ and spectral density σ²: increments over Δt are
    independent N(μΔt, σ²Δt)."""
    rate, variance_rate, dt, n = 0.01, 0.04, 0.2, 20000
    series = run(air_data(**{**QUIET, "drift_rate": rate, "drift_variance_rate": variance_rate},
                          seed=3), n, OUTPUTS, climbing)
    assert np.max(np.abs(series["baro_h"] - true_height(series["time"])
                         - series["baro_drift"])) < 1e-6
    increments = np.diff(np.concatenate([[0.0], series["baro_drift"]]))
    sigma = math.sqrt(variance_rate * dt)
    assert abs(increments.mean() - rate * dt) < mean_tolerance(sigma, n)
    assert abs(increments.std(ddof=1) - sigma) < std_tolerance(sigma, n)


def test_default_drift_is_about_ten_metres_per_hour():
    """bao2017 Fig. 1: about +10 m in an hour. Over 400 seeds the drift after 3600 s has mean
    drift_rate·3600 = 10 m and standard deviation √(σ²·3600) = 3 m."""
    runs = 400
    final = []
    for seed in range(runs):
        sensor = air_data(step=60.0, seed=seed)
        run(sensor, 60, ())
        final.append(sensor.baro_drift)
    final = np.array(final)
    defaults = AirDataParams()
    assert defaults.drift_rate * 3600.0 == pytest.approx(10.0)
    spread = math.sqrt(defaults.drift_variance_rate * 3600.0)
    assert abs(final.mean() - 10.0) < mean_tolerance(spread, runs)
    assert abs(final.std(ddof=1) - spread) < std_tolerance(spread, runs)


def test_enabling_one_error_source_does_not_change_another_ones_realization():
    noise = {**QUIET, "height_noise_std": 1.0}
    drift = {**QUIET, "drift_variance_rate": 0.05}
    both = {**noise, "drift_variance_rate": 0.05}
    errors = {}
    for name, params in (("noise", noise), ("drift", drift), ("both", both)):
        series = run(air_data(seed=8, **params), 2000, OUTPUTS, climbing)
        errors[name] = series["baro_h"] - true_height(series["time"])
    assert np.max(np.abs(errors["both"] - errors["noise"] - errors["drift"])) < 1e-6


# --------------------------------------------------------------------- wind disturbance
def eq11(p_s: float, v: float, rho: float, T0: float, P0: float, beta: float) -> float:
    """bao2017 eq. (11), written out independently of the core:
    ε_e = (T0/β)[(P_S/P0)^(-βR/g) - ((P_S - ½ρv²)/P0)^(-βR/g)]."""
    x = -beta * R_AIR / G0
    return T0 / beta * ((p_s / P0) ** x - ((p_s - 0.5 * rho * v * v) / P0) ** x)


def wind_error(params: dict, p_static: float, T_air: float, v: float) -> tuple[float, float]:
    """(baro_h in wind - baro_h in calm air, baro_p in wind) after one sample."""
    readings = []
    for wind in (v, 0.0):
        sensor = air_data(**{**QUIET, **params})
        run(sensor, 1, (), lambda t, w=wind: {"p_static": p_static, "T_air": T_air,
                                              "wind_speed": w})
        readings.append((sensor.baro_h, sensor.baro_p))
    return readings[0][0] - readings[1][0], readings[0][1]


@pytest.mark.parametrize("h", [0.0, 800.0, 3000.0])
@pytest.mark.parametrize("v", [1.5, 2.5, 3.5, 12.0])
@pytest.mark.parametrize("rho", [0.0, 1.25])
def test_wind_error_is_exactly_seed_001_eq_11(h, v, rho):
    """Eq. (11) is the correction (true minus measured height) when its pressure argument is
    the undisturbed static pressure: the error is its negative. Evaluated at the disturbed
    pressure, as the paper's P_S' suggests, it differs by terms of order (½ρv²/p)²."""
    air = isa_air(h)
    density = rho or air["p_static"] / (R_AIR * air["T_air"])
    error, baro_p = wind_error({"dynamic_pressure_density": rho}, air["p_static"],
                               air["T_air"], v)
    expected = -eq11(air["p_static"], v, density, ISA_T0, ISA_P0, ISA_LAPSE_RATE)
    assert error > 0  # less static pressure: the barometer reads high
    assert error == pytest.approx(expected, rel=0, abs=1e-9)
    at_measured = -eq11(baro_p, v, density, ISA_T0, ISA_P0, ISA_LAPSE_RATE)
    assert at_measured == pytest.approx(error, rel=4 * 0.5 * density * v * v / baro_p)


@pytest.mark.parametrize(("v", "table_3"), [(1.5, 0.1283), (2.5, 0.3510), (3.5, 0.6857)])
def test_wind_error_matches_seed_001_table_3_at_a_site_air_density_of_1_12(v, table_3):
    """docs/papers.md: Table 3's theoretical values are eq. (11) with the paper's ρ = 1.25 kg/m³ in
    eq. (7) at a site whose own air density is about 1.12 kg/m³ (a warm day: 30 °C). The
    barometer is calibrated at the site. The error scales as 1/ρ_site, and that density is
    inferred ("about 1.12"): 5 % covers 1.07-1.18 kg/m³, a site ±15 K around 30 °C."""
    T_site = 303.15
    p_site = 1.12 * R_AIR * T_site
    error, _ = wind_error({"dynamic_pressure_density": 1.25, "P0": p_site, "T0": T_site},
                          p_site, T_site, v)
    assert error == pytest.approx(table_3, rel=0.05)


def test_with_the_actual_air_density_the_wind_error_is_the_dynamic_head():
    """With ρ the density of the air itself, eq. (11) is ½ρv²/(ρg) = v²/(2g) to first order,
    whatever the weather: 0.1147 m at 1.5 m/s. The second-order term is of relative size
    ½ρv²/p ≈ 1.4 Pa / 1e5 Pa ≈ 1e-5 (5.5e-6 here); bound 1e-3."""
    for p_static, T_air in ((ISA_P0, ISA_T0), (95000.0, 305.0)):
        error, _ = wind_error({"P0": p_static, "T0": T_air}, p_static, T_air, 1.5)
        assert error == pytest.approx(1.5**2 / (2 * G0), rel=1e-3)


def test_wind_coupling_scales_the_dynamic_pressure():
    """Eq. (11) is linear in the pressure drop up to its second-order term, of relative size
    ½ρv²/p = 61 Pa / 101325 Pa = 6e-4 at 10 m/s (1.2e-4 here); bound 1e-3."""
    full, _ = wind_error({}, ISA_P0, ISA_T0, 10.0)
    half, _ = wind_error({"wind_coupling": 0.5}, ISA_P0, ISA_T0, 10.0)
    assert half == pytest.approx(full / 2, rel=1e-3)


# --------------------------------------------------------------------- principle error
def principle_error(p0_rate: float, T0_rate: float, duration: float) -> tuple[float, float,
                                                                              float, float]:
    """Fly the barometer (calibrated for ISA at sea level at launch) at heights 0-3000 m in an
    atmosphere whose sea-level pressure and temperature drift for ``duration`` seconds; fit
    baro_h - h = a·h + b. Returns (a, b, ΔP/P0, ΔT/T0)."""
    heights = np.linspace(0.0, 3000.0, 7)
    errors = []
    for h in heights:
        atmosphere = Atmosphere(AtmosphereParams(p0_rate=p0_rate, T0_rate=T0_rate),
                                step_size=10.0, inputs={"h": h})
        run(atmosphere, round(duration / 10.0), ())
        sensor = air_data(**QUIET)
        run(sensor, 1, (), lambda t, a=atmosphere: {"p_static": a.p_static, "T_air": a.T_air})
        errors.append(sensor.baro_h - h)
    a, b = np.polyfit(heights, errors, 1)
    residual = np.array(errors) - (a * heights + b)
    assert np.max(np.abs(residual)) < 1e-6  # the error is exactly linear in h
    return a, b, (atmosphere.p0_actual - ISA_P0) / ISA_P0, (atmosphere.T0_actual - ISA_T0) / ISA_T0


@pytest.mark.parametrize(("p0_rate", "T0_rate"), [
    (0.0, 0.01), (0.0, -0.01), (-1.0, 0.0), (1.0, 0.0), (-1.0, -0.01), (0.5, 0.008),
])
def test_scale_factor_and_bias_emerge_as_seed_000_eqs_3_4_to_first_order(p0_rate, T0_rate):
    """whang2008 eqs. (3)-(4): a = ΔT/T0, b = (RT0/g)ΔP/P0; bao2017 eq. (5) adds the
    first-order term (RΓ/g)ΔP/P0 to a, which whang2008 neglects. Both papers' a and b are the
    correction (true minus baro height, cf. bao2017 eq. 4 and docs/papers.md on eq. 3): the error
    baro_h - h = a·h + b has the opposite signs, a ≈ -ΔT/T0 - (RΓ/g)ΔP/P0 and
    b ≈ -(RT0/g)ΔP/P0 (a warmer or higher-pressure atmosphere makes the barometer read low).

    First order: with r = ΔP/P0, s = ΔT/T0, ε = |r| + |s| ≤ 0.1, the exact error is linear in
    h with a = (1+r)^x/(1+s) - 1 and b = (T0/Γ)((1+r)^x - 1), x = -ΓR/g ≈ 0.19, so the
    neglected second-order terms are bounded by |Δa| ≤ 2ε² and |Δb| ≤ (RT0/g)·r²."""
    a, b, r, s = principle_error(p0_rate, T0_rate, duration=1000.0)
    epsilon = abs(r) + abs(s)
    scale_eq3, bias_eq4 = s, R_AIR * ISA_T0 / G0 * r
    pressure_term = R_AIR * ISA_LAPSE_RATE / G0 * r  # bao2017 eq. (5)
    assert a == pytest.approx(-(scale_eq3 + pressure_term), abs=2 * epsilon**2)
    assert b == pytest.approx(-bias_eq4, abs=R_AIR * ISA_T0 / G0 * r * r + 1e-9)
    if p0_rate == 0.0:
        assert abs(b) < 1e-6
        assert a == pytest.approx(-scale_eq3, abs=2 * epsilon**2)


def test_the_principle_error_grows_with_the_weather_drift():
    """hajiyev Section 5's drift (-10 Pa/s, -0.01 K/s): the bias follows -(RT0/g)·ΔP(t)/P0
    as the pressure falls (first order, as above), growing linearly in time."""
    biases = []
    for duration in (10.0, 20.0, 40.0, 80.0):
        a, b, r, s = principle_error(-10.0, -0.01, duration)
        assert b == pytest.approx(-R_AIR * ISA_T0 / G0 * r, abs=R_AIR * ISA_T0 / G0 * r * r)
        biases.append(b)
    assert 0 < biases[0] < biases[1] < biases[2] < biases[3]


def test_noise_beyond_the_calibration_atmosphere_is_refused_by_name():
    """The calibration's formula has no pressure where its temperature T0 + lapse·(h - H0)
    reaches 0 K: 29 m above H0 with T0 = 1 K and the steepest lapse rate, -0.0342 K/m, which
    a noise of 1000 m leaves within a few samples. The sample fails with a
    ValueError naming the cause instead of a complex pressure (TypeError at t = 0)."""
    sensor = air_data(**{**QUIET, "height_noise_std": 1000.0, "T0": 1.0,
                         "lapse_rate": -0.0342}, seed=1)
    with pytest.raises(ValueError, match=r"beyond the calibration's atmosphere, whose "
                                         r"temperature reaches 0 K: lower height_noise_std"):
        run(sensor, 10, OUTPUTS, lambda t: {"p_static": 1.0e5, "T_air": 288.0})


def test_noise_std_beyond_its_bound_is_refused_at_initialization():
    with pytest.raises(ParameterError, match=r"'height_noise_std' = 1000000.0: must be <= 1000"):
        air_data(height_noise_std=1e6)
