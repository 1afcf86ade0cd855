"""VerticalDynamics against closed-form solutions."""

import math

import pytest

from altfusion.errors import ParameterError
from altfusion.physics.vertical_dynamics import (
    MAX_SUBSTEPS,
    VerticalDynamics,
    VerticalDynamicsParams,
)


def fly(model: VerticalDynamics, thrust: float, duration: float) -> VerticalDynamics:
    steps = round(duration / model.dt)
    for n in range(steps):
        model.thrust = thrust
        model.do_step(model.clock.time(n), model.dt)
    return model


@pytest.mark.parametrize("step", [0.001, 0.01, 0.2, 1.0])
def test_constant_thrust_without_drag_is_a_parabola(step):
    """RK4 is exact for a constant acceleration (h is a quadratic in t), so only rounding
    remains. It accumulates as a random walk over the n ≤ 20000 sub-steps (1 ms steps over
    20 s): √n·ε·|h| ≈ 141 × 2.2e-16 × 260 m ≈ 8e-12 m (bound 1e-9 m), and
    ≈ 141 × 2.2e-16 × 13 m/s ≈ 4e-13 m/s for vz (bound 1e-11 m/s); az is one evaluation,
    exact to ε·0.5 (bound 1e-12 m/s²)."""
    params = VerticalDynamicsParams(mass=2.0, drag_coefficient=0.0, h0=100.0, vz0=3.0)
    thrust = 2.0 * (9.80665 + 0.5)  # net acceleration +0.5 m/s²
    model = fly(VerticalDynamics(params, step_size=step), thrust, 20.0)
    assert model.h == pytest.approx(100.0 + 3.0 * 20.0 + 0.5 * 0.5 * 20.0**2, abs=1e-9)
    assert model.vz == pytest.approx(3.0 + 0.5 * 20.0, abs=1e-11)
    assert model.az == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("step", [0.01, 0.1, 0.5])
def test_free_fall_with_quadratic_drag_follows_the_tanh_solution(step):
    m, c, g = 1.5, 0.05, 9.80665
    params = VerticalDynamicsParams(mass=m, drag_coefficient=c, h0=5000.0)
    model = fly(VerticalDynamics(params, step_size=step), 0.0, 30.0)
    v_terminal = math.sqrt(m * g / c)
    t = 30.0
    vz = -v_terminal * math.tanh(g * t / v_terminal)
    h = 5000.0 - v_terminal**2 / g * math.log(math.cosh(g * t / v_terminal))
    # RK4 at 1 ms sub-steps: global error O(1e-12) per unit; 1e-8 m is a loose bound.
    assert model.vz == pytest.approx(vz, abs=1e-9)
    assert model.h == pytest.approx(h, abs=1e-8)


def test_results_do_not_depend_on_the_communication_step():
    params = VerticalDynamicsParams(h0=10.0)
    fine = fly(VerticalDynamics(params, step_size=0.001), 20.0, 6.0)
    coarse = fly(VerticalDynamics(params, step_size=0.5), 20.0, 6.0)
    assert coarse.h == pytest.approx(fine.h, abs=1e-10)


def test_vehicle_rests_on_the_ground_without_enough_thrust():
    model = fly(VerticalDynamics(VerticalDynamicsParams(h0=0.0)), 5.0, 2.0)
    assert (model.h, model.vz, model.az) == (0.0, 0.0, 0.0)


def test_vehicle_lands_and_stays_down():
    model = fly(VerticalDynamics(VerticalDynamicsParams(h0=2.0)), 0.0, 5.0)
    assert model.h == 0.0 and model.vz == 0.0


def test_non_finite_thrust_is_an_error_not_a_nan():
    model = VerticalDynamics()
    model.thrust = float("nan")
    with pytest.raises(ValueError, match="thrust = nan"):
        model.do_step(0.0, 0.01)


def test_a_thrust_driving_the_state_non_finite_is_refused_and_the_state_kept():
    """1e308 N on 1.5 kg overflows the RK4 stages to inf: the step fails, the state stays."""
    model = VerticalDynamics()
    model.thrust = 1e308
    with pytest.raises(ValueError, match="thrust = 1e\\+308 N drives the state non-finite"):
        model.do_step(0.0, 0.01)
    assert (model.h, model.vz) == (0.0, 0.0)


def test_a_sub_step_needing_unbounded_work_is_refused_naming_the_parameter():
    """1e-300 s would need 1e298 RK4 sub-steps per 0.01 s step (the run would hang)."""
    with pytest.raises(ParameterError, match="'max_substep' = 1e-300"):
        VerticalDynamics(VerticalDynamicsParams(max_substep=1e-300))
    bound = VerticalDynamics(VerticalDynamicsParams(max_substep=0.01 / MAX_SUBSTEPS))
    assert bound._substeps == MAX_SUBSTEPS


def test_any_communication_step_integrates_exactly_to_its_end():
    """The same climb on the 0.01 s tick, in host steps of 1 ms, of 0.025 s and in one
    0.75 s step: RK4 with sub-steps of at most 5 ms agrees to its truncation error
    (O(dt⁴) with a ≈ 1 m/s² and drag: far below 1e-9 m), and a 1e-13 s remainder moves
    nothing measurable."""
    params = VerticalDynamicsParams(h0=10.0, vz0=2.0)
    thrust = 1.5 * (9.80665 + 1.0)
    on_tick = fly(VerticalDynamics(params, step_size=0.01), thrust, 0.75)
    for host_step in (0.001, 0.025, 0.75):
        model = VerticalDynamics(params, step_size=0.01)
        model.thrust = thrust
        time = 0.0
        while time < 0.75 - 1e-12:
            model.do_step(time, host_step)
            time += host_step
        model.do_step(time, 0.75 - time if time < 0.75 else 1e-13)
        assert model.h == pytest.approx(on_tick.h, abs=1e-9), host_step
        assert model.vz == pytest.approx(on_tick.vz, abs=1e-9), host_step


def test_a_step_of_one_tick_is_the_ticks_own_integration_bit_for_bit():
    params = VerticalDynamicsParams(h0=10.0, vz0=2.0)
    stepped, updated = VerticalDynamics(params), VerticalDynamics(params)
    for n in range(50):
        stepped.thrust = updated.thrust = 20.0 + n % 7
        stepped.do_step(n * 0.01, 0.01)
        updated.clock.tick()
        updated.update()
        assert (stepped.h, stepped.vz, stepped.az) == (updated.h, updated.vz, updated.az)
