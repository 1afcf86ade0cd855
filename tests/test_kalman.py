"""The shared Kalman machinery (altfusion.estimators.kalman)."""

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from altfusion.estimators.kalman import (
    constant_states_noise,
    inflate_along,
    joseph_first_of_two,
    limit_variance,
    move_datum,
    predict_constant_acceleration_in_place,
    predict_height_and_speed,
    predict_sparse,
    quadratic_form,
    rederive,
    shift_state,
    sparse_dot,
    update_first_of_two,
    update_one_state,
    update_scalar,
    update_scalar_of,
    white_jerk_noise,
)
from altfusion.estimators.registry import ESTIMATOR_CLASSES

sys.path.insert(0, str(Path(__file__).parent))
from kalman_reference import joseph, predict, update  # noqa: E402

positive = st.floats(min_value=1e-3, max_value=1e4)


@given(P=positive, R=positive, x=st.floats(-1e3, 1e3), z=st.floats(-1e3, 1e3))
def test_scalar_update_is_the_textbook_one(P, R, x, z):
    """Both sides are a few floating-point operations on the same numbers, so they differ by
    rounding only: a few ulps (2.2e-16 relative each). 1e-9 relative (for x: of the operands'
    magnitudes, since z - x may cancel) is far above that and far below any formula error."""
    result = update(np.array([x]), np.array([[P]]), z, np.array([[1.0]]), R)
    K = P / (P + R)
    assert result.K[0, 0] == pytest.approx(K)
    assert result.x[0] == pytest.approx(x + K * (z - x), abs=1e-9 * (1 + abs(z) + abs(x)))
    assert result.P[0, 0] == pytest.approx((1 - K) * P, rel=1e-9)


@given(P=positive, R=positive, alpha=st.floats(0.0, 1.0))
def test_joseph_form_is_exact_for_a_scaled_gain(P, R, alpha):
    """The Joseph form holds for any gain; both sides differ by rounding only (1e-9 relative,
    as in test_scalar_update_is_the_textbook_one)."""
    result = update(np.array([0.0]), np.array([[P]]), 1.0, np.array([[1.0]]), R,
                    gain_scale=alpha)
    K = alpha * P / (P + R)
    assert result.P[0, 0] == pytest.approx((1 - K) ** 2 * P + K**2 * R, rel=1e-9)


def test_vector_update_keeps_p_symmetric_positive_definite():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((3, 3))
    P = A @ A.T + np.eye(3)
    H = np.array([[1.0, 0.0, 1.0]])
    result = update(np.zeros(3), P, 2.0, H, 0.5)
    assert np.array_equal(result.P, result.P.T)
    assert np.all(np.linalg.eigvalsh(result.P) > 0)
    assert result.nis == pytest.approx(4.0 / ((H @ P @ H.T)[0, 0] + 0.5))


@given(P=st.floats(0.0, 1e6), R=positive, x=st.floats(-1e4, 1e4), z=st.floats(-1e4, 1e4),
       gain_scale=st.floats(0.0, 1.0))
def test_one_state_update_on_floats_is_the_array_update_bit_for_bit(P, R, x, z, gain_scale):
    """Not to rounding: the same floats (the estimators' outputs are checksummed)."""
    result = update(np.array([x]), np.array([[P]]), z, np.array([[1.0]]), R, gain_scale)
    assert _bits(update_one_state(x, P, z, R, gain_scale)) == _bits(
        (result.x[0], result.P[0, 0], result.K[0, 0]))


def test_first_of_two_states_update_on_floats_is_the_array_update_bit_for_bit():
    """For H = [1, 0] the floats of :func:`update` and :func:`joseph`, whatever BLAS's
    kernel (every product in their matrix products is exact, no sum has more than two
    non-zero terms): on covariances of every scale, with the exact zeros of a diagonal
    start. 1000 draws."""
    rng = np.random.default_rng(2)
    H = np.array([[1.0, 0.0]])
    for draw in range(1000):
        P = _random_covariance(rng, 2) if draw % 4 else np.diag(rng.uniform(0.1, 100.0, 2))
        P = 0.5 * (P + P.T)
        x = rng.normal(0.0, 100.0, 2)
        z, R = float(rng.normal(0.0, 100.0)), float(10 ** rng.uniform(-4, 3))
        result = update(x, P, z, H, R)
        x_new, P_new, gain = update_first_of_two(x.tolist(), P.tolist(), z, R)
        assert _bits(x_new) == _bits(result.x)
        assert _bits(P_new) == _bits(result.P)
        assert _bits(gain) == _bits(result.K[:, 0])
        R_other = float(10 ** rng.uniform(-4, 3))
        assert _bits(joseph_first_of_two(P.tolist(), gain, R_other)) == _bits(
            joseph(P, result.K, H, R_other))


@pytest.mark.parametrize("H", [((0, 1.0),), ((0, 1.0), (2, 1.0)), ((0, 1.0), (3, 1.0))])
def test_a_sparse_rows_products_are_the_array_products_bit_for_bit(H):
    """H x and H P Hᵀ of a sparse row (XuSHAEKF's and BaselineKF's rows: at most two terms
    per sum, all exact products) are the floats of ``H @ x`` and ``H @ P @ H.T``, on
    symmetric covariances of every scale, with a diagonal start's exact zeros. 500 draws."""
    rng = np.random.default_rng(3)
    H_array = np.zeros((1, 4))
    for i, h in H:
        H_array[0, i] = h
    for draw in range(500):
        P = _random_covariance(rng, 4) if draw % 4 else np.diag(rng.uniform(0.1, 100.0, 4))
        P = 0.5 * (P + P.T)
        x = rng.normal(0.0, 100.0, 4)
        predicted, hph = sparse_dot(x.tolist(), H), quadratic_form(P.tolist(), H)
        assert _bits((predicted, hph)) == _bits(
            ((H_array @ x)[0], (H_array @ P @ H_array.T)[0, 0]))


SPARSE_TRANSITIONS = {"XuSHAEKF": "_Phi", "BaselineKF": "_F", "WhangGAEstimator": "_F"}
"""The estimators that predict with :func:`predict_sparse`, and the attribute holding their
transition matrix as sparse rows, built for their step (xu2016 eq. 10, a constant speed with
a constant bias, whang2008 eq. 33)."""


@pytest.mark.parametrize("model", sorted(SPARSE_TRANSITIONS))
def test_a_sparse_predict_is_the_matrix_one(model):
    """F P Fᵀ + Q and F x + B u from F's sparse rows equal the matrix form to rounding
    (1e-12 relative: a few float operations per entry, each within 1.1e-16) and are exactly
    symmetric. 300 draws of dt, P, Q and x."""
    rng = np.random.default_rng(13)
    for _ in range(300):
        dt = 10 ** rng.uniform(-3, 0)
        rows = getattr(ESTIMATOR_CLASSES[model](step_size=dt), SPARSE_TRANSITIONS[model])
        n = len(rows)
        F = np.zeros((n, n))
        for a, row in enumerate(rows):
            for b, f in row:
                F[a, b] = f
        P, Q = _random_covariance(rng, n), _random_covariance(rng, n)
        x, Bu = 100 * rng.standard_normal(n), rng.standard_normal(n)
        x_s, P_s = predict_sparse(x.tolist(), P.tolist(), rows, Q.tolist(), Bu.tolist())
        x_m, P_m = predict(x, P, F, Q, np.diag(Bu), np.ones(n))
        np.testing.assert_allclose(x_s, x_m, rtol=1e-12, atol=1e-12 * np.abs(x).max())
        np.testing.assert_allclose(P_s, P_m, rtol=1e-12, atol=1e-12 * np.abs(P_m).max())
        assert np.array_equal(np.array(P_s), np.array(P_s).T)
        assert predict_sparse(x.tolist(), P.tolist(), rows, Q.tolist())[0] == pytest.approx(
            (F @ x).tolist(), rel=1e-12, abs=1e-12 * np.abs(x).max())


@pytest.mark.parametrize("H", [((0, 1.0),), ((0, 1.0), (3, 1.0))])
def test_a_scalar_update_with_a_scaled_gain_is_the_matrix_one(H):
    """xu2016's weighted update (eq. 26, K = α P Hᵀ/S) in scalar arithmetic equals the matrix
    form's Joseph update to rounding (1e-9 relative, as for the unweighted updates above),
    P exactly symmetric and positive definite. 200 draws. (That α = 1 keeps the unweighted
    update's floats is the estimator checksums' to show: YangFusionKF and AltitudeEKF.)"""
    rng = np.random.default_rng(17)
    H_array = np.zeros((1, 4))
    for i, h in H:
        H_array[0, i] = h
    for _ in range(200):
        P, x = _random_covariance(rng, 4), 100 * rng.standard_normal(4)
        z, R, alpha = float(rng.normal(0.0, 100.0)), float(10 ** rng.uniform(-4, 3)), \
            float(rng.uniform(0.0, 1.0))
        innovation = z - sparse_dot(x.tolist(), H)
        x_s, P_s, S = update_scalar(x.tolist(), P.tolist(), H, innovation, R, alpha)
        matrix = update(x, P, z, H_array, R, gain_scale=alpha)
        scale = np.abs(P).max()
        np.testing.assert_allclose(x_s, matrix.x, rtol=1e-9, atol=1e-9 * (1 + np.abs(x).max()))
        np.testing.assert_allclose(P_s, matrix.P, rtol=1e-9, atol=1e-9 * scale)
        assert pytest.approx(matrix.S[0, 0], rel=1e-12) == S
        assert np.array_equal(np.array(P_s), np.array(P_s).T)
        assert np.all(np.linalg.eigvalsh(np.array(P_s)) > 0)


def _bits(values) -> bytes:
    """The IEEE 754 bytes of ``values`` (floats, nested sequences or arrays): equal only if
    every float is the same, signed zeros included."""
    return np.asarray(values, dtype=float).tobytes()


def _correlations(P: np.ndarray) -> np.ndarray:
    deviations = np.sqrt(np.diag(P))
    return P / np.outer(deviations, deviations)


def _random_covariance(rng, n: int) -> np.ndarray:
    A = rng.standard_normal((n, n)) * 10 ** rng.uniform(-2, 2)
    return A @ A.T + 1e-3 * np.eye(n)


def _as_tuples(P: np.ndarray) -> tuple:
    return tuple(map(tuple, P.tolist()))


def test_scalar_constant_acceleration_predict_is_the_matrix_one():
    """The written-out F P Fᵀ + Q equals the matrix form to rounding, and is exactly
    symmetric."""
    rng = np.random.default_rng(11)
    for _ in range(500):
        dt = 10 ** rng.uniform(-3, 0)
        F = np.array([[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        Q = np.array(white_jerk_noise(dt, 10 ** rng.uniform(-3, 1)))
        P, x = _random_covariance(rng, 3), 100 * rng.standard_normal(3)
        x_s, P_s = x.tolist(), P.tolist()
        predict_constant_acceleration_in_place(x_s, P_s, dt, _as_tuples(Q))
        x_m, P_m = predict(x, P, F, Q)
        np.testing.assert_allclose(x_s, x_m, rtol=1e-12, atol=1e-12 * np.abs(x).max())
        np.testing.assert_allclose(P_s, P_m, rtol=1e-12, atol=1e-12 * np.abs(P_m).max())
        assert np.array_equal(np.array(P_s), np.array(P_s).T)


@pytest.mark.parametrize("n, bias", [(3, 2), (7, 2), (5, 4)])
def test_the_height_and_speed_predict_is_the_matrix_one(n, bias):
    """h and v driven by a measured acceleration less a bias state, the other states
    constant: x⁻ = F x + B a, and P with its rows h and v mirrored into columns h and v (as
    the caller does after adding Q) is F P Fᵀ, to rounding; the rows other than h and v keep
    P's entries outside columns h and v, bit for bit, and P itself is not changed."""
    rng = np.random.default_rng(12)
    for _ in range(300):
        dt = 10 ** rng.uniform(-3, 0)
        a = 10 * rng.standard_normal()
        F = np.eye(n)
        F[0, 1], F[0, bias], F[1, bias] = dt, -dt * dt / 2, -dt
        B = np.zeros(n)
        B[0], B[1] = dt * dt / 2, dt
        P, x = _random_covariance(rng, n), 100 * rng.standard_normal(n)
        rows = P.tolist()
        x_s, P_s = predict_height_and_speed(x.tolist(), rows, dt, a, bias)
        assert rows == P.tolist()
        np.testing.assert_allclose(x_s, F @ x + B * a, rtol=1e-12,
                                   atol=1e-12 * np.abs(x).max())
        mirrored = np.array(P_s)
        mirrored[:, :2] = mirrored[:2, :].T
        expected = F @ P @ F.T
        np.testing.assert_allclose(mirrored, expected, rtol=1e-12,
                                   atol=1e-12 * np.abs(expected).max())
        assert np.array_equal(np.array(P_s)[2:, 2:], P[2:, 2:])


@pytest.mark.parametrize("constant", [1, 2])
def test_scalar_predict_with_constant_states_is_the_matrix_one(constant):
    """Bias states after (position, speed, acceleration): F = diag(F₃, I), Q block diagonal
    (:func:`constant_states_noise`); the written-out form equals the matrix one to rounding
    (1e-12, as above) and P⁻ is exactly symmetric."""
    rng = np.random.default_rng(12)
    n = 3 + constant
    for _ in range(200):
        dt = 10 ** rng.uniform(-3, 0)
        F = np.eye(n)
        F[:3, :3] = [[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]]
        walks = tuple(10 ** rng.uniform(-6, 0, constant))
        Q = np.array(constant_states_noise(white_jerk_noise(dt, 10 ** rng.uniform(-3, 1)),
                                           walks))
        assert np.array_equal(np.diag(Q)[3:], walks) and np.count_nonzero(Q[3:, :3]) == 0
        P, x = _random_covariance(rng, n), 100 * rng.standard_normal(n)
        x_s, P_s = x.tolist(), P.tolist()
        predict_constant_acceleration_in_place(x_s, P_s, dt, _as_tuples(Q))
        x_m, P_m = predict(x, P, F, Q)
        np.testing.assert_allclose(x_s, x_m, rtol=1e-12, atol=1e-12 * np.abs(x).max())
        np.testing.assert_allclose(P_s, P_m, rtol=1e-12, atol=1e-12 * np.abs(P_m).max())
        assert np.array_equal(np.array(P_s), np.array(P_s).T)


def test_a_shifted_state_is_one_component_moved_and_uncorrelated():
    P = _random_covariance(np.random.default_rng(13), 4)
    x, P_new = [1.0, 2.0, 3.0, 4.0], P.tolist()
    shift_state(x, P_new, 1, 5.0, 0.5)
    P_new = np.array(P_new)
    assert x == [1.0, 7.0, 3.0, 4.0]
    assert P_new[1, 1] == 0.5 and np.count_nonzero(P_new[1]) == np.count_nonzero(P_new[:, 1]) == 1
    others = [0, 2, 3]
    assert np.array_equal(P_new[np.ix_(others, others)], P[np.ix_(others, others)])


def test_a_rederived_state_has_the_covariance_of_its_linear_map():
    """x_2 := 1.5 x_0 - 0.2 x_1 + e, Var(e) = 0.3: the covariance is A P Aᵀ + 0.3 e₂e₂ᵀ, A the
    identity with row 2 replaced by H; the other states' block unchanged."""
    P = _random_covariance(np.random.default_rng(17), 4)
    H = ((0, 1.5), (1, -0.2))
    A = np.eye(4)
    A[2] = [1.5, -0.2, 0.0, 0.0]
    expected = A @ P @ A.T
    expected[2, 2] += 0.3
    P_new = [list(row) for row in P]
    rederive(P_new, 2, H, 0.3)
    assert np.allclose(P_new, expected, rtol=1e-12, atol=1e-12)
    assert np.array_equal(np.array(P_new), np.array(P_new).T)


def test_a_moved_datum_has_the_covariance_of_its_linear_map():
    """x_0 set onto a sample of variance 0.4, x_1 and x_3 moved with it by u = (1, 1, 0, -1):
    the covariance is A P Aᵀ + 0.4 u uᵀ with A = I - u e₀ᵀ (the old error of x_0 forgotten,
    x_1 - x_0 and x_3 + x_0 keeping theirs), x_2 untouched; exactly symmetric."""
    P = _random_covariance(np.random.default_rng(23), 4)
    u = np.array([1.0, 1.0, 0.0, -1.0])
    A = np.eye(4) - np.outer(u, np.eye(4)[0])
    expected = A @ P @ A.T + 0.4 * np.outer(u, u)
    P_new = [list(row) for row in P]
    move_datum(P_new, 0, list(u), 0.4)
    assert np.allclose(P_new, expected, rtol=1e-12, atol=1e-12)
    assert np.array_equal(np.array(P_new), np.array(P_new).T)
    assert P_new[0][0] == pytest.approx(0.4)
    d = np.array([-1.0, 1.0, 0.0, 0.0])                         # x_1 - x_0: kept
    assert d @ np.array(P_new) @ d == pytest.approx(d @ P @ d, rel=1e-12)
    assert P_new[2] == pytest.approx(list(P[2] - P[0][2] * u), rel=1e-12)


def test_an_inflation_along_a_direction_leaves_the_orthogonal_combinations():
    """P + 2.5 u uᵀ: the variance of x_0 grows by 2.5, that of x_0 - x_1
    (u = (1, 1, 0)) does not, and x_2 is untouched."""
    P = _random_covariance(np.random.default_rng(29), 3)
    u = [1.0, 1.0, 0.0]
    P_new = [list(row) for row in P]
    inflate_along(P_new, u, 2.5)
    assert np.allclose(P_new, P + 2.5 * np.outer(u, u), rtol=1e-12, atol=1e-12)
    d = np.array([1.0, -1.0, 0.0])
    assert d @ np.array(P_new) @ d == pytest.approx(d @ P @ d, rel=1e-12)
    assert P_new[2] == list(P[2])


def test_a_limited_variance_keeps_the_correlations_and_the_other_states():
    """A variance above the limit is brought to it with its correlation coefficients kept (P
    stays positive definite); the other states' block is untouched; one at or below the
    limit is left as it was, bit for bit."""
    P = _random_covariance(np.random.default_rng(31), 4)
    P[2] *= 30.0
    P[:, 2] *= 30.0                           # Var x_2 = 900 x what the draw gave
    rows = P.tolist()                         # the estimators' form (a list of row lists)
    limit_variance(rows, 2, 1.0)
    limited = np.array(rows)
    assert limited[2, 2] == pytest.approx(1.0, rel=1e-15)
    np.testing.assert_allclose(_correlations(limited), _correlations(P), rtol=1e-12)
    others = [0, 1, 3]
    assert np.array_equal(limited[np.ix_(others, others)], P[np.ix_(others, others)])
    assert np.all(np.linalg.eigvalsh(limited) > 0.0)
    kept = P.tolist()
    limit_variance(kept, 2, P[2, 2])
    assert np.array_equal(np.array(kept), P)


def test_scalar_component_updates_one_by_one_are_the_joint_matrix_update():
    """Independent measurements of state components applied one at a time in scalar
    arithmetic (H = a row of I) give the joint update (H = rows of I, R diagonal) to
    rounding; P stays exactly symmetric and positive definite."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(1, 6))
        P, x = _random_covariance(rng, n), 100 * rng.standard_normal(n)
        rows = sorted(rng.choice(n, int(rng.integers(1, n + 1)), replace=False).tolist())
        z = 100 * rng.standard_normal(len(rows))
        variances = 10 ** rng.uniform(-3, 3, len(rows))
        x_s, P_s = x.tolist(), P.tolist()
        for row, z_j, r_j in zip(rows, z, variances, strict=True):
            x_s, P_s, S = update_scalar(x_s, P_s, ((row, 1.0),), float(z_j) - x_s[row],
                                        float(r_j))
        joint = update(x, P, z, np.eye(n)[rows], np.diag(variances))
        scale = np.abs(P).max()
        np.testing.assert_allclose(x_s, joint.x, rtol=1e-9, atol=1e-9 * (1 + np.abs(x).max()))
        np.testing.assert_allclose(P_s, joint.P, rtol=1e-9, atol=1e-9 * scale)
        assert np.array_equal(np.array(P_s), np.array(P_s).T)
        assert np.all(np.linalg.eigvalsh(np.array(P_s)) > 0)


def test_scalar_component_update_returns_the_innovation_variance():
    x, P, S = update_scalar([1.0, 2.0], [[4.0, 1.0], [1.0, 3.0]], ((1, 1.0),), 3.0, 1.0)
    assert S == 4.0
    assert x == pytest.approx((1.0 + 0.25 * 3.0, 2.0 + 0.75 * 3.0))
    assert P[1][1] == pytest.approx(3.0 - 9.0 / 4.0)


def test_predict_propagates_mean_and_covariance():
    F = np.array([[1.0, 0.5], [0.0, 1.0]])
    Q = np.diag([0.1, 0.2])
    x, P = predict(np.array([1.0, 2.0]), np.eye(2), F, Q, np.array([[0.125], [0.5]]), 1.0)
    assert np.allclose(x, [2.125, 2.5])
    assert np.allclose(P, F @ F.T + Q)


def test_filter_is_consistent_nis_mean_equals_measurement_dimension():
    """A random walk observed in noise: the mean NIS of a consistent filter is 1 (χ²₁).
    With N = 20,000 steps (correlated little once converged) the mean has σ ≈ √(2/N) = 0.01,
    so ±0.05 is a 5-sigma bound."""
    rng = np.random.default_rng(42)
    q, r = 0.3, 2.0
    truth, x, P = 0.0, np.array([0.0]), np.array([[10.0]])
    nis = []
    for _ in range(20_000):
        truth += rng.normal(0, np.sqrt(q))
        x, P = predict(x, P, np.eye(1), np.array([[q]]))
        result = update(x, P, truth + rng.normal(0, np.sqrt(r)), np.eye(1), r)
        x, P = result.x, result.P
        nis.append(result.nis)
    assert np.mean(nis[100:]) == pytest.approx(1.0, abs=0.05)


def test_a_consider_update_moves_only_its_states_and_keeps_p_a_covariance():
    """update_scalar_of: with every state listed it is update_scalar; with some left out
    their estimates do not move, P stays symmetric and positive definite, and the listed
    states' variances shrink less than in the full update (the considered errors stay)."""
    rng = np.random.default_rng(7)
    A = rng.standard_normal((5, 5))
    P = (A @ A.T + 0.1 * np.eye(5)).tolist()
    x = rng.standard_normal(5).tolist()
    H = ((0, 1.0), (3, -1.0))
    full_x, full_P, _ = update_scalar(x, P, H, 0.7, 0.2)
    all_x, all_P = update_scalar_of(x, P, H, 0.7, 0.2, range(5))
    assert all_x == full_x and all_P == full_P             # the same floats: one step
    some_x, some_P = update_scalar_of(x, P, H, 0.7, 0.2, (0, 1, 3))
    assert some_x[2] == x[2] and some_x[4] == x[4]
    some_P = np.array(some_P)
    assert (some_P == some_P.T).all()
    assert np.linalg.eigvalsh(some_P).min() > 0.0
    assert some_P[0, 0] >= full_P[0][0] - 1e-12 and some_P[0, 0] < P[0][0]
