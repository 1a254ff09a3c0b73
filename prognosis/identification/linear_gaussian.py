"""The linear Gaussian state-space model identified by EM (Gasperin et al. (2011), eqs. 2-3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from bondgraph.errors import PHMWarning

from .. import _linalg as linalg
from .data import check_covariance, check_data, check_inputs, check_matrix
from ..errors import PrognosisError

__all__ = ["IdentificationWarning", "LinearGaussianModel", "check_model_data"]


class IdentificationWarning(PHMWarning, RuntimeWarning):
    """An M-step had to floor the eigenvalues of a noise covariance (the model is close to degenerate)."""



@dataclass(frozen=True, eq=False, repr=False)
class LinearGaussianModel:
    """``x_{t+1} = A x_t + B u_t + w_t``, ``y_t = C x_t + D u_t + v_t`` (Gasperin et al. (2011), eqs. 2-3).

    ``[w_t; v_t] ~ N(0, [[Q, S], [S^T, R]])`` independently over ``t`` and of ``x_1 ~ N(mu1, P1)``.

    Parameters
    ----------
    A : array (n, n)
    B : array (n, r), or None for a model without inputs (``r = 0``)
    C : array (m, n)
    D : array (m, r), or None (zeros; ``r`` is taken from ``B``)
    Q : array (n, n), symmetric positive semi-definite
    R : array (m, m), symmetric positive definite
    S : array (n, m), or None for ``S = 0``.  ``[[Q, S], [S^T, R]]`` must be positive semi-definite.
    mu1 : array (n,), or None for zeros
    P1 : array (n, n), symmetric positive semi-definite, or None for the identity

    Arrays are stored as read-only float arrays; a bad shape, a non-finite entry, an asymmetric or
    indefinite covariance raises a ``PrognosisError`` that names the matrix.

    Example
    -------
    >>> m = LinearGaussianModel(A=[[0.5, 0.1], [0.0, 1.02]], B=None, C=[[1.0, 1.0]], D=None,
    ...                         Q=0.01 * np.eye(2), R=[[0.1]])
    >>> (m.n_states, m.n_inputs, m.n_outputs), round(m.spectral_radius, 2), m.is_stable
    ((2, 0, 1), 1.02, False)
    >>> x, y = m.simulate(steps=5, rng=1)
    >>> x.shape, y.shape
    ((5, 2), (5, 1))
    """

    A: np.ndarray
    B: np.ndarray | None
    C: np.ndarray
    D: np.ndarray | None
    Q: np.ndarray
    R: np.ndarray
    S: np.ndarray | None = None
    mu1: np.ndarray | None = None
    P1: np.ndarray | None = None

    def __post_init__(self):
        a = check_matrix("A", self.A)
        n = a.shape[0]
        if a.shape != (n, n):
            raise PrognosisError(f"A must be square (n, n), got shape {a.shape}")
        c = check_matrix("C", self.C)
        if c.shape[1] != n:
            raise PrognosisError(f"C must have shape (m, {n}) for {n} states, got {c.shape}")
        m = c.shape[0]
        if self.B is None:
            r = 0 if self.D is None else check_matrix("D", self.D).shape[1]
            b = np.zeros((n, r))
        else:
            b = check_matrix("B", self.B, rows=n)
            r = b.shape[1]
        d = np.zeros((m, r)) if self.D is None else check_matrix("D", self.D, rows=m)
        if b.shape != (n, r):
            raise PrognosisError(f"B must have shape ({n}, {r}) to match D, got {b.shape}")
        if d.shape != (m, r):
            raise PrognosisError(f"D must have shape ({m}, {r}) for {m} outputs and {r} inputs, got {d.shape}")
        q = check_covariance("Q", self.Q, n)
        rr = check_covariance("R", self.R, m)
        s = np.zeros((n, m)) if self.S is None else check_matrix("S", self.S)
        if s.shape != (n, m):
            raise PrognosisError(f"S must have shape ({n}, {m}), got {s.shape}")
        mu1 = np.zeros(n) if self.mu1 is None else np.asarray(self.mu1, dtype=float).reshape(-1)
        if mu1.shape != (n,) or not np.all(np.isfinite(mu1)):
            raise PrognosisError(f"mu1 must be a finite vector of {n} entries, got shape {np.shape(self.mu1)}")
        p1 = np.eye(n) if self.P1 is None else check_covariance("P1", self.P1, n)
        if np.linalg.eigvalsh(rr)[0] <= 0.0:
            raise PrognosisError("R must be positive definite (the innovations need it)")
        if np.any(s):
            joint = np.block([[q, s], [s.T, rr]])
            if np.linalg.eigvalsh(joint)[0] < -1e-10 * max(1.0, np.abs(joint).max()):
                raise PrognosisError("[[Q, S], [S^T, R]] must be positive semi-definite: S is too large for Q and R")
        for name, value in (("A", a), ("B", b), ("C", c), ("D", d), ("Q", q), ("R", rr), ("S", s),
                            ("mu1", mu1), ("P1", p1)):
            value = np.array(value, dtype=float)
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def n_states(self) -> int:
        """``n``, the dimension of ``x``."""
        return self.A.shape[0]

    @property
    def n_inputs(self) -> int:
        """``r``, the dimension of ``u`` (0 without inputs)."""
        return self.B.shape[1]

    @property
    def n_outputs(self) -> int:
        """``m``, the dimension of ``y``."""
        return self.C.shape[0]

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of ``A``, by decreasing modulus (the modes of the fault dynamics)."""
        values = np.linalg.eigvals(self.A)
        return values[np.argsort(-np.abs(values), kind="stable")]

    @property
    def spectral_radius(self) -> float:
        """``rho(A) = max |lambda_i(A)|``: above 1 the state (the fault) grows without input."""
        return float(np.max(np.abs(np.linalg.eigvals(self.A)))) if self.n_states else 0.0

    @property
    def is_stable(self) -> bool:
        """``rho(A) < 1``."""
        return self.spectral_radius < 1.0

    def simulate(self, u: ArrayLike | None = None, rng=None, *, steps: int | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Draw states ``x`` (T, n) and outputs ``y`` (T, m) for the inputs ``u`` (T, r).

        ``x_1 ~ N(mu1, P1)``, then eqs. (2)-(3) with ``[w_t; v_t] ~ N(0, [[Q, S], [S^T, R]])``.  Without
        inputs pass ``steps`` instead of ``u``.  ``rng`` is a ``numpy.random.Generator``, a seed or None.

        Example
        -------
        >>> m = LinearGaussianModel(A=[[0.8]], B=[[1.0]], C=[[2.0]], D=[[0.0]], Q=[[0.0]], R=[[1e-12]],
        ...                         mu1=[0.0], P1=[[0.0]])
        >>> x, y = m.simulate(np.ones((3, 1)), rng=0)
        >>> np.round(x[:, 0], 6).tolist()
        [0.0, 1.0, 1.8]
        """
        if u is None:
            if steps is None:
                raise PrognosisError("simulate needs the inputs u (T, r) or, for a model without inputs, steps")
            u = np.zeros((int(steps), 0))
        u = check_inputs(u, None, self.n_inputs)
        if steps is not None and steps != u.shape[0]:
            raise PrognosisError(f"steps ({steps}) disagrees with the {u.shape[0]} rows of u")
        rng = np.random.default_rng(rng)
        steps, n = u.shape[0], self.n_states
        noise = rng.standard_normal((steps, n + self.n_outputs)) @ linalg.eigen_root(self.noise_covariance).T
        x = np.empty((steps, n))
        if steps:
            x[0] = self.mu1 + linalg.eigen_root(self.P1) @ rng.standard_normal(n)
        drive = u @ self.B.T + noise[:, :n]
        for t in range(steps - 1):
            x[t + 1] = self.A @ x[t] + drive[t]
        y = x @ self.C.T + u @ self.D.T + noise[:, n:]
        return x, y

    def transformed(self, T: ArrayLike) -> "LinearGaussianModel":
        """The same model in the state basis ``x' = T x`` (``T`` invertible): same outputs, same likelihood.

        ``A' = T A T^-1``, ``B' = T B``, ``C' = C T^-1``, ``Q' = T Q T^T``, ``S' = T S``, ``mu1' = T mu1``,
        ``P1' = T P1 T^T``; ``D``, ``R`` and the eigenvalues are unchanged.  EM cannot tell these models
        apart, so the basis it lands in is arbitrary; :class:`OnlineEM` uses this to keep it well scaled.

        Example
        -------
        >>> m = LinearGaussianModel(A=[[0.5, 1.0], [0.0, 0.9]], B=None, C=[[1.0, 0.0]], D=None,
        ...                         Q=np.eye(2), R=[[1.0]])
        >>> m2 = m.transformed(np.diag([2.0, 0.5]))
        >>> m2.A.tolist(), m2.C.tolist(), bool(np.allclose(m2.eigenvalues, m.eigenvalues))
        ([[0.5, 4.0], [0.0, 0.9]], [[0.5, 0.0]], True)
        """
        t = check_matrix("T", T)
        if t.shape != (self.n_states, self.n_states):
            raise PrognosisError(f"T must have shape ({self.n_states}, {self.n_states}), got {t.shape}")
        t_inv = np.linalg.inv(t)  # raises LinAlgError if T is singular
        return LinearGaussianModel(A=t @ self.A @ t_inv, B=t @ self.B, C=self.C @ t_inv, D=self.D,
                                   Q=linalg.symmetric(t @ self.Q @ t.T), R=self.R,
                                   S=t @ self.S if np.any(self.S) else None,
                                   mu1=t @ self.mu1, P1=linalg.symmetric(t @ self.P1 @ t.T))

    @property
    def noise_covariance(self) -> np.ndarray:
        """``[[Q, S], [S^T, R]]``, the covariance of ``[w_t; v_t]``."""
        return np.block([[self.Q, self.S], [self.S.T, self.R]])

    def __repr__(self) -> str:
        def show(a):
            return np.array2string(np.asarray(a), precision=4, suppress_small=True, separator=", ").replace("\n", "")

        eig = ", ".join(f"{v:.4g}" for v in self.eigenvalues)
        body = ", ".join(f"{name}={show(getattr(self, name))}" for name in ("A", "B", "C", "D", "Q", "R"))
        extra = f", S={show(self.S)}" if np.any(self.S) else ""
        return (f"LinearGaussianModel(n_states={self.n_states}, n_inputs={self.n_inputs}, "
                f"n_outputs={self.n_outputs}, spectral_radius={self.spectral_radius:.4g}, eigenvalues=[{eig}], "
                f"{body}{extra}, mu1={show(self.mu1)}, P1={show(self.P1)})")


def check_model_data(model: LinearGaussianModel, y, u) -> tuple[np.ndarray, np.ndarray]:
    """``y`` and ``u`` checked against the model's numbers of outputs and inputs (a ``PrognosisError`` naming them)."""
    if u is None and model.n_inputs:
        raise PrognosisError(f"u is required: the model has {model.n_inputs} inputs")
    y, u = check_data(y, u)
    if y.shape[1] != model.n_outputs:
        raise PrognosisError(f"y has {y.shape[1]} columns but the model has {model.n_outputs} outputs")
    if u.shape[1] != model.n_inputs:
        raise PrognosisError(f"u has {u.shape[1]} columns but the model has {model.n_inputs} inputs")
    return y, u
