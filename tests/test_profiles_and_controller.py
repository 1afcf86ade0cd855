"""Reference profiles and the flight controller's tracking on every profile."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from altfusion.errors import ParameterError
from altfusion.physics.controller_design import design
from altfusion.physics.flight_controller import (
    DESIGN_KD,
    DESIGN_KI,
    DESIGN_KP,
    FlightController,
    FlightControllerParams,
)
from altfusion.physics.profiles import PROFILE_NAMES, make_profile
from altfusion.physics.vertical_dynamics import VerticalDynamics, VerticalDynamicsParams

TABLE = "0 0; 10 5; 50 5; 60 0"


def test_yang2020_phases_as_in_seed_003():
    profile = make_profile("yang2020")
    assert profile.reference(30.0)[2] == 0.2            # accelerating climb
    assert profile.reference(90.0)[1:] == (12.0, 0.0)    # uniform climb at 12 m/s
    assert profile.reference(150.0)[2] == -0.2           # slowing down
    assert profile.reference(210.0) == pytest.approx((1440.0, 0.0, 0.0))  # cruise
    assert profile.reference(270.0)[2] == -0.2
    assert profile.reference(330.0)[1:] == (-12.0, 0.0)
    assert profile.reference(390.0)[2] == 0.2
    # the landing is the sum of the phases' closed forms: rounding of 1440 m terms, ~1e-13 m
    assert profile.reference(420.0)[:2] == pytest.approx((0.0, 0.0), abs=1e-9)


def test_hajiyev_descends_from_about_10894_m_to_about_123_m():
    profile = make_profile("hajiyev")
    assert profile.reference(0.0)[0] == pytest.approx(10894.0, abs=3.0)
    assert profile.reference(1560.0)[0] == pytest.approx(123.47, abs=0.5)


def test_unknown_profile_is_rejected_by_name():
    with pytest.raises(ParameterError, match="'profile' = 'loop'"):
        make_profile("loop")


@settings(deadline=None, max_examples=60)
@given(name=st.sampled_from([n for n in PROFILE_NAMES if n != "table"]),
       t=st.floats(min_value=0.5, max_value=1500.0))
def test_profiles_are_consistent_h_vz_az(name, t):
    """vz is the time derivative of h and az that of vz (central differences; at a kink the
    difference is the mean of both sides, hence the allowance of the jump across it). The
    1e-6 floor is above a central difference's rounding, ε·|h| / 2d ≈ 2.2e-16 × 1.1e4 m /
    2e-4 s ≈ 1e-8 m/s (h up to the 10,894 m of the hajiyev profile)."""
    profile = make_profile(name)
    d = 1e-4
    (h1, v1, a1), (h2, v2, a2) = profile.reference(t - d), profile.reference(t + d)
    _, v, a = profile.reference(t)
    assert (h2 - h1) / (2 * d) == pytest.approx(v, abs=1e-6 + abs(v2 - v1))
    assert (v2 - v1) / (2 * d) == pytest.approx(a, abs=1e-6 + abs(a2 - a1))


def test_default_gains_are_the_python_control_pole_placement():
    result = design()
    assert (result.kp, result.kd, result.ki) == pytest.approx((DESIGN_KP, DESIGN_KD, DESIGN_KI))
    assert np.allclose(sorted(result.closed_loop_poles.real), [-1.0, -1.0, -1.0])
    assert result.phase_margin_deg > 45.0


# Worst tracking error allowed per profile, m. Paper profiles are feasible, so the PID with
# feedforward tracks them to about 1e-4 m; 'hajiyev' levels off with a step in vz_ref
# (-4.2 m/s to 0) and 'table' has corners: both overshoot by up to about 1 m.
BOUNDS = {"yang2020": 1e-3, "whang2008": 1e-3, "xu_hover15": 1e-3, "xu_hover35": 1e-3,
          "xu_multipoint": 1e-3, "fault_flight": 1e-3, "hold": 1e-9, "hajiyev": 1.0,
          "table": 0.2}
DURATIONS = {"yang2020": 420, "whang2008": 600, "xu_hover15": 120, "xu_hover35": 120,
             "xu_multipoint": 1000, "fault_flight": 300, "hold": 60, "hajiyev": 1600, "table": 100}


@pytest.mark.parametrize("name", PROFILE_NAMES)
def test_controller_tracks_every_profile_within_its_bound(name):
    profile = make_profile(name, table=TABLE)
    h0, vz0, _ = profile.reference(0.0)
    plant = VerticalDynamics(VerticalDynamicsParams(h0=h0, vz0=vz0))
    controller = FlightController(FlightControllerParams(profile=name, profile_table=TABLE),
                                  inputs={"h_fb": h0, "vz_fb": vz0})
    worst = 0.0
    for n in range(round(DURATIONS[name] / 0.01)):
        plant.thrust = controller.thrust
        plant.do_step(n * 0.01, 0.01)
        controller.h_fb, controller.vz_fb = plant.h, plant.vz
        controller.do_step(n * 0.01, 0.01)
        worst = max(worst, abs(plant.h - controller.h_ref))
    assert worst < BOUNDS[name]


def test_absurd_feedback_gives_a_bounded_thrust_or_an_error_never_nan():
    """A finite but absurd altitude is clipped by the saturation; kp (1e300) x error (-1e308)
    plus ki x integral (+inf) is inf - inf: refused."""
    controller = FlightController()
    controller.h_fb = 1e308
    controller.do_step(0.0, controller.dt)
    assert controller.thrust == 0.0
    wild = FlightController(FlightControllerParams(kp=1e300, ki=1e300))
    wild.h_fb, wild.vz_fb = 1e308, -1e308
    with pytest.raises(ValueError, match="gives no thrust"):
        wild.do_step(0.0, wild.dt)
