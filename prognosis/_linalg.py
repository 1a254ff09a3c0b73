"""Small dense linear algebra shared by every Gaussian filter, smoother and sampler of prognosis.

One place for the square roots, solves and checks of covariance matrices, so that the
Kalman family (:mod:`prognosis.statespace`) and the identification by EM
(:mod:`prognosis.identification`) agree on their contracts.  Two solves with different
contracts are kept on purpose:

* :func:`solve` (LU, least squares when singular): the few-by-few innovation systems of a
  filter step, where the call overhead of a factorization dominates;
* :func:`solve_psd` and :func:`solve_psd_stack` (Cholesky, minimum-norm least squares or
  pseudo-inverse when numerically singular): the smoother and EM, where a covariance may
  be exactly singular (a state without process noise) and the minimum-norm answer matters.

Examples
--------
>>> a = np.array([[4.0, 2.0], [2.0, 3.0]])
>>> root = psd_sqrt(a)
>>> bool(np.allclose(root @ root.T, a)), bool(np.allclose(a @ solve_psd(a, np.eye(2)), np.eye(2)))
(True, True)
"""

from __future__ import annotations

import numpy as np

from .errors import PrognosisError

__all__ = [
    "block", "covariance_matrix", "eigen_root", "psd_sqrt", "solve", "solve_psd", "solve_psd_stack",
    "state_vector", "symmetric", "tria",
]


def symmetric(a: np.ndarray) -> np.ndarray:
    """The symmetric part ``(a + a^T) / 2`` (round-off makes products of covariances drift apart)."""
    return 0.5 * (a + a.T)


def tria(matrix: np.ndarray) -> np.ndarray:
    """Lower-triangular ``S`` with ``S S^T = C C^T`` from the QR decomposition of ``C^T``.

    The triangularization of the square-root cubature filter (Arasaratnam and Haykin 2009;
    Du et al. (n.d.), eq. 25).  The diagonal is made non-negative (column signs are free).

    >>> c = np.array([[1.0, 2.0, 0.5], [0.0, 1.0, 3.0]])
    >>> s = tria(c)
    >>> bool(np.allclose(s @ s.T, c @ c.T)), bool(s[0, 1] == 0), bool(np.all(np.diag(s) >= 0))
    (True, True, True)
    """
    matrix = np.asarray(matrix, float)
    r = np.linalg.qr(matrix.T, mode="r")
    n = matrix.shape[0]
    s = r[:n, :n].T if r.shape[0] >= n else np.vstack([r, np.zeros((n - r.shape[0], r.shape[1]))]).T[:, :n]
    signs = np.where(np.diag(s) < 0, -1.0, 1.0)
    return np.tril(s * signs)


def psd_sqrt(matrix: np.ndarray) -> np.ndarray:
    """A square root ``S`` with ``S S^T = P`` of a symmetric positive semi-definite ``P``.

    Cholesky when ``P`` is definite, else the root from ``eigh`` (a zero process noise
    on a state is allowed).

    >>> s = psd_sqrt(np.diag([4.0, 0.0]))   # semi-definite: the eigen root
    >>> bool(np.allclose(s @ s.T, np.diag([4.0, 0.0])))
    True
    """
    try:
        return np.linalg.cholesky(matrix)
    except np.linalg.LinAlgError:
        values, vectors = np.linalg.eigh(matrix)
        return vectors * np.sqrt(np.clip(values, 0.0, None))


def eigen_root(a: np.ndarray) -> np.ndarray:
    """``L = V sqrt(Lambda)`` with ``L L^T = a`` from the eigen-decomposition of a PSD ``a``.

    Unlike :func:`psd_sqrt` the root is always the eigen one, so it is continuous in ``a``
    (a sampler drawing with it gives draws that move smoothly with the covariance).

    >>> root = eigen_root(np.array([[2.0, 1.0], [1.0, 2.0]]))
    >>> bool(np.allclose(root @ root.T, [[2.0, 1.0], [1.0, 2.0]]))
    True
    """
    if a.size == 0:
        return a.copy()
    values, vectors = np.linalg.eigh(symmetric(a))
    return vectors * np.sqrt(np.maximum(values, 0.0))


def solve(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``matrix^{-1} rhs`` for a small non-singular matrix (least squares if singular).

    LAPACK ``gesv`` through numpy: on the few-by-few matrices of a filter step the
    call overhead dominates, and numpy's is a fraction of scipy's ``cho_solve``.

    >>> solve(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([1.0, 1.0])).tolist()
    [0.5, 0.25]
    """
    try:
        return np.linalg.solve(matrix, rhs)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(matrix, rhs, rcond=None)[0]


def solve_psd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a^-1 b`` for a symmetric positive semi-definite ``a``: Cholesky, minimum-norm least squares if singular.

    >>> solve_psd(np.diag([1.0, 0.0]), np.array([2.0, 3.0])).tolist()   # the singular direction gets 0
    [2.0, 0.0]
    """
    if a.size == 0:
        return np.zeros((0,) + b.shape[1:])
    try:
        root = np.linalg.cholesky(a)
        if np.min(np.diag(root)) <= 1e-13 * np.sqrt(np.max(np.diag(a))):
            raise np.linalg.LinAlgError("numerically singular")
        return np.linalg.solve(root.T, np.linalg.solve(root, b))
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(a, b, rcond=None)[0]


def solve_psd_stack(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a_k^-1 b_k`` for a stack of symmetric positive semi-definite ``a_k`` (pseudo-inverse if singular).

    >>> solve_psd_stack(np.stack([np.eye(2), 2 * np.eye(2)]), np.ones((2, 2, 1)))[:, :, 0].round(12).tolist()
    [[1.0, 1.0], [0.5, 0.5]]
    """
    try:
        root = np.linalg.cholesky(a)
        diag = np.diagonal(root, axis1=1, axis2=2)
        scale = np.sqrt(np.max(np.diagonal(a, axis1=1, axis2=2), axis=1, keepdims=True))
        if np.any(diag <= 1e-13 * scale):
            raise np.linalg.LinAlgError("numerically singular")
        return np.linalg.solve(np.swapaxes(root, 1, 2), np.linalg.solve(root, b))
    except np.linalg.LinAlgError:
        return np.linalg.pinv(a, hermitian=True) @ b


def block(matrix: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``matrix[rows][:, rows]`` (the whole matrix when every row is measured).

    >>> block(np.arange(9.0).reshape(3, 3), np.array([True, False, True])).tolist()
    [[0.0, 2.0], [6.0, 8.0]]
    """
    return matrix if rows.all() else matrix[np.ix_(rows, rows)]


def state_vector(value, n: int, name: str, labels) -> np.ndarray:
    """``value`` as ``n`` finite floats, or a ``PrognosisError`` naming ``name`` and the labels at fault.

    >>> state_vector([1, 2], 2, "mean", ["x", "v"]).tolist()
    [1.0, 2.0]
    """
    vector = np.asarray(value, float).reshape(-1)
    if vector.shape != (n,):
        raise PrognosisError(f"{name}: expected {n} values for {list(labels)}, got shape {vector.shape}")
    if not np.all(np.isfinite(vector)):
        raise PrognosisError(f"{name}: non-finite value for {[labels[i] for i in np.nonzero(~np.isfinite(vector))[0]]}")
    return vector


def covariance_matrix(value, n: int, name: str, labels) -> np.ndarray:
    """``value`` as a symmetric PSD (n, n) covariance; ``n`` variances give a diagonal one.

    Raises a ``PrognosisError`` naming ``name`` (and the labels of negative variances) otherwise.

    >>> covariance_matrix([1.0, 4.0], 2, "Q", ["x", "v"]).tolist()
    [[1.0, 0.0], [0.0, 4.0]]
    """
    matrix = np.asarray(value, float)
    if matrix.ndim == 1 and matrix.shape == (n,):
        matrix = np.diag(matrix)
    if matrix.shape != (n, n):
        raise PrognosisError(f"{name}: expected a ({n}, {n}) matrix or {n} variances for {list(labels)}, "
                             f"got shape {matrix.shape}")
    if not np.all(np.isfinite(matrix)):
        raise PrognosisError(f"{name}: non-finite entries")
    if not np.allclose(matrix, matrix.T, rtol=1e-10, atol=0.0):
        raise PrognosisError(f"{name}: not symmetric")
    diagonal = np.diag(matrix)
    if np.any(diagonal < 0):
        raise PrognosisError(f"{name}: negative variance for {[labels[i] for i in np.nonzero(diagonal < 0)[0]]}")
    if np.linalg.eigvalsh(symmetric(matrix)).min() < -1e-12 * max(float(diagonal.max()), 1e-300):
        raise PrognosisError(f"{name}: not positive semi-definite")
    return symmetric(matrix)
