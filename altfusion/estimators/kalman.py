"""The Kalman machinery every estimator shares: propagation and scalar updates.

The estimators step on the textbook equations (x⁻ = F x + B u, P⁻ = F P Fᵀ + Q; the scalar
update with the Joseph-form covariance (I - K H) P⁻ (I - K H)ᵀ + K R Kᵀ, which keeps P
symmetric positive semi-definite for any gain) in scalar arithmetic on Python floats:
vectors are sequences of floats, matrices sequences of rows, a measurement's H and a
transition's F sparse rows of (state index, coefficient) pairs. Never on numpy arrays, for
two reasons: a numpy operation on a 3x3 array costs ~0.5 µs whatever it computes, a float
operation ~0.03 µs; and BLAS sums and fuses its products in an order of its own that depends
on the processor (OpenBLAS picks its kernel at run time: with fused multiply-adds on Haswell
and later, without on Sandy Bridge), so that an estimator stepped on arrays gives other bits
on another machine. Python's float operations are IEEE 754's, rounded once each, on every
machine. The array forms are the tests' reference (``tests/kalman_reference.py``): every
form here equals them to rounding, some bit for bit (tests/test_kalman.py).

The module is compiled by mypyc (:mod:`altfusion.compiled`). The updates and the sparse
prediction copy what they read into lists of their annotated types (P's rows, H's terms,
x) and loop over indices: compiled, such a loop reads unboxed floats from a list directly,
where the same loop over a ``Sequence``, or a ``map`` over ``operator`` functions, calls
back into the interpreter for every element; interpreted, the copies cost a C-level
``list()`` each. A filter that owns its x and P (no one else holds them) updates them in
place instead (the ``_in_place`` forms: the same floats, no copy).
"""
# ruff: noqa: B905  (the scalar forms zip sequences of equal lengths by construction; a
# zip(..., strict=...) is a keyword call, which costs more than a short row's arithmetic)

import math
from collections.abc import Iterable, Sequence
from operator import add
from typing import Final

# ----------------------------------------------------------------- scalar arithmetic
Vector = Sequence[float]
Matrix = Sequence[Sequence[float]]

STATE_AND_COVARIANCE: Final = {"x": ("P",)}
"""``state_covariances`` of a filter whose state vector is ``x`` and its covariance ``P``: a
restored FMU state must keep the two one size (:mod:`altfusion.fmi.state`)."""


def diagonal(variances: Sequence[float]) -> list[list[float]]:
    """The diagonal matrix of ``variances``, as rows (a covariance of independent errors)."""
    n = len(variances)
    return [[variance if i == j else 0.0 for j in range(n)] for i, variance in enumerate(variances)]


# ------------------------------------------- the same floats as the arrays
# BLAS sums a matrix product's terms with fused multiply-adds in its own order, so float
# arithmetic rarely gives its floats. It does where each entry of the products of the array
# update and its Joseph form (tests/kalman_reference.py) is one product, or one product plus
# a term times 1 (the other terms times 0): a filter of one state, and a measurement of the
# first of two states (H = [1, 0]). There a fused multiply-add rounds once where float
# arithmetic rounds once too, and the order cannot matter: the floats are the same on any
# BLAS (tests/test_kalman.py). (update_scalar, below, is the same update in another order of
# operations: equal to rounding, not bit for bit.)


def update_one_state(x: float, P: float, z: float, R: float, gain_scale: float = 1.0,
                     ) -> tuple[float, float, float]:
    """The update of a one-state filter (H = [1]) on floats: x, P and the gain K, the
    floats the array update gives for 1x1 arrays.

        S = P⁻ + R,  K = gain_scale·P⁻/S,  x = x⁻ + K (z - x⁻),
        P = (1 - K) P⁻ (1 - K) + K R K                                 (Joseph form)
    """
    K = (gain_scale / (P + R)) * P
    I_KH = 1.0 - K
    return x + K * (z - x), I_KH * P * I_KH + K * R * K, K


def update_first_of_two(x: Vector, P: Matrix, z: float, R: float,
                        ) -> tuple[list[float], list[list[float]], list[float]]:
    """The update of a two-state filter by a measurement of its first state
    (H = [1, 0]) on floats: x, P and the gain K, the floats the array update gives for these
    arrays (section above); :func:`joseph_first_of_two` is its covariance."""
    (x0, x1), (p00, p01) = x, P[0]
    scale = 1.0 / (p00 + R)
    K = [scale * p00, scale * p01]
    y = z - x0
    return [x0 + K[0] * y, x1 + K[1] * y], joseph_first_of_two(P, K, R), K


def joseph_first_of_two(P: Matrix, K: Vector, R: float) -> list[list[float]]:
    """The Joseph form of a two-state filter for H = [1, 0] on floats, the floats it gives
    for these arrays: with I - K H = [[1 - K₀, 0], [-K₁, 1]] each entry of M = (I - K H) P⁻
    is one product or a product and P⁻'s own entry, and so is each of A = M (I - K H)ᵀ;
    then A + K R Kᵀ, symmetrized."""
    (p00, p01), (p10, p11) = P
    k0, k1 = K
    i00 = 1.0 - k0
    m00, m01 = i00 * p00, i00 * p01                      # M = (I - K H) P⁻
    m10, m11 = p10 - k1 * p00, p11 - k1 * p01
    kr0, kr1 = k0 * R, k1 * R                            # K R
    a00 = m00 * i00 + kr0 * k0                           # M (I - K H)ᵀ + K R Kᵀ
    a01 = m01 - m00 * k1 + kr0 * k1
    a10 = m10 * i00 + kr1 * k0
    a11 = m11 - m10 * k1 + kr1 * k1
    return [[0.5 * (a00 + a00), 0.5 * (a01 + a10)], [0.5 * (a10 + a01), 0.5 * (a11 + a11)]]


def white_jerk_noise(dt: float, jerk_psd: float) -> Matrix:
    """Q = q·∫ φφᵀ, φ = [t²/2, t, 1]: the process noise over dt of a white jerk of spectral
    density q acting on (position, speed, acceleration)."""
    return (
        (jerk_psd * dt**5 / 20.0, jerk_psd * dt**4 / 8.0, jerk_psd * dt**3 / 6.0),
        (jerk_psd * dt**4 / 8.0, jerk_psd * dt**3 / 3.0, jerk_psd * dt**2 / 2.0),
        (jerk_psd * dt**3 / 6.0, jerk_psd * dt**2 / 2.0, jerk_psd * dt),
    )


def predict_constant_acceleration_in_place(x: list[float], P: list[list[float]], dt: float,
                                           Q: tuple[tuple[float, ...], ...]) -> None:
    """In place: the time update for the constant-acceleration model of (position, speed,
    acceleration), F = [[1, dt, dt²/2], [0, 1, dt], [0, 0, 1]], written out: x⁻ = F x,
    P⁻ = F P Fᵀ + Q, into ``x`` and ``P`` (a filter's own: each entry of P is read before it
    is written).

    States after the first three (biases) are constant: F = diag(F₃, I), so their own block
    of P only gains their block of Q, and their covariances with the first three move by F₃.
    With such states Q is given over all of them (n x n, as :func:`constant_states_noise`
    gives it).

    P and Q must be symmetric; P⁻ is, exactly (its upper triangle is mirrored, and the
    constant states' block P + Q is the same float on either side of the diagonal)."""
    h, v, a = x[0], x[1], x[2]
    P0, P1, P2 = P[0], P[1], P[2]
    p00, p01, p02, p11, p12, p22 = P0[0], P0[1], P0[2], P1[1], P1[2], P2[2]
    Q0, Q1, Q2 = Q[0], Q[1], Q[2]
    half = dt * dt / 2.0
    r00 = p00 + dt * p01 + half * p02                   # first row of F P
    r01 = p01 + dt * p11 + half * p12
    r02 = p02 + dt * p12 + half * p22
    r11 = p11 + dt * p12                                # second row (its last two entries)
    r12 = p12 + dt * p22
    m00 = r00 + dt * r01 + half * r02 + Q0[0]          # (F P) Fᵀ + Q, upper triangle
    m01 = r01 + dt * r02 + Q0[1]
    m02 = r02 + Q0[2]
    m11 = r11 + dt * r12 + Q1[1]
    m12 = r12 + Q1[2]
    m22 = p22 + Q2[2]
    x[0] = h + dt * v + half * a
    x[1] = v + dt * a
    P0[0], P0[1], P0[2] = m00, m01, m02
    P1[0], P1[1], P1[2] = m01, m11, m12
    P2[0], P2[1], P2[2] = m02, m12, m22
    for k in range(3, len(x)):                # the constant states (plain loops: cheaper than
        P_k, Q_k = P[k], Q[k]                 # a comprehension's frame at these sizes)
        p0, p1, p2 = P0[k], P1[k], P2[k]
        d0 = p0 + dt * p1 + half * p2 + Q0[k]     # F₃ times the constant states' columns
        d1 = p1 + dt * p2 + Q1[k]
        d2 = p2 + Q2[k]
        P0[k] = P_k[0] = d0
        P1[k] = P_k[1] = d1
        P2[k] = P_k[2] = d2
        for j in range(3, len(x)):            # row k's own entries, read before written
            P_k[j] = P_k[j] + Q_k[j]


def predict_height_and_speed(x: Vector, P: Matrix, dt: float, acceleration: float,
                             bias: int) -> tuple[list[float], list[list[float]]]:
    """x⁻ = F x + B a and F P Fᵀ in the rows of h and v, without Q, for states 0 and 1 the
    height h and vertical speed v driven by a measured ``acceleration`` a less the bias
    state ``bias`` (b, the other states constant):

        h⁻ = h + dt v + dt²/2 (a - b),   v⁻ = v + dt (a - b)

    F differs from I in the rows of h and v only (∂h⁻/∂b = -dt²/2, ∂v⁻/∂b = -dt): rows h and
    v of F P, then their entries in columns h and v of (F P) Fᵀ. The other rows' entries in
    columns h and v are left as P had them: the caller adds Q to rows h and v and then
    mirrors those rows into columns h and v (P⁻ symmetric). Returns x⁻ and that P."""
    P_new = _rows(P)
    c = 0.5 * dt * dt                                 # ∂h⁻/∂(-b)
    e = dt                                            # ∂v⁻/∂(-b)
    a = acceleration - x[bias]
    x_new = [x[0] + dt * x[1] + 0.5 * dt * dt * a, x[1] + dt * a]
    for k in range(2, len(x)):
        x_new.append(x[k])
    P_h, P_v, P_b = P_new[0], P_new[1], P_new[bias]
    for j in range(len(P_h)):                         # rows h and v of F P, in place
        p1, p2 = P_v[j], P_b[j]
        P_h[j] = P_h[j] + dt * p1 - c * p2
        P_v[j] = p1 - e * p2
    for row in (P_h, P_v):                            # (F P) Fᵀ in columns h and v
        row[0], row[1] = row[0] + dt * row[1] - c * row[bias], row[1] - e * row[bias]
    return x_new, P_new


def add_height_speed_noise(P: list[list[float]], dt: float, q: float, walks: Sequence[float],
                           bias: int, bias_noise: float) -> None:
    """In place, on the P⁻ of :func:`predict_height_and_speed`: Q of one step added, then rows
    h and v mirrored into columns h and v (P⁻ exactly symmetric). Q: a white acceleration of
    spectral density ``q`` driving h and v (q dt³/3, q dt²/2, q dt), the random walk of each
    state i of spectral density ``walks[i]``, and ``bias_noise`` on the bias state ``bias``."""
    P_h, P_v = P[0], P[1]
    P_h[0] += q * dt**3 / 3.0
    P_v[0] += q * dt**2 / 2.0           # the symmetry loop copies it to P[0][1]
    P_v[1] += q * dt
    for i in range(len(walks)):
        P[i][i] += walks[i] * dt
    P[bias][bias] += bias_noise * dt
    for j in range(len(P)):
        row = P[j]
        row[0], row[1] = P_h[j], P_v[j]


def constant_states_noise(Q: Matrix, variances: Sequence[float]) -> tuple[tuple[float, ...], ...]:
    """``Q`` (n x n) extended by states that are constant up to independent random walks
    whose variances over the step are ``variances`` (a block diagonal Q)."""
    n, m = len(Q), len(variances)
    return (*(tuple(row) + (0.0,) * m for row in Q),
            *(tuple(0.0 for _ in range(n + i)) + (variance,) + (0.0,) * (m - i - 1)
              for i, variance in enumerate(variances)))


def shift_state(x, P, index: int, innovation: float, variance: float) -> None:
    """In place: x[index] moved by ``innovation``, its variance ``variance``, uncorrelated
    with the other states (a reset onto a measurement)."""
    x[index] += innovation
    decorrelate(P, index, variance)


def decorrelate(P, index: int, variance: float) -> None:
    """In place: state ``index`` of covariance P given variance ``variance`` and no
    correlation with the other states (:func:`shift_state`'s covariance part, for a second
    covariance of the same state)."""
    for j in range(len(P)):
        P[index][j] = P[j][index] = 0.0
    P[index][index] = variance


def rederive(P, index: int, H: Sequence[tuple[int, float]], variance: float) -> None:
    """In place: state ``index`` of covariance P re-derived as the sparse combination H x of
    the other states (H does not involve ``index``) plus an independent error of
    ``variance`` (a reset onto a measurement of a difference of states):
    Cov(x_index, x) = P Hᵀ and Var(x_index) = H P Hᵀ + variance."""
    cross = _times_row(P, list(H))
    for j, c in enumerate(cross):
        P[index][j] = P[j][index] = c
    P[index][index] = sparse_dot(cross, H) + variance


def move_datum(P, index: int, direction: Sequence[float], variance: float) -> None:
    """In place: state ``index`` set onto a new value of independent error of ``variance``,
    the states moved along with it by ``direction`` (u, u[index] = 1: x ← x + u·y keeps
    every difference the measurements see) keeping their errors relative to it, the error
    of its old value forgotten (a datum moved onto one sample):

        P ← A P Aᵀ + variance·u uᵀ,   A = I - u e_indexᵀ,
        P_ab ← P_ab - (u_a P_index,b + u_b P_index,a) + u_a u_b (P_index,index + variance)
    """
    row = P[index][:]
    base = row[index] + variance
    for a, u_a in enumerate(direction):
        P_a = P[a]
        for b, u_b in enumerate(direction):
            P_a[b] = P_a[b] - (u_a * row[b] + u_b * row[a]) + u_a * u_b * base


def limit_variance(P: list[list[float]], index: int, maximum: float) -> None:
    """In place: the variance of state ``index`` held at most ``maximum``, by scaling its row
    and column of P by √(maximum/P_ii) (P ← D P D, D = I but that factor at ``index``: P
    stays positive semi-definite and every correlation coefficient as it was). PX4 EKF2
    bounds its state variances the same way in ``constrainStateVariances`` (the
    accelerometer bias's at 1 (m/s²)², there by fusing a zero innovation)."""
    variance = P[index][index]
    if variance > maximum:
        scale = math.sqrt(maximum / variance)
        P_index = P[index]
        for j in range(len(P_index)):
            P_index[j] *= scale
        for P_a in P:
            P_a[index] *= scale


def inflate_along(P, direction: Sequence[float], variance: float) -> None:
    """In place: P ← P + variance·u uᵀ, an independent error of ``variance`` added along
    ``direction`` u (every combination orthogonal to u keeps its variance)."""
    for P_a, u_a in zip(P, direction, strict=True):
        if u_a:
            for b, u_b in enumerate(direction):
                P_a[b] += variance * u_a * u_b


def quadratic_form(P: Matrix, H: Sequence[tuple[int, float]]) -> float:
    """H P Hᵀ for a sparse row H ((state index, coefficient) pairs): the variance of the
    measured combination of states, the innovation variance without R."""
    total = 0.0                           # H (P Hᵀ), each sum from 0 in H's order, as
    for i, h in H:                        # sparse_dot of sparse_dot gives them
        P_i = P[i]
        inner = 0.0
        for j, c in H:
            inner += c * P_i[j]
        total += h * inner
    return total


def predict_sparse(x: Vector, P: list[list[float]], F: Sequence[Sequence[tuple[int, float]]],
                   Q: Matrix, Bu: Vector | None = None,
                   ) -> tuple[list[float], list[list[float]]]:
    """The time update for a transition matrix F given as sparse rows (each a tuple of
    (state index, coefficient) pairs), in scalar arithmetic: x⁻ = F x + B u, P⁻ = F P Fᵀ + Q
    (``Bu``: B u, or None for none).

    Row a of F P is P Fₐᵀ (P symmetric), each entry of F P Fᵀ a sparse sum of that row:
    the work grows with F's non-zero entries, not with n³. The upper triangle is computed and
    mirrored, so that P⁻ is exactly symmetric (P and Q must be symmetric)."""
    x_old, terms = list(x), [list(F_a) for F_a in F]
    FP = [_times_row(P, F_a) for F_a in terms]
    n = len(terms)
    P_new = _rows(Q)
    for a in range(n):                    # plain loops (a comprehension's frame costs more)
        FP_a, P_a = FP[a], P_new[a]
        for b in range(a, n):
            total = 0.0                   # _dot(FP_a, terms[b]), written out
            for i, f in terms[b]:
                total += f * FP_a[i]
            P_a[b] = P_new[b][a] = total + P_a[b]
    x_new: list[float] = []
    for F_a in terms:
        total = 0.0                       # _dot(x_old, F_a)
        for i, f in F_a:
            total += f * x_old[i]
        x_new.append(total)
    return (x_new if Bu is None else list(map(add, x_new, Bu))), P_new


def update_scalar(x: Vector, P: Matrix, H: Sequence[tuple[int, float]], innovation: float,
                  variance: float, gain_scale: float = 1.0,
                  ) -> tuple[list[float], list[list[float]], float]:
    """The update by one scalar measurement whose Jacobian row H is sparse (given as
    (state index, coefficient) pairs), in scalar arithmetic; ``innovation`` y = z - h(x⁻) is
    computed by the caller (an extended Kalman filter's nonlinear h); returns x, P and the
    innovation variance S.

        r = P⁻ Hᵀ,  S = H r + R,  K = α r / S,  x = x⁻ + K y
        P = P⁻ - (K rᵀ + r Kᵀ) + S K Kᵀ            (the Joseph form, expanded)

    The Joseph form (I - K H) P⁻ (I - K H)ᵀ + K R Kᵀ expands to the second line for any K,
    so it stays exact for a gain scaled by a weight α = ``gain_scale`` (xu2016 eq. 26). P
    must be symmetric (its upper triangle is read) and stays exactly so (each entry's sum
    is the same float for (a, b) and (b, a))."""
    x_new, P_new = list(x), _rows(P)
    S = update_scalar_in_place(x_new, P_new, H, innovation, variance, gain_scale)
    return x_new, P_new, S


def update_scalar_in_place(x: list[float], P: list[list[float]],
                           H: Sequence[tuple[int, float]], innovation: float, variance: float,
                           gain_scale: float = 1.0) -> float:
    """:func:`update_scalar` written into ``x`` and ``P`` themselves, for a filter whose x
    and P no one else holds (no copy made: at five states the copy of P costs a fifth of
    the update); returns S. The same floats as :func:`update_scalar` (the Joseph form's
    entry (a, b), b ≥ a, is read before anything is written to it)."""
    terms = list(H)
    row = _times_row(P, terms)
    S = _dot(row, terms) + variance
    K: list[float] = []
    if gain_scale == 1.0:
        for r in row:
            K.append(r / S)
    else:
        scale = gain_scale / S
        for r in row:
            K.append(r * scale)
    _gain_step(x, P, row, K, S, innovation)
    return S


def update_scalar_of(x: Vector, P: Matrix, H: Sequence[tuple[int, float]], innovation: float,
                     variance: float, states: Sequence[int],
                     ) -> tuple[list[float], list[list[float]]]:
    """:func:`update_scalar` that moves only ``states`` (a Schmidt-Kalman, or "consider",
    update: the gain of every other state is 0, their errors considered in S but not
    estimated from the measurement); returns x and P.

        K_i = r_i / S for i in states, 0 otherwise;  P = P⁻ - (K rᵀ + r Kᵀ) + S K Kᵀ

    the Joseph form, right for any gain. P stays exactly symmetric."""
    P_new, terms = _rows(P), list(H)
    row = _times_row(P_new, terms)
    S = _dot(row, terms) + variance
    K = [0.0] * len(row)
    for i in states:
        K[i] = row[i] / S
    return _gain_step(list(x), P_new, row, K, S, innovation)


def _rows(P: Matrix) -> list[list[float]]:
    """A copy of P as a list of lists (the update writes into it); a comprehension, which
    compiled is a native loop, where ``list(map(list, P))`` calls ``map`` and each ``list``
    through the interpreter."""
    return [list(row) for row in P]


def _gain_step(x: list[float], P: list[list[float]], row: list[float], K: list[float],
               S: float, innovation: float) -> tuple[list[float], list[list[float]]]:
    """In place, on x and P (the caller's copies, or a filter's own): x + K y and the Joseph
    form P - (K rᵀ + r Kᵀ) + S K Kᵀ of a scalar update of gain K (r = P Hᵀ, S its innovation
    variance) for a symmetric P: the upper triangle computed and mirrored, each entry's sum
    being the same float for (a, b) and (b, a) (entry (a, b), b ≥ a, is read before anything
    is written to it). Plain loops over indices: compiled, they run on unboxed floats; interpreted,
    a comprehension's frame (Python 3.11) would cost more than the arithmetic it saves."""
    n = len(K)
    for a in range(n):
        x[a] = x[a] + K[a] * innovation
    for a in range(n):
        P_a, r_a, k_a = P[a], row[a], K[a]
        for b in range(a, n):
            k_b = K[b]
            P_a[b] = P[b][a] = P_a[b] - (k_a * row[b] + r_a * k_b) + k_a * k_b * S
    return x, P


def _times_row(P: list[list[float]], H: list[tuple[int, float]]) -> list[float]:
    """P Hᵀ for a sparse row H: each entry the sum of H's terms from 0 in H's order (as
    :func:`sparse_dot`), written out for rows of one and two terms."""
    row: list[float] = []
    if len(H) == 1:
        i, h = H[0]
        for P_a in P:
            row.append(0.0 + h * P_a[i])
    elif len(H) == 2:
        i, h = H[0]
        j, g = H[1]
        for P_a in P:
            row.append(0.0 + h * P_a[i] + g * P_a[j])
    else:
        for P_a in P:
            row.append(_dot(P_a, H))
    return row


def _dot(v: list[float], H: list[tuple[int, float]]) -> float:
    """:func:`sparse_dot` of typed lists, for the updates' own rows (compiled, its list
    reads take AltitudeEKF's step 2.7 % below :func:`sparse_dot`'s ``Sequence`` reads, which
    the estimators' tuples of terms need)."""
    total = 0.0
    for i, h in H:
        total += h * v[i]
    return total


def running_sum(values: Iterable[float]) -> float:
    """The values added one after the other from 0.0: the float Python 3.11's ``sum`` gives,
    on every Python (from 3.12 on, ``sum`` compensates its floats' rounding errors and gives
    other bits). For a few terms; a long window takes ``math.fsum`` (correctly rounded)."""
    total = 0.0
    for value in values:
        total += value
    return total


def sparse_dot(v: Vector, H: Sequence[tuple[int, float]]) -> float:
    """H v for a sparse row H ((state index, coefficient) pairs), summed from 0 in H's order
    (:func:`running_sum`'s order; :func:`_times_row` sums the same way)."""
    total = 0.0
    for i, h in H:
        total += h * v[i]
    return total
