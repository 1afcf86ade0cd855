"""The atmosphere against the ISA table and its drift, lapse-rate and gust processes."""

import math

import numpy as np
import pytest

from altfusion.constants import G0, R_AIR
from altfusion.physics.atmosphere import H_MAX, H_MIN, Atmosphere, AtmosphereParams
from altfusion.physics.barometric import BarometricFormula, height_from_pressure, pressure_at

# ICAO standard atmosphere (geopotential altitude): h m, p Pa, T K, rho kg/m³.
ISA_TABLE = [
    (0.0, 101325.0, 288.15, 1.2250),
    (1000.0, 89874.6, 281.65, 1.1116),
    (2000.0, 79495.2, 275.15, 1.0065),
    (5000.0, 54019.9, 255.65, 0.73612),
    (8000.0, 35599.8, 236.15, 0.52517),
    (11000.0, 22632.1, 216.65, 0.36392),
    (15000.0, 12044.6, 216.65, 0.19367),
    (20000.0, 5474.89, 216.65, 0.088035),
]


@pytest.mark.parametrize(("h", "p", "T", "rho"), ISA_TABLE)
def test_matches_the_isa_table(h, p, T, rho):
    atmosphere = Atmosphere(inputs={"h": h})
    # The table gives 5-6 significant digits: agree to 2e-5 relative.
    assert atmosphere.p_static == pytest.approx(p, rel=2e-5)
    assert atmosphere.T_air == pytest.approx(T, abs=1e-9)
    assert atmosphere.rho_air == pytest.approx(rho, rel=2e-4)


def test_barometric_height_inverts_pressure():
    """height_from_pressure inverts pressure_at exactly; rounding of a few ε in p moves the
    height by the scale height R·T/g ≈ 8.6 km times that: ~1e-11 m (bound 1e-7 m over the
    troposphere; 1e-9 m for the isothermal case at 500 m)."""
    for h in np.linspace(-300.0, 11000.0, 50):
        p = pressure_at(h, 100500.0, 295.0, -0.0058)
        assert height_from_pressure(p, 100500.0, 295.0, -0.0058) == pytest.approx(h, abs=1e-7)
    assert height_from_pressure(pressure_at(500.0, 1e5, 280.0, 0.0), 1e5, 280.0, 0.0) == (
        pytest.approx(500.0, abs=1e-9))


def test_linear_drift_starts_on_time():
    params = AtmosphereParams(p0_rate=-10.0, T0_rate=-0.01, drift_start_time=2.0)
    atmosphere = Atmosphere(params, step_size=0.5)
    for n in range(10):
        atmosphere.do_step(0.5 * n, 0.5)
    assert atmosphere.time == 5.0
    assert atmosphere.p0_actual == 101325.0 - 10.0 * 3.0
    assert atmosphere.T0_actual == pytest.approx(288.15 - 0.03)


def test_lapse_rate_changes_every_period_with_the_stated_sigma():
    sigma, period, step = 0.003, 10.0, 0.5
    atmosphere = Atmosphere(AtmosphereParams(lapse_rate_std=sigma, lapse_rate_period=period,
                                             seed=7), step_size=step)
    values, changes_at = [], []
    previous = atmosphere.lapse_rate_actual
    for n in range(20 * 2000):
        atmosphere.do_step(step * n, step)
        if atmosphere.lapse_rate_actual != previous:
            changes_at.append(atmosphere.time)
            values.append(atmosphere.lapse_rate_actual)
            previous = atmosphere.lapse_rate_actual
    assert all(t % period == 0 for t in changes_at)
    assert len(values) == 2000
    deviations = np.array(values) + 0.0065
    # sample σ of N = 2000 normal draws: 99.9 % interval ±3.29·σ/√(2N)
    assert abs(deviations.std(ddof=1) - sigma) < 3.29 * sigma / math.sqrt(2 * len(values))
    # mean: 99.9 % interval ±3.29·σ/√N
    assert abs(deviations.mean()) < 3.29 * sigma / math.sqrt(len(values))


def test_gusts_have_the_stated_sigma_and_correlation_time():
    params = AtmosphereParams(wind_mean=20.0, gust_std=1.5, gust_time_constant=2.0, seed=3)
    atmosphere = Atmosphere(params, step_size=0.1)
    samples = []
    for n in range(200_000):
        atmosphere.do_step(0.1 * n, 0.1)
        samples.append(atmosphere.wind_speed)
    gust = np.array(samples) - 20.0
    # 200,000 samples with correlation time 20 steps: about 5,000 independent ones;
    # σ of the σ estimate ≈ σ/√(2·5000) = 1 %, so 5 % is a > 4-sigma bound.
    assert gust.std() == pytest.approx(1.5, rel=0.05)
    lag = 20  # one correlation time: autocorrelation e^-1
    rho = np.corrcoef(gust[:-lag], gust[lag:])[0, 1]
    assert rho == pytest.approx(math.exp(-1.0), abs=0.05)


def test_same_seed_same_weather_other_seed_other_weather():
    def lapse_series(seed):
        atmosphere = Atmosphere(AtmosphereParams(lapse_rate_std=0.003, seed=seed))
        out = []
        for n in range(3000):
            atmosphere.do_step(0.01 * n, 0.01)
            out.append(atmosphere.lapse_rate_actual)
        return out

    assert lapse_series(1) == lapse_series(1)
    assert lapse_series(1) != lapse_series(2)


def test_terrain_profile_is_interpolated_in_time():
    atmosphere = Atmosphere(AtmosphereParams(terrain_profile="0 100; 10 200"), step_size=1.0)
    for n in range(5):
        atmosphere.do_step(float(n), 1.0)
    assert atmosphere.terrain_h == 150.0


@pytest.mark.parametrize("h", [float("nan"), float("inf"), -1e308, H_MAX * 1.01, H_MIN - 1.0])
def test_an_altitude_outside_the_model_is_refused_not_a_nan(h):
    atmosphere = Atmosphere()
    atmosphere.h = h
    with pytest.raises(ValueError, match="input h = .* outside the model's range"):
        atmosphere.do_step(0.0, 0.01)
    assert math.isfinite(atmosphere.p_static)


def test_a_kept_calibration_is_the_barometric_formula_with_and_without_a_lapse_rate():
    """BarometricFormula about a reference off sea level (a barometer's calibration at 450 m)
    against the formula written out here in numpy: p = p_ref·(T/T_ref)^(-g/(Γ R)), and its
    isothermal limit p_ref·exp(-g Δh/(R T_ref)) below |Γ| 1e-12 K/m; heights the inverse.
    Both sides are a few operations on the same numbers (rounding: a few ulps); 1e-12
    relative is far above that and far below any formula error."""
    rng = np.random.default_rng(7)
    h = rng.uniform(-500.0, 9000.0, 200)
    for lapse in (-0.0065, 0.003, 0.0, 1e-13):
        formula = BarometricFormula(95000.0, 280.0, lapse, 450.0)
        if abs(lapse) < 1e-12:
            expected = 95000.0 * np.exp(-G0 * (h - 450.0) / (R_AIR * 280.0))
        else:
            expected = 95000.0 * ((280.0 + lapse * (h - 450.0)) / 280.0) ** (-G0 / (lapse * R_AIR))
        pressures = [formula.pressure(x) for x in h.tolist()]
        assert np.allclose(pressures, expected, rtol=1e-12, atol=0.0)
        assert np.allclose([formula.height(x) for x in pressures], h, rtol=0.0, atol=1e-8)
