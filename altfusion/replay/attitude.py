"""Attitude helpers for PX4 logs: quaternion interpolation and the vertical of body vectors.

PX4's ``vehicle_attitude.q`` = [w, x, y, z] (Hamilton) rotates body-frame (FRD: forward,
right, down) vectors into the local NED frame: v_NED = R(q) v_FRD. Only the third row of R,
the body axes' components along "down", is needed here.
"""

import numpy as np

MAX_ATTITUDE_GAP = 0.5
"""Longest interval (s) between attitude samples that is interpolated across."""


def down_row(q: np.ndarray) -> np.ndarray:
    """The third row of R(q) for unit quaternions ``q`` (N, 4): (N, 3).

    R[2] = [2(xz - wy), 2(yz + wx), w² - x² - y² + z²]; its last element is cos(tilt)."""
    w, x, y, z = (q[:, i] for i in range(4))
    return np.column_stack((2 * (x * z - w * y), 2 * (y * z + w * x),
                            w * w - x * x - y * y + z * z))


def interpolate_quaternions(t_q: np.ndarray, q: np.ndarray, t: np.ndarray,
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Attitude at times ``t`` by normalised linear interpolation (nlerp) of ``q`` at ``t_q``.

    Returns (quaternions (N, 4), covered): ``covered`` is false where ``t`` lies outside the
    attitude samples or between two that are more than ``MAX_ATTITUDE_GAP`` apart; those rows
    are NaN. Consecutive quaternions are sign-aligned first (q and -q are the same attitude)."""
    q = np.array(q, dtype=float)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    flips = np.cumsum(np.concatenate(([0], np.sum(q[1:] * q[:-1], axis=1) < 0))) % 2
    q[flips == 1] *= -1.0
    result = np.full((len(t), 4), np.nan)
    if len(t_q) == 0:
        return result, np.zeros(len(t), dtype=bool)
    right = np.searchsorted(t_q, t, side="left")
    exact = (right < len(t_q)) & (t_q[np.minimum(right, len(t_q) - 1)] == t)
    inside = (right > 0) & (right < len(t_q))
    lo, hi = np.maximum(right - 1, 0), np.minimum(right, len(t_q) - 1)
    inside &= (t_q[hi] - t_q[lo]) <= MAX_ATTITUDE_GAP
    covered = inside | exact
    span = np.where(inside, t_q[hi] - t_q[lo], 1.0)
    weight = np.where(inside, (t - t_q[lo]) / span, 0.0)[:, None]
    blend = (1.0 - weight) * q[lo] + weight * q[hi]
    blend[exact] = q[hi[exact]]
    blend /= np.linalg.norm(blend, axis=1, keepdims=True)
    result[covered] = blend[covered]
    return result, covered
