"""What the commands write: --out checked first, text to stdout or a file, JSON values, plots."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from bgphm.files import check_output, input_files, write_text
from bgphm.units import units_of

from ._progress import Progress

__all__ = ["emit", "estimate_labels", "finite_or_none", "fmt", "json_value", "output_directory", "output_file",
           "units_of", "vars_of", "write_plots", "write_report"]


def output_file(args) -> Path | None:
    """``--out`` of a command writing one file, checked before any work; None for stdout."""
    if args.out in (None, "-"):
        return None
    return check_output(args.out, kind="file", inputs=input_files(args.model, getattr(args, "inputs", None)),
                        force=args.force)


def output_directory(args) -> Path | None:
    """``--out`` of a command writing a directory of files, checked before any work; None without it."""
    if args.out is None:
        return None
    return check_output(args.out, kind="directory", inputs=input_files(args.model, args.data), force=args.force)


def emit(text: str, out: Path | None) -> None:
    if out is None:
        sys.stdout.write(text)
        return
    print(f"wrote {write_text(out, text)}")


def finite_or_none(value) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def fmt(value) -> str:
    return "n/a" if value is None else f"{value:.4g}"


def json_value(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serializable: {type(value).__name__}")


def estimate_labels(summary: dict, failures: dict, units) -> dict:
    """What the prognosis plots name: the residuals' units, and the reported candidate, its unit and failure
    value (none for a pair or a sensor)."""
    labels = {"units": summary["units"]["residuals"]}
    candidate = summary.get("candidate")
    if isinstance(candidate, str) and candidate in failures:
        labels.update(parameter=candidate, unit=units.text(candidate) or None, failure=failures[candidate])
    return labels


def vars_of(args) -> dict:
    """The command line's options as settings for a report (what the run was asked)."""
    return {key: value for key, value in sorted(vars(args).items()) if key not in ("quiet", "debug")}


def write_report(out: Path, page) -> Path:
    """``report.html`` in ``out``, written whole (:class:`bgphm.run_report.Page`)."""
    return write_text(out / "report.html", page.html())


def write_plots(kind: str, out: Path, payload, progress: Progress, labels: dict | None = None) -> list[Path]:
    """The PNG plots of a command.  ``labels`` holds what the axes name: ``units`` (ARR name -> the residual's
    unit) and, for prognosis, ``parameter``, ``unit`` and ``failure`` of the reported candidate."""
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only: no window, no display needed
        import matplotlib.pyplot as plt

        from bgphm import plotting
    except ImportError:
        progress("matplotlib is not installed: no plots (pip install 'bondgraph-phm[plot]')")
        return []

    labels = labels or {}
    units = labels.get("units", {})
    paths = []
    evaluations = payload if kind == "detection" else payload[:1]
    for e in evaluations:
        fig, ax = plt.subplots(figsize=(8, 3.5))
        plotting.plot_evaluation(e, ax=ax, title=e.name, unit=units.get(e.name))
        paths.append(plotting.save_figure(fig, out / f"residual_{e.name}.png"))
    result = None if kind == "detection" else payload[1]
    if result is not None and result.t.size:
        fig, ax = plt.subplots(figsize=(8, 3.5))
        plotting.plot_estimate(result, ax=ax, label=labels.get("parameter"), unit=labels.get("unit"),
                               failure=labels.get("failure"), truth=labels.get("truth"))
        paths.append(plotting.save_figure(fig, out / "estimate.png"))
        fig, ax = plt.subplots(figsize=(8, 3.5))
        plotting.plot_rul(result, ax=ax, eol=labels.get("eol"))
        paths.append(plotting.save_figure(fig, out / "rul.png"))
        if result.rul:
            fig, ax = plt.subplots(figsize=(6, 3.5))
            plotting.plot_rul_distribution(result.rul[-1], ax=ax)
            paths.append(plotting.save_figure(fig, out / "rul_distribution.png"))
    return paths
