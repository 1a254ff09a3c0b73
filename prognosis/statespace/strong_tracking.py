"""Strong tracking for the Kalman filters (Du et al. (n.d.), section 3; Zhou et al. 1990).

Pass ``fading=StrongTracking()`` to any of them.  At the measurement update
the predicted covariance's propagated part is inflated by a suboptimal fading
factor ``lambda_k >= 1`` (eq. 7, 36)::

    P_{k|k-1} = lambda_k (P*_{k|k-1} - Q_{k-1}) + Q_{k-1},
    lambda_k = max(1, tr N_k / tr M_k),
    N_k = V_k - H Q H^T - beta R_k,          M_k = H (P* - Q) H^T,
    V_k = eps_1 eps_1^T (k = 1),  (rho V_{k-1} + eps_k eps_k^T) / (1 + rho),

so that the innovation sequence stays orthogonal when the model is wrong
(a drifting parameter whose law is unknown).  The derivative-free form
(eqs. 17-20, 27-35) replaces ``H`` by ``P_xz^T P*^{-1}`` (eq. 17) from the
sigma or cubature points drawn from ``P*``; the EKF uses its Jacobian.

Note on eq. (35): substituting eq. (20) it writes
``M_k = Z Z^T - V_k + N_k``, which drops the ``+ R_k`` that ``P_zz`` carries in
eq. (32); eq. (20) itself gives ``M_k = Z Z^T - H Q H^T = H (P* - Q) H^T``,
which is what is computed here (with the printed form ``M`` can turn negative
when the measurement noise dominates).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import _linalg as linalg
from ..errors import PrognosisError

__all__ = ["StrongTracking"]


@dataclass
class StrongTracking:
    """Suboptimal fading factor of the strong tracking filter (Du et al. (n.d.), eqs. 7-10, 17-20).

    Parameters
    ----------
    forgetting : float
        ``rho`` of eq. (10), in (0, 1]: weight of the past in ``V_k``.  The paper
        does not give it; 0.95 is the value of Zhou et al.
    softening : float
        ``beta >= 1`` multiplying ``R_k`` in ``N_k`` (1 in the paper); a larger value
        makes the filter fade less on measurement noise.
    max_factor : float
        Upper bound on ``lambda_k`` (no bound by default).

    Examples
    --------
    A sudden change of the decay rate ``a`` from 0.1 to 0.2: a filter with a small
    process noise on ``a`` follows slowly, with strong tracking it follows at once.

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import ExtendedKalmanFilter, discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> def run(fading):
    ...     ekf = ExtendedKalmanFilter(model, [1.0, 0.1], np.diag([1e-6, 1e-6]), np.diag([1e-8, 1e-8]), [[1e-6]],
    ...                                fading=fading)
    ...     truth, factors = 1.0, []
    ...     for k in range(40):
    ...         truth *= 0.9 if k < 20 else 0.8
    ...         factors.append(ekf.step([truth]).fading)
    ...     return round(float(ekf.mean[1]), 2), max(factors) > 1.0
    >>> run(None), run(StrongTracking())
    ((0.12, False), (0.2, True))

    The factor itself, for an innovation of 3 whose predicted variance is 2 (``H = 1``, ``Q = 0``, ``R = 1``):
    ``lambda = (9 - 1) / (2 - 1)``.

    >>> StrongTracking().factor(np.array([3.0]), np.eye(1), np.eye(1), np.array([[2.0]]), np.zeros((1, 1)), np.eye(1))
    8.0
    """

    forgetting: float = 0.95
    softening: float = 1.0
    max_factor: float = np.inf
    _v: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        if not 0.0 < self.forgetting <= 1.0:
            raise PrognosisError(f"forgetting (rho) must be in (0, 1], got {self.forgetting}")
        if self.softening < 1.0:
            raise PrognosisError(f"softening (beta) must be >= 1, got {self.softening}")
        if not self.max_factor >= 1.0:
            raise PrognosisError(f"max_factor must be >= 1, got {self.max_factor}")

    def reset(self) -> None:
        """Forget ``V_k`` (eq. 10); the filters call this at their start and in ``reinitialize``."""
        self._v = None

    def factor(self, residual: np.ndarray, predicted: np.ndarray, cross: np.ndarray, innovation: np.ndarray,
               process: np.ndarray, noise: np.ndarray) -> float:
        """``lambda_k`` from the innovation ``eps`` (m,), ``P*`` (n, n), ``P_xz`` (n, m), ``P_zz`` (m, m), Q, R."""
        outer = np.outer(residual, residual)
        rho = self.forgetting
        self._v = outer if self._v is None or self._v.shape != outer.shape else (rho * self._v + outer) / (1 + rho)
        h = linalg.solve(predicted, cross).T  # eq. 17: H = P_xz^T P*^{-1}
        hqh = h @ process @ h.T
        n = self._v - hqh - self.softening * noise
        m = innovation - noise - hqh  # eq. 20: M = H (P* - Q) H^T
        trace_m = float(np.trace(m))
        if not trace_m > 0.0:
            return 1.0
        return float(np.clip(np.trace(n) / trace_m, 1.0, self.max_factor))
