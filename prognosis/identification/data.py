"""Checks of the arrays the identification functions take: outputs ``y``, inputs ``u``, model matrices.

Each check returns float arrays of the expected shape or raises a ``PrognosisError`` naming the array
and what is wrong with it.

>>> y, u = check_data([1.0, 2.0, float("nan")], None)
>>> y.shape, u.shape
((3, 1), (3, 0))
"""

from __future__ import annotations

import numpy as np

from ..errors import PrognosisError

__all__ = [
    "as_columns", "check_covariance", "check_data", "check_future_inputs", "check_inputs", "check_matrix",
]


def check_matrix(name: str, value, rows: int | None = None) -> np.ndarray:
    """``value`` as a finite 2-D float matrix (a 1-D one of ``rows`` entries as a column); the error names ``name``."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise PrognosisError(f"{name} must be a numeric matrix: {exc}") from None
    if a.ndim == 1 and rows is not None and a.size == rows:
        a = a[:, None]
    if a.ndim != 2:
        raise PrognosisError(f"{name} must be a 2-D matrix, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise PrognosisError(f"{name} has non-finite entries")
    if rows is not None and a.shape[0] != rows:
        raise PrognosisError(f"{name} must have {rows} rows, got shape {a.shape}")
    return a


def check_covariance(name: str, value, size: int) -> np.ndarray:
    """``value`` as a symmetric positive semi-definite (size, size) matrix; the error names ``name``."""
    a = check_matrix(name, value)
    if a.shape != (size, size):
        raise PrognosisError(f"{name} must have shape ({size}, {size}), got {a.shape}")
    scale = max(1.0, float(np.abs(a).max())) if a.size else 1.0
    if not np.allclose(a, a.T, rtol=0.0, atol=1e-9 * scale):
        raise PrognosisError(f"{name} must be symmetric")
    a = 0.5 * (a + a.T)
    if size and np.linalg.eigvalsh(a)[0] < -1e-10 * scale:
        raise PrognosisError(f"{name} must be positive semi-definite (smallest eigenvalue "
                             f"{np.linalg.eigvalsh(a)[0]:.3g})")
    return a


def as_columns(value, name: str) -> np.ndarray:
    """``value`` as a float array, a 1-D series as one column; a clear error naming it if not numeric."""
    try:
        value = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise PrognosisError(f"{name} must be numeric: {exc}") from None
    return value[:, None] if value.ndim == 1 else value


def check_data(y, u) -> tuple[np.ndarray, np.ndarray]:
    """``y`` as (T, m) with NaN allowed, ``u`` as (T, r) finite (r = 0 for None)."""
    y = as_columns(y, "y")
    if y.ndim != 2 or y.shape[0] == 0 or y.shape[1] == 0:
        raise PrognosisError(f"y must have shape (T,) or (T, m) with T, m >= 1, got {y.shape}")
    if np.any(np.isinf(y)):
        raise PrognosisError("y has infinite entries (use NaN for a missing measurement)")
    return y, check_inputs(u, y.shape[0], None)


def check_inputs(u, steps: int | None, width: int | None, name: str = "u") -> np.ndarray:
    """``u`` as finite (T, r) inputs, checked against ``steps`` rows and ``width`` columns when given."""
    if u is None:
        if width:
            raise PrognosisError(f"{name} is required: the model has {width} inputs")
        if steps is None:
            raise PrognosisError(f"{name} is required")
        return np.zeros((steps, 0))
    u = as_columns(u, name)
    if u.ndim != 2:
        raise PrognosisError(f"{name} must have shape (T, r), got {u.shape}")
    if steps is not None and u.shape[0] != steps:
        raise PrognosisError(f"{name} has {u.shape[0]} rows but y has {steps}")
    if width is not None and u.shape[1] != width:
        raise PrognosisError(f"{name} has {u.shape[1]} columns but the model has {width} inputs")
    if not np.all(np.isfinite(u)):
        raise PrognosisError(f"{name} has non-finite entries (inputs must be known)")
    return u


def check_future_inputs(u_future, steps: int | None, width: int, caller: str) -> np.ndarray:
    """The known future inputs as (H, r); without inputs, ``steps`` gives the horizon H."""
    if u_future is None:
        if steps is None:
            raise PrognosisError(f"{caller} needs u_future (H, r) or, for a model without inputs, steps")
        u_future = np.zeros((int(steps), 0))
    return check_inputs(u_future, None, width, name="u_future")


