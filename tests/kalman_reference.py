"""The textbook Kalman filter on numpy arrays (filterpy style): the reference the
estimators' scalar forms (``altfusion.estimators.kalman``) are tested against.

The estimators never step on these: numpy's BLAS sums and fuses a product's terms in an
order that depends on the processor, and a call on a 3x3 array costs ~0.5 µs whatever it
computes. All arrays are float; a scalar measurement has H of shape (1, n) and R (1, 1).
"""

from functools import cache
from typing import NamedTuple

import numpy as np


def symmetrize(P: np.ndarray) -> np.ndarray:
    """(P + Pᵀ)/2: removes the asymmetry rounding errors accumulate."""
    return 0.5 * (P + P.T)


def predict(x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray,
            B: np.ndarray | None = None, u: np.ndarray | float | None = None,
            ) -> tuple[np.ndarray, np.ndarray]:
    """Time update: x⁻ = F x + B u,  P⁻ = F P Fᵀ + Q."""
    x = F.dot(x)
    if B is not None and u is not None:
        x = x + B.dot(np.atleast_1d(u))
    return x, symmetrize(F.dot(P).dot(F.T) + Q)


class Update(NamedTuple):
    """Result of a measurement update (a named tuple: built once per update, cheaply)."""

    x: np.ndarray
    P: np.ndarray
    innovation: np.ndarray
    """y = z - H x⁻"""
    S: np.ndarray
    """Innovation covariance H P⁻ Hᵀ + R."""
    K: np.ndarray
    """Gain P⁻ Hᵀ S⁻¹."""

    @property
    def nis(self) -> float:
        """Normalised innovation squared yᵀ S⁻¹ y (χ² with dim(z) degrees of freedom)."""
        return float(self.innovation @ np.linalg.solve(self.S, self.innovation))


def update(x: np.ndarray, P: np.ndarray, z: np.ndarray | float, H: np.ndarray,
           R: np.ndarray | float, gain_scale: float = 1.0) -> Update:
    """Measurement update with the Joseph form.

        y = z - H x⁻
        S = H P⁻ Hᵀ + R
        K = gain_scale · P⁻ Hᵀ S⁻¹
        x = x⁻ + K y
        P = (I - K H) P⁻ (I - K H)ᵀ + K R Kᵀ

    ``gain_scale`` (a weight α ≤ 1 on the gain, xu2016 eq. 26) keeps the Joseph form exact
    for the gain actually used.
    """
    z = np.asarray(z, dtype=float).reshape(-1)
    R = np.asarray(R, dtype=float).reshape(len(z), len(z))
    y = z - H.dot(x)
    HP = H.dot(P)
    if len(z) == 1:                   # a scalar S: no symmetrization, no LAPACK (a hot path)
        S = HP.dot(H.T) + R
        K = (gain_scale / S[0, 0]) * HP.T
    else:
        S = symmetrize(HP.dot(H.T) + R)
        K = gain_scale * np.linalg.solve(S, HP).T
    return Update(x + K.dot(y), joseph(P, K, H, R), y, S, K)


def joseph(P: np.ndarray, K: np.ndarray, H: np.ndarray, R: np.ndarray | float) -> np.ndarray:
    """P = (I - K H) P⁻ (I - K H)ᵀ + K R Kᵀ: the covariance after an update with the gain K,
    whatever gain it is, for a measurement noise of covariance R. With the filter's own K
    and R, :func:`update`'s P; with another R (the measurement's true noise where the
    filter's R is not), the covariance of the filter's actual error."""
    R = np.asarray(R, dtype=float).reshape(K.shape[1], K.shape[1])
    I_KH = _identity(len(P)) - K.dot(H)
    return symmetrize(I_KH.dot(P).dot(I_KH.T) + K.dot(R).dot(K.T))


@cache
def _identity(n: int) -> np.ndarray:
    """I of size n, made once (read only: every use makes a new array from it)."""
    identity = np.eye(n)
    identity.flags.writeable = False
    return identity
