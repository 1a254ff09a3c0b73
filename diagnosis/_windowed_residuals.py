"""An ARR over records as window-integrated terms: the residual functions a parameter fit minimizes.

Each ARR is split into ``coefficient(theta) * feature(signals)`` terms (:func:`split_terms`), each feature
integrated over windows of :data:`INTEGRATION_WINDOW` samples with the covariance its sensors' noise gives it,
and :class:`Problem` holds every ARR's window residuals, each over its predicted noise, as functions of the
parameters relative to their datasheet values (:func:`windowed_problem`).  Private to
:mod:`diagnosis.parameter_estimation`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy.signal import savgol_coeffs

from .derivatives import default_window, derivative
from .detection import robust_std
from .records import Record
from .steps import step_mask

__all__ = ["INTEGRATION_WINDOW", "NUMERIC_FLOOR", "QUADRATURES", "Block", "Problem", "split_terms",
           "windowed_problem"]

#: Samples over which each row integrates an ARR (windows side by side, one sample apart).  The relation
#: holds integrated over any stretch; integrated, a derivative term ``c dx/dt`` becomes ``c (x(b) - x(a))``,
#: exact and without the derivative filter's noise, and every other term is averaged.  Noise in a regressor
#: biases a least-squares fit towards zero by its variance over the regressor's (errors in variables): over a
#: longer stretch the signal's change grows and its noise does not.
INTEGRATION_WINDOW = 50
#: An ARR is never trusted to hold better than this share of the size of its terms: its residual on a clean
#: record is the error of the numbers that stand for the signals (the trapezoid rule, a derivative estimate, an
#: encoder's counts), which no sensor noise hides.  Without that floor a noise-free record would weigh its
#: windows infinitely and a weakly seen direction would swing to absorb those errors.
NUMERIC_FLOOR = 1e-4
#: The rules a window's integral of a feature's samples may follow (see :func:`estimate_parameters`).
QUADRATURES = ("trapezoid", "euler")


@dataclass
class Block:
    """One ARR over the records: ``features`` (rows x terms) of its window-integrated terms, the terms'
    coefficients as functions of the fitted parameters (and their derivatives), and ``noise``: the covariance of
    one row's features that the sensors' noise and the numbers' own error make (see :func:`_scale`)."""

    name: str
    features: np.ndarray
    coefficient: object
    gradient: list
    noise: np.ndarray
    keys: list = field(default_factory=list)  # (record, first sample) of each row's window


@dataclass
class Problem:
    """The window-integrated residuals of the ARRs over the records, as functions of the chosen parameters
    relative to their datasheet values, each ARR's divided by the noise its sensors give it at those parameters:
    ``residual(x)``, ``jacobian(x)``, rows grouped by ARR."""

    names: list
    nominal: np.ndarray
    blocks: list

    def _coefficients(self, block: Block, x: np.ndarray) -> np.ndarray:
        return np.asarray(block.coefficient(*(self.nominal * x)), float).reshape(-1)

    def _gradient(self, block: Block, x: np.ndarray) -> np.ndarray:
        """d coefficients / d x (terms x parameters)."""
        theta = self.nominal * x
        return np.column_stack([np.asarray(g(*theta), float).reshape(-1) for g in block.gradient]) * self.nominal

    def _scale(self, block: Block, c: np.ndarray) -> float:
        """The ARR's window residual noise at coefficients ``c``: ``sqrt(c' N c)``."""
        return math.sqrt(max(float(c @ block.noise @ c), 0.0)) or 1.0

    def residual(self, x: np.ndarray) -> np.ndarray:
        """Each ARR's window residuals over their noise at ``x``."""
        parts = []
        for b in self.blocks:
            c = self._coefficients(b, x)
            parts.append(b.features @ c / self._scale(b, c))
        return np.concatenate(parts)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        rows = []
        for b in self.blocks:
            c, dc = self._coefficients(b, x), self._gradient(b, x)
            scale = self._scale(b, c)
            # d(r / s) = dr / s - r ds / s^2, with ds = dc' N c / s
            rows.append(b.features @ dc / scale
                        - np.outer(b.features @ c, dc.T @ b.noise @ c) / scale ** 3)
        return np.vstack(rows)

    def per_arr(self, x: np.ndarray) -> dict:
        """ARR name -> its window residuals, in the ARR's own unit."""
        return {b.name: b.features @ self._coefficients(b, x) for b in self.blocks}


def windowed_problem(arrs: Sequence, records: Sequence[Record], names: list, values: Mapping, window: int | None,
             domains: Mapping | None = None, quadrature: str = "trapezoid") -> Problem:
    symbols = [sp.Symbol(n) for n in names]
    fixed = {sp.Symbol(p): v for p, v in values.items() if p not in names}
    blocks = []
    for arr in arrs:
        if not set(names) & set(arr.parameters):
            continue
        compiled = arr.compiled
        try:
            nominal = arr.nominal.xreplace(compiled.symbols).xreplace(fixed)
            terms = split_terms(nominal, compiled.points, symbols, domains)
        except ValueError as error:  # the other ARRs may still hold its parameters
            warnings.warn(f"{arr.name} is left out of the parameter fit: {error}", stacklevel=3)
            continue
        parts = [part for part in (_window_features(compiled, record, list(terms), window, quadrature)
                                         for record in records)
                 if part[0].shape[0]]
        if not parts:  # no whole window in any record
            continue
        features = np.vstack([f for f, _, _ in parts])
        noise = sum(n for _, n, _ in parts) / features.shape[0]
        # the numbers' own error (trapezoid rule, derivative estimates, an encoder's counts): a share of each term
        noise = noise + NUMERIC_FLOOR ** 2 * np.diag(np.mean(features ** 2, axis=0))
        coefficients = sp.Matrix([list(terms.values())])
        blocks.append(Block(arr.name, features, sp.lambdify(symbols, coefficients, modules="numpy"),
                             [sp.lambdify(symbols, coefficients.diff(s), modules="numpy") for s in symbols], noise,
                             [(r, int(start)) for r, (_, _, starts) in enumerate(parts) for start in starts]))
    return Problem(names, np.array([float(values[n]) for n in names]), blocks)


def split_terms(expression: sp.Expr, points: list, parameters: list, domains: Mapping | None = None) -> dict:
    """The ARR as ``sum coefficient(theta) * feature(points)``: feature -> coefficient.

    A parameter whose domain has one sign is taken with it, so that ``Abs(Q/a)`` is ``Abs(Q)/a``; a relation
    whose denominator mixes parameters and signals (a gas law's ``p_0 V/(V_a - V)``) is taken by its numerator,
    which holds where the relation does.  A term whose parameters and signals still cannot be told apart (a
    parameter inside a function of the signals) raises ValueError."""
    signed = {}
    for p in parameters:
        lo, hi = (domains or {}).get(str(p), (-math.inf, math.inf))
        if lo >= 0 or hi <= 0:
            signed[p] = sp.Symbol(str(p), positive=lo >= 0, negative=hi <= 0)
    back = {v: k for k, v in signed.items()}
    expression = expression.xreplace(signed)  # rebuilt: Abs and sign take the signs out
    chosen = [signed.get(p, p) for p in parameters]
    try:
        found = _split(expression, points, chosen)
    except ValueError:
        numerator, denominator = sp.fraction(sp.together(expression))
        if not (denominator.free_symbols & set(chosen) and denominator.free_symbols & set(points)):
            raise
        found = _split(numerator, points, chosen)
    return {feature: coefficient.xreplace(back) for feature, coefficient in found.items()}


def _split(expression: sp.Expr, points: list, parameters: list) -> dict:
    found: dict = {}
    for term in sp.Add.make_args(sp.expand_mul(expression)):
        coefficient, feature = term.as_independent(*points, as_Add=False)
        if feature.free_symbols & set(parameters):
            coefficient, feature = sp.expand_power_base(term, force=True).as_independent(*points, as_Add=False)
        if feature.free_symbols & set(parameters):
            raise ValueError(f"{term} mixes parameters and signals")
        found[feature] = found.get(feature, 0) + coefficient
    return found


def _sensor_noise(values: np.ndarray) -> float:
    """A sampled signal's white-noise standard deviation, from its fourth differences (``70 sigma^2`` for white
    noise; a smooth signal's own are far smaller, and a step's few are outliers the robust spread ignores)."""
    samples = np.asarray(values, float)
    samples = samples[np.isfinite(samples)]
    if samples.size < 20:
        return 0.0
    return float(robust_std(np.diff(samples, 4)) / math.sqrt(70.0))


def _window_features(compiled, record: Record, features: list, window: int | None,
                     quadrature: str = "trapezoid") -> tuple:
    """Each feature integrated over the windows of ``record`` (rows: windows, columns: features), the sum over
    the rows of the features' noise covariance, and each row's first sample.

    A feature ``g(x) dx/dt`` (a first derivative, ``g = 1``) integrates exactly to ``G(x(b)) - G(x(a))``, ``G``
    the antiderivative of ``g`` (:func:`_antiderivative`), and a higher derivative ``d^n x/dt^n`` to the
    difference of the estimates of ``d^(n-1) x/dt^(n-1)`` at the window's ends; any other feature by the
    trapezoid rule (``quadrature="euler"``: the left rectangle rule, exact for a record of an explicit Euler
    model) from its samples.  A window is kept only where the derivative estimates it needs are finite and do
    not reach across an input's step.  Each signal's white noise (:func:`_sensor_noise`) reaches the features
    through their slopes, read by differences one noise level either side, and through the derivative filter's
    coefficients (:func:`_noise_kernels`); the same three values give the mean a curved feature gains from the
    noise (``x**2`` gains ``sigma**2``), taken off its samples."""
    width = int(window or INTEGRATION_WINDOW)
    t = record.t
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    exact = {k: g for k, g in ((k, _antiderivative(f, compiled)) for k, f in enumerate(features)) if g is not None}
    higher = {k: compiled.derivatives[f] for k, f in enumerate(features)
              if k not in exact and f in compiled.derivatives and compiled.derivatives[f][1] > 1}
    numeric = [f for k, f in enumerate(features) if k not in exact]
    points = compiled.point_values(record) if any(f.free_symbols - set(map(sp.Symbol, compiled.signals))
                                                  for f in numeric) else None
    values = {sp.Symbol(s): np.asarray(record[s], float) for s in compiled.signals}
    sigma = {sp.Symbol(s): _sensor_noise(record[s]) for s in compiled.signals}
    filters = {}  # derivative point -> (its signal, the filter's coefficients)
    if points is not None:
        values.update(dict(zip(compiled.points, points)))
        for point, (name, order) in compiled.derivatives.items():
            filters[point] = (sp.Symbol(name), savgol_coeffs(default_window(), 3, deriv=order, delta=step, use="dot"))
            sigma[point] = sigma[sp.Symbol(name)] * float(np.linalg.norm(filters[point][1]))
    usable = _trusted_samples(compiled, record, points or [], numeric)
    for name in compiled.signals:  # a gap in any signal
        usable &= np.isfinite(np.asarray(record[name], float))
    # windows one sample apart: two windows sharing an end sample would share its noise (x(b) - x(a) then x(c) -
    # x(b)), and their residuals would be anti-correlated
    starts = np.arange(0, len(record) - width, width + 1)
    ends = starts + width
    bad = np.concatenate([[0], np.cumsum(~usable)])
    keep = (bad[ends + 1] - bad[starts]) == 0  # no unusable sample in [start, end]
    a, b = starts[keep], ends[keep]
    weights = np.full(width + 1, step)  # each sample's share of a window's integral
    if quadrature == "euler":
        weights[-1] = 0.0
    else:
        weights[[0, -1]] = step / 2
    columns, kernels = [], []
    for k, feature in enumerate(features):
        if k in higher:
            name, order = higher[k]
            lower = derivative(record, name, order=order - 1, window=default_window())
            columns.append(lower[b] - lower[a])
            kernels.append(_end_kernels(sp.Symbol(name), order - 1, sigma, a.size, width, step))
            continue
        samples, slope = _feature_samples(exact.get(k, feature), values, sigma, t.shape)
        if k in exact:
            columns.append(samples[b] - samples[a])
        else:
            samples = np.where(usable, samples, 0.0)  # windows holding an unusable sample were dropped above
            heights = samples[:-1] if quadrature == "euler" else 0.5 * (samples[1:] + samples[:-1])
            cumulative = np.concatenate([[0.0], np.cumsum(heights * np.diff(t))])
            columns.append(cumulative[b] - cumulative[a])
        kernels.append(_noise_kernels(slope, filters, a, width, None if k in exact else weights))
    noise = np.zeros((len(features), len(features)))
    for k in range(len(features)):
        for m in range(k, len(features)):
            noise[k, m] = noise[m, k] = sum(sigma[s] ** 2 * float(np.sum(kernels[k][s] * kernels[m][s]))
                                            for s in kernels[k].keys() & kernels[m].keys())
    matrix = np.column_stack(columns) if columns else np.empty((0, 0))
    return matrix, noise, a


def _noise_kernels(slopes: dict, filters: dict, a: np.ndarray, width: int, weights: np.ndarray | None) -> dict:
    """Signal -> (windows x samples): how much of each sample's noise, from half a derivative filter before the
    window to half one after it, a feature's window value carries.  ``weights`` None: an exact difference, its
    slope at the ends; else an integral, each sample's weight times the slope, spread over the derivative
    filter's span for a derivative estimate."""
    half = (default_window() - 1) // 2
    span = width + 1 + 2 * half
    out: dict = {}
    inside = a[:, None] + np.arange(width + 1)
    for point, slope in slopes.items():
        signal, coefficients = filters.get(point, (point, None))
        kernel = out.setdefault(signal, np.zeros((a.size, span)))
        if weights is None:
            kernel[:, half + width] += slope[a + width]
            kernel[:, half] -= slope[a]
            continue
        share = weights * slope[inside]
        if coefficients is None:
            kernel[:, half:half + width + 1] += share
            continue
        for q, c in enumerate(coefficients):  # the estimate at i reads samples i - half ... i + half
            kernel[:, q:q + width + 1] += c * share
    return out


def _end_kernels(signal, order: int, sigma: dict, windows: int, width: int, step: float) -> dict:
    """Signal -> (windows x samples) of a difference of ``order``-th derivative estimates at a window's ends."""
    half = (default_window() - 1) // 2
    coefficients = savgol_coeffs(default_window(), 3, deriv=order, delta=step, use="dot")
    kernel = np.zeros((windows, width + 1 + 2 * half))
    kernel[:, width:width + 2 * half + 1] += coefficients
    kernel[:, :2 * half + 1] -= coefficients
    return {signal: kernel} if sigma.get(signal, 0.0) > 0 else {}


def _antiderivative(feature: sp.Expr, compiled) -> sp.Expr | None:
    """``G(x)`` with ``dG/dt = feature`` when the feature is ``g(x) dx/dt`` for one signal ``x`` (``x`` itself for
    ``dx/dt``), else None: its integral over a window is then exact, with no derivative estimate."""
    for point, (name, order) in compiled.derivatives.items():
        if order != 1 or point not in feature.free_symbols:
            continue
        signal = sp.Symbol(name)
        slope = sp.diff(feature, point)
        if not slope.free_symbols <= {signal} or sp.simplify(feature - slope * point) != 0:
            return None
        real = sp.Dummy("x", real=True)
        antiderivative = sp.integrate(slope.xreplace({signal: real}), real)
        return None if antiderivative.has(sp.Integral) else antiderivative.xreplace({real: signal})
    return None


def _feature_samples(feature: sp.Expr, values: dict, sigma: dict, shape: tuple) -> tuple[np.ndarray, dict]:
    """A feature's samples, less the mean its signals' noise adds to it, and its slope along each noisy signal."""
    symbols = list(values)
    function = sp.lambdify(symbols, feature, modules="numpy")

    def at(shift: dict) -> np.ndarray:
        with np.errstate(all="ignore"):
            return np.broadcast_to(np.asarray(function(*(values[s] + shift.get(s, 0.0) for s in symbols)), float),
                                   shape)

    samples = at({})
    slopes, bias = {}, np.zeros(shape)
    for s in feature.free_symbols & {s for s, v in sigma.items() if v > 0}:
        up, down = at({s: sigma[s]}), at({s: -sigma[s]})
        slopes[s] = np.nan_to_num((up - down) / (2.0 * sigma[s]), posinf=0.0, neginf=0.0)
        bias += np.nan_to_num(0.5 * (up - 2.0 * samples + down), posinf=0.0, neginf=0.0)
    return samples - bias, slopes


def _trusted_samples(compiled, record: Record, points: list, features: list) -> np.ndarray:
    """Samples where the point values the numeric features need are finite and not across an input's step."""
    needed = set().union(*(f.free_symbols for f in features)) if features else set()
    usable = np.ones(len(record), bool)
    for symbol, values in zip(compiled.points, points):
        if symbol in needed:
            usable &= np.isfinite(values)
    arr = compiled.arr
    orders = [compiled.derivatives[s][1] for s in needed if s in compiled.derivatives]
    inputs = [s for s in arr.signals if s not in arr.sensors and s in record.columns]
    if inputs:  # a step, and the fast transient after it, defeat the derivative filter and the trapezoid rule
        reach = default_window() + max(orders, default=1)
        usable &= ~step_mask({"t": record.t, **{s: record[s] for s in inputs}}, inputs, reach)
    return usable
