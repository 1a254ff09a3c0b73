"""What the commands write: --out checked first, text to stdout or a file, JSON values, plots."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from bgphm.files import check_output, input_files, write_text

from ._progress import Progress

__all__ = ["emit", "finite_or_none", "fmt", "json_value", "output_directory", "output_file", "write_plots"]


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


def write_plots(kind: str, out: Path, payload, progress: Progress) -> list[Path]:
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only: no window, no display needed
        import matplotlib.pyplot as plt

        from bgphm import plotting
    except ImportError:
        progress("matplotlib is not installed: no plots (pip install 'bondgraph-phm[plot]')")
        return []

    paths = []
    if kind == "detection":
        for e in payload:
            fig, ax = plt.subplots(figsize=(8, 3.5))
            plotting.plot_evaluation(e, ax=ax, title=e.name)
            paths.append(plotting.save_figure(fig, out / f"residual_{e.name}.png"))
    else:
        evaluation, result = payload
        fig, ax = plt.subplots(figsize=(8, 3.5))
        plotting.plot_evaluation(evaluation, ax=ax, title=evaluation.name)
        paths.append(plotting.save_figure(fig, out / f"residual_{evaluation.name}.png"))
        if result is not None and result.t.size:
            fig, ax = plt.subplots(figsize=(8, 3.5))
            plotting.plot_estimate(result, ax=ax)
            paths.append(plotting.save_figure(fig, out / "estimate.png"))
            fig, ax = plt.subplots(figsize=(8, 3.5))
            plotting.plot_rul(result, ax=ax)
            paths.append(plotting.save_figure(fig, out / "rul.png"))
            if result.rul:
                fig, ax = plt.subplots(figsize=(6, 3.5))
                plotting.plot_rul_distribution(result.rul[-1], ax=ax)
                paths.append(plotting.save_figure(fig, out / "rul_distribution.png"))
    return paths
