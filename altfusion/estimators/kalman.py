"""The Kalman machinery every estimator shares: propagation, update, gating.

Written next to the equations (filterpy style) with the Joseph-form covariance update, which
keeps P symmetric positive semi-definite for any gain, followed by explicit symmetrisation.
All arrays are float numpy arrays; a scalar measurement has H of shape (1, n) and R (1, 1).
Products are ``ndarray.dot``: the same BLAS call as ``@`` (the same floats), without the
generalized-ufunc dispatch that dominates the cost of a product of 3x3 matrices.
"""

from collections.abc import Sequence
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

    ``gain_scale`` (a weight α ≤ 1 on the gain, seed 004 eq. 26) keeps the Joseph form exact
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
    I_KH = _identity(len(x)) - K.dot(H)
    P_new = symmetrize(I_KH.dot(P).dot(I_KH.T) + K.dot(R).dot(K.T))
    return Update(x + K.dot(y), P_new, y, S, K)


def update_components(x: np.ndarray, P: np.ndarray, indices: tuple[int, ...],
                      z: Sequence[float], variances: Sequence[float]) -> Update:
    """:func:`update` for independent direct measurements of state components: z_j measures
    x[indices[j]] with variance variances[j], i.e. H = rows ``indices`` of I, R = diag.

    The same arithmetic as ``update(x, P, z, I[indices], diag(variances))``, bit for bit,
    without the products by H and R: a product by a row of I only selects (every other term
    of its sums is exactly ±0), so H x, H P Hᵀ, K H and K R are indexing and scaling; the
    products with real sums (P of the Joseph form, K y, (K R) Kᵀ) stay matrix products.
    """
    I_KH = _identity(len(x)).copy()
    if len(indices) == 1:            # a scalar S: no symmetrization, no LAPACK (a hot path)
        row = indices[0]
        y = np.array([z[0] - x.item(row)])
        s = P.item(row, row) + variances[0]
        S = np.array([[s]])
        K = (1.0 / s) * P[row:row + 1].T
        I_KH[:, row] -= K[:, 0]
        KR = K * variances[0]
    else:
        rows = list(indices)
        HP = P[rows]
        y = np.array(z) - x[rows]
        S = symmetrize(HP[:, rows] + np.diag(variances))
        K = np.linalg.solve(S, HP).T
        I_KH[:, rows] -= K
        KR = np.multiply(K, variances, order="C")
    P_new = symmetrize(I_KH.dot(P).dot(I_KH.T) + KR.dot(K.T))
    return Update(x + K.dot(y), P_new, y, S, K)


@cache
def _identity(n: int) -> np.ndarray:
    """I of size n, made once (read only: every use makes a new array from it)."""
    identity = np.eye(n)
    identity.flags.writeable = False
    return identity


def scalar_gate(innovation: float, variance: float, sigmas: float) -> bool:
    """True if |y| ≤ sigmas·√S (the measurement passes a gate of ``sigmas`` standard deviations).

    ``sigmas <= 0`` disables the gate."""
    return sigmas <= 0 or innovation * innovation <= sigmas * sigmas * variance
