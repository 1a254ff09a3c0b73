"""The covariance of a windowed parameter fit: sandwich, leverage, Newey-West, the modelled floor.

Private to :mod:`diagnosis.parameter_estimation`.
"""

from __future__ import annotations

import math

import numpy as np

from ._windowed_residuals import Problem
from .detection import robust_std

__all__ = ["LAGS", "fit_covariance"]

#: Lags of the residuals' autocorrelation that the intervals count (Newey-West): neighbouring windows share an
#: end sample, and a derivative estimate's noise spans a few samples.
LAGS = 5


def fit_covariance(problem: Problem, x: np.ndarray, prior: float = math.inf) -> tuple[np.ndarray, dict, dict]:
    """The fit's covariance (relative parameters), robust to the residuals' own variance and autocorrelation:
    the sandwich of the objective's Hessian (:func:`_hessian`) about a Newey-West middle (Bartlett weights over
    :data:`LAGS` lags) of the windows' scores.  A window's score adds its rows of every ARR (ARRs that share a
    sensor share its noise), its residuals first scaled up by their leverage (:func:`_window_scores`).  An ARR
    whose residual is quieter than its sensors and numbers predict (a clean record) counts as noisy as
    predicted.  Also each ARR's residual spread, in its own unit, and the ratio of its scores' variance with
    the lags to without (its inflation)."""
    jac, scaled, per_arr = problem.jacobian(x), problem.residual(x), problem.per_arr(x)
    information = np.eye(x.size) / prior ** 2  # the prior's own share
    bread = np.linalg.pinv(_hessian(problem, x, jac, scaled) + information)
    noise, inflation, start = {}, {}, 0
    meat = information.copy()
    for block in problem.blocks:
        size = block.features.shape[0]
        rows, residual = jac[start:start + size], scaled[start:start + size]
        start += size
        scores = rows * residual[:, None]
        noise[block.name] = float(robust_std(per_arr[block.name]))
        spread = robust_std(residual)
        if spread < 1.0:  # quieter than predicted: the prediction's share of the information
            meat += (1.0 - spread ** 2) * rows.T @ rows
        own = _newey_west(scores)
        inflation[block.name] = float(np.trace(own) / np.trace(scores.T @ scores)) if np.any(scores) else 1.0
    index = _rows_by_window(problem)
    windows = _window_scores(jac, scaled, index, np.linalg.pinv(jac.T @ jac + information))
    for record in sorted({r for r, _ in windows}):
        meat += _newey_west(np.array([windows[k] for k in sorted(k for k in windows if k[0] == record)]))
    sandwich = bread @ meat @ bread
    # the same sandwich with the windows' scores averaged over the record: each ARR's residual variance (at least
    # the predicted) and the ARRs' correlations (redundant ARRs share their sensors' noise).  The plain middle
    # squares the scores of the few windows that hold most of a parameter's information, and on some records it
    # comes out far too small; this one cannot, and the intervals take the wider of the two
    steady = bread @ (_modelled_middle(index, len(problem.blocks), jac, scaled) + information) @ bread
    wider = np.sqrt(np.maximum(np.diag(steady), np.diag(sandwich)) / np.maximum(np.diag(sandwich), 1e-300))
    return sandwich * np.outer(wider, wider), noise, inflation


def _rows_by_window(problem: Problem) -> dict:
    """Window (record, first sample) -> {ARR's block number: its row in the stacked residuals}."""
    index: dict = {}
    start = 0
    for b, block in enumerate(problem.blocks):
        for row, key in enumerate(block.keys):
            index.setdefault(key, {})[b] = start + row
        start += block.features.shape[0]
    return index


def _modelled_middle(index: dict, count: int, jac: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """``sum_w J_w' V J_w`` over the windows (``index``: :func:`_rows_by_window`), ``V`` the covariance of the
    ``count`` ARRs' scaled residuals over one window, estimated over all of them (each ARR's variance at least
    1, the predicted)."""
    second, shared = np.zeros((count, count)), np.zeros((count, count))
    for rows in index.values():
        blocks = list(rows)
        values = residual[[rows[b] for b in blocks]]
        second[np.ix_(blocks, blocks)] += np.outer(values, values)
        shared[np.ix_(blocks, blocks)] += 1.0
    covariance = second / np.maximum(shared, 1.0)
    spread = np.sqrt(np.maximum(np.diag(covariance), 1e-300))
    correlation = np.clip(covariance / np.outer(spread, spread), -1.0, 1.0)
    level = np.maximum(spread, 1.0)
    covariance = correlation * np.outer(level, level)
    middle = np.zeros((jac.shape[1], jac.shape[1]))
    for rows in index.values():
        blocks = list(rows)
        block = jac[[rows[b] for b in blocks]]
        middle += block.T @ covariance[np.ix_(blocks, blocks)] @ block
    return middle


def _window_scores(jac: np.ndarray, residual: np.ndarray, index: dict, inverse: np.ndarray) -> dict:
    """Window -> its score ``J_w' (I - H_w)^(-1/2) u_w``: the rows of every ARR over that window, their residuals
    scaled up by their leverage ``H_w = J_w (J'J)^-1 J_w'`` (Bell and McCaffrey's small-sample correction).  A
    window that pulls the fit towards itself leaves a residual smaller than its noise; with few windows per
    parameter the plain scores would make the intervals too narrow."""
    scores = {}
    for key, rows in index.items():
        at = list(rows.values())
        block = jac[at]
        values, vectors = np.linalg.eigh(np.eye(len(at)) - block @ inverse @ block.T)
        # a leverage of 1 (a window that alone fixes a direction) would divide by zero: cap its correction
        root = (vectors / np.sqrt(np.clip(values, 0.01, 1.0))) @ vectors.T
        scores[key] = block.T @ (root @ residual[at])
    return scores


def _hessian(problem: Problem, x: np.ndarray, jac: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """Half the Hessian of the sum of squared residuals, by central differences of its gradient.  Its
    Gauss-Newton part alone, ``J'J``, counts the regressors' noise as information (it holds their noisy
    Gram matrix), which the curvature of the noise scaling takes back; where the difference is not positive
    definite (a flat direction), ``J'J``."""
    gauss_newton = jac.T @ jac
    step = 1e-6
    columns = []
    for k in range(x.size):
        dx = np.zeros(x.size)
        dx[k] = step * max(abs(x[k]), 1.0)
        up = problem.jacobian(x + dx).T @ problem.residual(x + dx)
        down = problem.jacobian(x - dx).T @ problem.residual(x - dx)
        columns.append((up - down) / (2.0 * dx[k]))
    hessian = 0.5 * (np.column_stack(columns) + np.column_stack(columns).T)
    if not np.all(np.isfinite(hessian)) or np.linalg.eigvalsh(hessian).min() <= 1e-9 * np.abs(hessian).max():
        return gauss_newton
    return hessian


def _newey_west(scores: np.ndarray) -> np.ndarray:
    """``sum_t g_t g_t' + sum_l (1 - l/(L+1)) sum_t (g_t g_{t-l}' + g_{t-l} g_t')`` over consecutive rows."""
    middle = scores.T @ scores
    for lag in range(1, min(LAGS, len(scores) - 1) + 1):
        cross = scores[lag:].T @ scores[:-lag]
        middle = middle + (1.0 - lag / (LAGS + 1)) * (cross + cross.T)
    return middle
