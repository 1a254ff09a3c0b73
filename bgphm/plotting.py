"""Plots of the toolkit's results: residuals and thresholds, simulations, estimates, RUL.

matplotlib is optional (``pip install 'bondgraph-phm[plot]'``) and imported inside the
functions, so importing this module costs nothing and works without it; calling a plot
function without matplotlib raises :class:`ImportError` with the install hint.  The plot
functions leave the backend alone: scripts that write files select ``Agg`` with
``pyplot("Agg")``, or hand their drawing function to :func:`write_figures`, which also
skips the figures (with a note) when matplotlib is missing.

Every plot function draws on ``ax`` (or ``axes``) when given, on a new figure otherwise,
and returns what it drew on.

Example
-------
>>> plt = pyplot("Agg")
>>> fig, ax = plt.subplots()
>>> shaded = band(ax, [0.0, 1.0, 2.0], [0.0, 0.5, 1.0], [1.0, 1.5, 2.0], label="5-95 %")
>>> shaded.get_alpha(), len(ax.collections)
(0.25, 1)
>>> plt.close(fig)
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from bgphm.files import write_with
from bondgraph.optional import import_optional

__all__ = [
    "MATPLOTLIB_MISSING", "axis_label", "band", "plot_estimate", "plot_evaluation", "plot_rul", "plot_rul_distribution",
    "plot_simulation", "pyplot", "save_figure", "write_figures",
]

if TYPE_CHECKING:  # annotations only: matplotlib stays optional
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    from bondgraph.simulation import SimulationResult
    from diagnosis.detection import Evaluation
    from prognosis.health_monitor import MonitorResult
    from prognosis.rul import RULDistribution

MATPLOTLIB_MISSING = "matplotlib is needed for plots: pip install 'bondgraph-phm[plot]'"


def pyplot(backend: str | None = None) -> ModuleType:
    """``matplotlib.pyplot``, imported now.

    Parameters
    ----------
    backend : str, optional
        Selected first, e.g. ``"Agg"`` to write files on a machine without a display.

    Raises
    ------
    ImportError
        Without matplotlib, with the install hint.
    """
    matplotlib = import_optional("matplotlib", MATPLOTLIB_MISSING)
    if backend is not None:
        matplotlib.use(backend)
    return import_optional("matplotlib.pyplot", MATPLOTLIB_MISSING)


def write_figures(draw: Callable[..., list[Path]], *args, **kwargs) -> list[Path]:
    """Call a function that writes figure files, if matplotlib is there.

    Selects the Agg backend and returns ``draw(*args, **kwargs)`` (the paths written); without
    matplotlib, says so on stderr and returns ``[]``, so scripts write their other results anyway.

    Parameters
    ----------
    draw : callable
        Draws and saves the figures (:func:`save_figure`), returning their paths.
    *args, **kwargs
        Passed to ``draw``.

    Returns
    -------
    list of Path
    """
    try:
        pyplot("Agg")
    except ImportError as error:
        print(f"  no figures: {error}", file=sys.stderr)
        return []
    return draw(*args, **kwargs)


def _axes(ax: Axes | None, **figure) -> Axes:
    """``ax``, or the Axes of a new figure."""
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(**figure)
    return ax


def save_figure(fig: Figure, path: str | Path, dpi: int = 110) -> Path:
    """Lay out, write and close a figure.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        Output file; the format follows the suffix (``.png``, ``.pdf``, ``.svg``...).
    dpi : int
        Resolution of raster formats.

    Returns
    -------
    Path
        ``path``, as a :class:`~pathlib.Path`.
    """
    plt = pyplot()
    path = Path(path)
    fig.tight_layout()
    # the format follows the suffix of path, which the temporary file keeps
    write_with(path, lambda temporary: fig.savefig(temporary, dpi=dpi, format=path.suffix.lstrip(".") or None))
    plt.close(fig)
    return path


def band(ax: Axes, x: Any, lower: Any, upper: Any, **kwargs) -> PolyCollection:
    """Shade the region between the curves ``lower`` and ``upper`` over ``x``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    x, lower, upper : array_like
        Abscissae and the two bounding curves (scalars broadcast).  NaN samples leave gaps.
    **kwargs
        Passed to :meth:`~matplotlib.axes.Axes.fill_between`; ``alpha`` defaults to 0.25 so
        the curves under the band stay visible, and the colour follows the property cycle.

    Returns
    -------
    matplotlib.collections.PolyCollection
        The band (``ax`` is the caller's already).
    """
    kwargs.setdefault("alpha", 0.25)
    return ax.fill_between(x, lower, upper, **kwargs)


def axis_label(name: str, unit: str | None = None) -> str:
    """An axis label: the quantity's name and, when known, its unit in parentheses.

    >>> axis_label("b", "N*m*s/rad"), axis_label("RUL", "s"), axis_label("theta")
    ('b (N*m*s/rad)', 'RUL (s)', 'theta')
    """
    return f"{name} ({unit})" if unit else name


def plot_evaluation(evaluation: Evaluation, ax: Axes | None = None, *, bglft: bool = False,
                    title: str | None = None, unit: str | None = None) -> Axes:
    """Residual of one ARR with its robust threshold band and the alarm.

    Draws ``-r_n`` against time, the interval band ``[B_lo - m, B_hi + m]`` (``m`` the noise
    margin), optionally the BG-LFT band ``[-sum|w_i| - m, sum|w_i| + m]``, and a dotted
    vertical line at the detection time when there is an alarm.

    Parameters
    ----------
    evaluation : diagnosis.detection.Evaluation
    ax : matplotlib.axes.Axes, optional
    bglft : bool
        Also shade the BG-LFT band.
    title : str, optional
        Default: the ARR's name.  Plain text: a ``$`` in it is shown, not read as mathtext.
    unit : str, optional
        The residual's unit (:meth:`diagnosis.ARR.unit`), on the vertical axis.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(8, 4))
    e = evaluation
    ax.plot(e.t, -e.residual, lw=0.8, label=r"$-r_n$")
    band(ax, e.t, e.lower - e.margin, e.upper + e.margin, color="tab:red", label="interval threshold")
    if bglft:
        band(ax, e.t, -e.bglft - e.margin, e.bglft + e.margin, color="tab:grey", alpha=0.2,
             label="BG-LFT threshold")
    if e.detection_time is not None:
        ax.axvline(e.detection_time, color="k", ls=":", label=f"alarm at t = {e.detection_time:g} s")
    ax.set_xlabel("t (s)")
    ax.set_ylabel(r"$-r_n$" + (f" ({unit})" if unit else ""))  # a unit text holds no "$" (bondgraph.units)
    # names come from the model and the record: shown as they are, never parsed as mathtext
    ax.set_title(e.name if title is None else title, parse_math=False)
    ax.legend(fontsize=8)
    return ax


def plot_simulation(result: SimulationResult, signals: Sequence[str] | None = None,
                    axes: Sequence[Axes] | Axes | None = None, units: Mapping[str, str] | None = None) -> Figure:
    """Trajectories of a simulation, one subplot per signal, sharing the time axis.

    Parameters
    ----------
    result : bondgraph.simulation.SimulationResult
    signals : sequence of str, optional
        Signal or state names (as ``result[name]`` takes them).  Default: every signal of
        the result (inputs and measured outputs, in the result's order).
    axes : Axes or sequence of Axes, optional
        One per signal; default: a new figure.
    units : mapping of str to str, optional
        Each signal's unit, on its axis (:attr:`bondgraph.model.BondGraph.units`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = pyplot()
    names = list(result.signals) if signals is None else list(signals)
    if not names:
        raise ValueError("no signal to plot")
    if axes is None:
        _, grid = plt.subplots(len(names), 1, figsize=(7, 1.8 + 1.4 * len(names)), sharex=True, squeeze=False)
        axes = list(grid[:, 0])
    else:
        axes = list(np.atleast_1d(np.asarray(axes, dtype=object)).ravel())
        if len(axes) != len(names):
            raise ValueError(f"{len(names)} signals need {len(names)} axes, got {len(axes)}")
    for ax, name in zip(axes, names):
        ax.plot(result.t, result[name], lw=1)
        ax.set_ylabel(axis_label(name, (units or {}).get(name)), parse_math=False)  # a name, not mathtext
    axes[-1].set_xlabel("t (s)")
    return axes[0].figure


def _truth_values(truth: Callable | Any, t: np.ndarray) -> np.ndarray:
    """``truth`` at the times ``t``: an array as it is, a callable called on all times or one by one."""
    if not callable(truth):
        return np.asarray(truth, float)
    try:
        return np.broadcast_to(np.asarray(truth(t), float), t.shape)
    except (TypeError, ValueError):  # a callable of one scalar time
        return np.array([float(truth(s)) for s in t])


def plot_estimate(result: MonitorResult, parameter_name: str = "theta", truth: Callable | Any = None,
                  ax: Axes | None = None, *, label: str | None = None, unit: str | None = None,
                  failure: float | None = None) -> Axes:
    """Particle-filter estimate of a degrading parameter (or of its rate) over time.

    Parameters
    ----------
    result : prognosis.health_monitor.MonitorResult
    parameter_name : {"theta", "gamma"}
        Which estimate of the result: the parameter ``theta`` or its degradation rate ``gamma``.
    truth : callable of t or array_like, optional
        The true values, drawn dashed.
    ax : matplotlib.axes.Axes, optional
    label, unit : str, optional
        The parameter's name (default ``parameter_name``) and unit, on the vertical axis.
    failure : float, optional
        The failure value, drawn as a horizontal line.

    Returns
    -------
    matplotlib.axes.Axes
        With the weighted mean and, when the result holds them, the 5-95 % quantiles as a band.
    """
    if parameter_name not in ("theta", "gamma"):
        raise ValueError(f"parameter_name must be 'theta' or 'gamma', got {parameter_name!r}")
    ax = _axes(ax, figsize=(7, 4))
    estimate, t = getattr(result, parameter_name), np.asarray(result.t, float)
    if "quantiles" in estimate:
        band(ax, t, estimate["quantiles"][:, 0], estimate["quantiles"][:, -1], color="C0", label="5-95 %")
    ax.plot(t, estimate.get("mean", np.full(t.shape, np.nan)), color="C0", label="estimate (mean)")
    if truth is not None:
        ax.plot(t, _truth_values(truth, t), "k--", label="true")
    if failure is not None:
        ax.axhline(failure, color="tab:red", ls="-.", lw=1, label=f"failure value {failure:.4g}" +
                   (f" {unit}" if unit else ""))
    ax.set_xlabel("t (s)")
    ax.set_ylabel(axis_label(label or parameter_name, unit), parse_math=False)
    ax.legend(fontsize=8)
    return ax


def plot_rul(result: MonitorResult, eol: float | None = None, alpha: float = 0.1, ax: Axes | None = None) -> Axes:
    """RUL predictions against the time they were made.

    Draws the median (solid) and the mean over the particles that fail within the horizon
    (dashed) with the 5-95 % band; percentiles beyond the horizon (censored particles) are
    drawn at the horizon, marked there, with the horizon dotted.  With ``eol``, also the true
    RUL ``eol - t`` and the alpha cone ``[(1 - alpha), (1 + alpha)] (eol - t)`` of the
    alpha-lambda metric.

    Parameters
    ----------
    result : prognosis.health_monitor.MonitorResult
    eol : float, optional
        True end of life (same time unit as the result).
    alpha : float
        Half-width of the cone, relative to the true RUL.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(7, 4))
    t = np.asarray(result.rul_t, float)
    if eol is not None:
        true = eol - t
        band(ax, t, (1 - alpha) * true, (1 + alpha) * true, color="tab:grey",
             label=rf"$\alpha$-cone ($\alpha$ = {alpha:g})")
        ax.plot(t, true, "k--", label="true RUL")
    if len(result.rul):
        horizon = np.array([p.horizon for p in result.rul], float)
        percentiles = result.rul_percentiles((5, 50, 95))
        q = np.minimum(percentiles, horizon[:, None])
        band(ax, t, q[:, 0], q[:, 2], color="C0", label="5-95 %")
        ax.plot(t, q[:, 1], color="C0", label="median")
        ax.plot(t, result.rul_mean, color="C1", ls="--", label="mean")
        cut = percentiles > horizon[:, None]
        if cut.any():  # beyond the horizon a percentile is unknown, not equal to it: say so on the plot
            ax.plot(t, horizon, color="tab:grey", ls=":", lw=1, label="horizon")
            for column, (level, marker) in enumerate(((5, "v"), (50, "o"), (95, "^"))):
                if cut[:, column].any():
                    ax.plot(t[cut[:, column]], horizon[cut[:, column]], marker, ls="none", color="tab:grey", ms=4,
                            label=f"{level} % beyond the horizon")
    ax.set(xlabel="t (s)", ylabel="RUL (s)")
    ax.legend(fontsize=8)
    return ax


def plot_rul_distribution(prediction: RULDistribution, ax: Axes | None = None, bins: int = 40) -> Axes:
    """Weighted histogram of one RUL prediction (the first asset).

    Bars hold probability mass (the particle weights normalized over all particles), so
    they add up to the fraction that fails within the horizon; the censored fraction (no
    failure within the horizon, RUL ``+inf``) is not drawn but given in the title.

    Parameters
    ----------
    prediction : prognosis.rul.RULDistribution
    ax : matplotlib.axes.Axes, optional
    bins : int or sequence
        As :meth:`~matplotlib.axes.Axes.hist` takes them.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, figsize=(7, 4))
    samples = np.asarray(prediction.samples, float)[0]
    weights = np.asarray(prediction.weights, float)[0]
    finite = np.isfinite(samples)
    total = weights.sum()
    mass = weights / total if total > 0 else np.zeros_like(weights)
    censored = float(mass[~finite].sum())
    ax.hist(samples[finite], bins=bins, weights=mass[finite], color="C0", alpha=0.7, label="predicted RUL")
    mean = float(prediction.mean[0])
    if np.isfinite(mean):
        ax.axvline(mean, color="C1", ls="--", label=f"mean {mean:.4g} s")
    ax.set(xlabel="RUL (s)", ylabel="probability mass",
           title=f"RUL distribution: {censored:.1%} censored (beyond the horizon, {prediction.horizon:g} s)")
    ax.legend(fontsize=8)
    return ax
