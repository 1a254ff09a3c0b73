"""Multi-step-ahead fault prediction with forecast measurements (Du et al. (n.d.), section 5).

A filter that estimates a drifting parameter as a state needs measurements to
move; the future ones do not exist yet.  At each step ``k``:

1. the filter assimilates the real measurement ``z_k``;
2. a forecaster (e.g. :class:`prognosis.statespace.elm.SeriesForecaster`, one ROS-ELM
   per measured variable) learns ``z_k`` online and forecasts
   ``z_{k+1}, ..., z_{k+n}``;
3. a *copy* of the filter steps through those pseudo-measurements; its
   estimate at ``k + n`` is the ``n``-step-ahead prediction of the state and
   of the parameter (steps 3-8).

The real filter is never fed a forecast: the copy is thrown away, and step
``k + 1`` starts from the filter that saw ``z_1..z_{k+1}`` (our reading of
step 9, which the paper leaves open).

Example
-------
>>> import sympy as sp
>>> from types import SimpleNamespace
>>> from prognosis.statespace import CubatureKalmanFilter
>>> from prognosis.statespace import discretize
>>> x, a = sp.symbols("x a")
>>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
>>> model = discretize(decay, dt=1.0, augment=["a"])
>>> ckf = CubatureKalmanFilter(model, [1.0, 0.1], np.diag([1e-6, 1e-4]), np.diag([1e-10, 1e-8]), [[1e-8]])
>>> z = 0.88 ** np.arange(1, 41)[:, None]  # the truth decays at 0.12, the filter starts at 0.1
>>> run = predict_ahead(ckf, z, horizon=3, start=20, forecasts=lambda k: z[k:k + 3])
>>> int(run.target[0]), round(float(run.predicted[0, 1]), 4)
(23, 0.12)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import PrognosisError

__all__ = ["LookAhead", "look_ahead", "predict_ahead"]


def look_ahead(estimator, forecasts, inputs=None) -> np.ndarray:
    """Means of a copy of ``estimator`` after each forecast measurement, shape ``(n, n_states)``.

    ``inputs`` is None or a mapping (signal -> value) for all steps, or a sequence of ``n`` inputs
    (future inputs are assumed known).

    Parameters
    ----------
    estimator : filter with ``step``, ``mean`` and ``copy``
        Left untouched: a copy steps through the forecasts.
    forecasts : array (n, m)
        Forecast measurements for the next ``n`` steps.
    inputs : None, mapping or sequence of ``n``

    Returns
    -------
    ndarray (n, n_states)

    Examples
    --------
    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import CubatureKalmanFilter
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> model = discretize(decay, dt=1.0, augment=["a"])
    >>> ckf = CubatureKalmanFilter(model, [1.0, 0.1], np.diag([1e-6, 1e-4]), np.diag([1e-10, 1e-8]), [[1e-8]])
    >>> means = look_ahead(ckf, [[0.9], [0.81], [0.729]])
    >>> np.round(means, 4).tolist()
    [[0.9, 0.1], [0.81, 0.1], [0.729, 0.1]]
    >>> ckf.mean.tolist()   # the filter itself has not moved
    [1.0, 0.1]
    """
    forecasts = np.atleast_2d(np.asarray(forecasts, float))
    copy = estimator.copy()
    means = np.empty((forecasts.shape[0], len(copy.mean)))
    for j, z in enumerate(forecasts):
        copy.step(z, _input(inputs, j))
        means[j] = copy.mean
    return means


@dataclass
class LookAhead:
    """A filter run with an ``n``-step-ahead prediction at every step from ``start``.

    Attributes
    ----------
    filtered : ndarray (K, n_states)
        Filtered mean after each real measurement ``z_1..z_K`` (row ``k - 1`` is time ``k``).
    fading : ndarray (K,)
        Strong-tracking factor of each real update (1 without strong tracking).
    nis : ndarray (K,)
        Normalized innovation squared of each real update.
    origin, target : ndarray of int
        Time ``k`` of each prediction and the time ``k + n`` it predicts.
    predicted : ndarray (len(target), n_states)
        Mean of the look-ahead copy at ``target``.
    seconds : float
        Wall time of the filter and its look-aheads (forecasting not included).

    Examples
    --------
    Returned by :func:`predict_ahead`; 20 measurements, 2-step-ahead predictions from time 15:

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import CubatureKalmanFilter
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> ckf = CubatureKalmanFilter(discretize(decay, dt=1.0, augment=["a"]), [1.0, 0.1], np.diag([1e-6, 1e-4]),
    ...                            np.diag([1e-10, 1e-8]), [[1e-8]])
    >>> z = 0.88 ** np.arange(1, 21)[:, None]
    >>> run = predict_ahead(ckf, z, horizon=2, start=15, forecasts=lambda k: z[k:k + 2])
    >>> run.filtered.shape, run.nis.shape, run.fading.tolist() == [1.0] * 20
    ((20, 2), (20,), True)
    >>> run.origin.tolist(), run.target.tolist(), run.predicted.shape
    ([15, 16, 17, 18], [17, 18, 19, 20], (4, 2))
    >>> bool(np.allclose(run.predicted[:, 0], z[16:, 0], rtol=1e-4)), run.seconds > 0
    (True, True)
    """

    filtered: np.ndarray
    fading: np.ndarray
    nis: np.ndarray
    origin: np.ndarray
    target: np.ndarray
    predicted: np.ndarray
    seconds: float


def predict_ahead(estimator, measurements, *, horizon: int, start: int, forecasts: Callable[[int], np.ndarray],
                  inputs=None) -> LookAhead:
    """Run ``estimator`` over ``measurements`` (K, m) with an ``horizon``-step look-ahead from time ``start``.

    Parameters
    ----------
    estimator : filter with ``step``, ``mean`` and ``copy`` (the Kalman filters or
        :class:`~prognosis.statespace.BootstrapParticleFilter`)
        Advanced in place over the real measurements.
    measurements : array (K, m)
        ``z_1..z_K``; row ``k - 1`` is time ``k``.
    horizon : int
        ``n``, the number of steps predicted ahead.
    start : int
        First time ``k`` at which a prediction is made (the paper's ``N0``, the end of the training window).
    forecasts : callable
        ``forecasts(k)`` -> array (horizon, m) of the measurements forecast at time ``k`` for ``k+1..k+n``.
        The forecaster is expected to have learned ``z_1..z_k`` when it is called.
    inputs : None or a mapping (signal -> value) for every step, or a sequence of K, one per time step

    Returns
    -------
    LookAhead

    Examples
    --------
    The rate of ``dx/dt = -a x`` is 0.12 (the filter starts at 0.1); forecasts
    here are the true future measurements, a perfect forecaster:

    >>> import sympy as sp
    >>> from types import SimpleNamespace
    >>> from prognosis.statespace import ExtendedKalmanFilter
    >>> from prognosis.statespace import discretize
    >>> x, a = sp.symbols("x a")
    >>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
    >>> ekf = ExtendedKalmanFilter(discretize(decay, dt=1.0, augment=["a"]), [1.0, 0.1], np.diag([1e-6, 1e-4]),
    ...                            np.diag([1e-10, 1e-8]), [[1e-8]])
    >>> z = 0.88 ** np.arange(1, 31)[:, None]
    >>> run = predict_ahead(ekf, z, horizon=5, start=10, forecasts=lambda k: z[k:k + 5])
    >>> int(run.origin[0]), int(run.target[0]), round(float(run.predicted[0, 0] / z[14, 0]), 4)
    (10, 15, 1.0)
    >>> round(float(ekf.mean[1]), 3)   # the filter itself has seen every real measurement
    0.12
    """
    z = np.asarray(measurements, float)
    if z.ndim != 2:
        raise PrognosisError(f"measurements: expected shape (K, m), got {z.shape}")
    if horizon < 1:
        raise PrognosisError(f"horizon must be at least 1 step, got {horizon}")
    steps = z.shape[0]
    if not 1 <= start <= steps - horizon:
        raise PrognosisError(f"start must be in [1, {steps - horizon}] for {steps} measurements and horizon {horizon}, "
                             f"got {start}")
    filtered = np.empty((steps, len(estimator.mean)))
    fading, nis = np.ones(steps), np.full(steps, np.nan)
    origin = np.arange(start, steps - horizon + 1)
    predicted = np.empty((origin.size, filtered.shape[1]))
    seconds = 0.0
    for k in range(1, steps + 1):
        begin = time.perf_counter()
        innovation = estimator.step(z[k - 1], _input(inputs, k - 1))
        filtered[k - 1], fading[k - 1], nis[k - 1] = estimator.mean, innovation.fading, innovation.nis
        seconds += time.perf_counter() - begin
        if k >= start and k + horizon <= steps:
            future = np.asarray(forecasts(k), float)
            if future.shape != (horizon, z.shape[1]):
                raise PrognosisError(f"forecasts({k}) returned shape {future.shape}, expected {(horizon, z.shape[1])}")
            begin = time.perf_counter()
            ahead_inputs = None if inputs is None else [_input(inputs, k + j) for j in range(horizon)]
            predicted[k - start] = look_ahead(estimator, future, ahead_inputs)[-1]
            seconds += time.perf_counter() - begin
    return LookAhead(filtered, fading, nis, origin, origin + horizon, predicted, seconds)


def _input(inputs, j: int):
    """``None`` or a mapping holds for every step; anything else is a sequence of per-step inputs."""
    return inputs if inputs is None or isinstance(inputs, Mapping) else inputs[j]
