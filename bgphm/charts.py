"""Line charts as inline SVG text, for the run reports: no plotting library, no script, nothing fetched.

A :class:`Chart` gathers what it draws (lines, bands, horizontal and vertical markers) and :meth:`Chart.svg`
writes one ``<svg>`` element: axes with round ticks, the axis labels (the quantity and its unit), a title and a
legend.  Every text is escaped; numbers are written with 4 significant digits.  A line of more points than the
chart has pixels is thinned to the minimum and maximum of each pixel column, so its envelope is kept and the
page stays small.  Non-finite values break a line (a gap, not a drop to zero).

Example
-------
>>> chart = Chart("ARR_1_m", x_label="t (s)", y_label="-r_n (N*m)")
>>> chart.band([0.0, 1.0, 2.0], [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], label="threshold")
>>> chart.line([0.0, 1.0, 2.0], [0.1, -0.2, 1.5], label="-r_n")
>>> chart.vline(1.8, label="alarm at 1.8 s")
>>> svg = chart.svg()
>>> svg.startswith("<svg") and "-r_n (N*m)" in svg and "alarm at 1.8 s" in svg
True
"""

from __future__ import annotations

import html
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Chart", "nice_ticks"]

#: The colours of successive lines (colour-blind safe), then of bands (the same, lighter).
PALETTE = ("#0072b2", "#d55e00", "#009e73", "#cc79a7", "#e69f00", "#56b4e9", "#000000")


def nice_ticks(low: float, high: float, count: int = 5) -> list[float]:
    """About ``count`` round tick values (1, 2 or 5 times a power of ten apart) covering ``[low, high]``.

    >>> nice_ticks(0.0, 1.0), nice_ticks(-3.2, 7.9, 4)
    ([0.0, 0.2, 0.4, 0.6, 0.8, 1.0], [-5.0, 0.0, 5.0, 10.0])
    """
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low:
        return [low] if math.isfinite(low) else []
    raw = (high - low) / max(count, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 5, 10) if m * power >= raw)
    first = math.floor(low / step + 1e-9) * step
    ticks, value = [], first
    while value < high + step * (1 - 1e-9):
        ticks.append(round(value, 12) + 0.0)  # + 0.0: no "-0"
        value += step
    return ticks


def _number(value: float) -> str:
    return f"{value:.4g}"


@dataclass
class _Item:
    kind: str            # "line", "band", "hline", "vline", "points"
    x: np.ndarray
    y: np.ndarray
    y2: np.ndarray | None
    label: str
    style: str           # "solid", "dashed", "dotted"
    colour: str


@dataclass
class Chart:
    """A line chart to be written as SVG; see the module's example.

    ``width`` and ``height`` are in CSS pixels (the SVG scales to its container's width, keeping its ratio).
    """

    title: str
    x_label: str = "t (s)"
    y_label: str = ""
    width: int = 760
    height: int = 300
    items: list = field(default_factory=list)

    def _colour(self, colour: str | None) -> str:
        if colour is not None:
            return colour
        used = sum(item.kind in ("line", "points") for item in self.items)
        return PALETTE[used % len(PALETTE)]

    def line(self, x: ArrayLike, y: ArrayLike, *, label: str = "", style: str = "solid",
             colour: str | None = None) -> None:
        """A line through ``(x, y)``; NaN or infinite values leave a gap."""
        self.items.append(_Item("line", _array(x), _array(y), None, label, style, self._colour(colour)))

    def points(self, x: ArrayLike, y: ArrayLike, *, label: str = "", colour: str | None = None) -> None:
        """Markers at ``(x, y)``."""
        self.items.append(_Item("points", _array(x), _array(y), None, label, "solid", self._colour(colour)))

    def band(self, x: ArrayLike, lower: ArrayLike, upper: ArrayLike, *, label: str = "",
             colour: str | None = None) -> None:
        """The area between ``lower`` and ``upper`` (a threshold, a percentile band), drawn under the lines."""
        colour = colour or PALETTE[sum(item.kind == "band" for item in self.items) % len(PALETTE)]
        self.items.append(_Item("band", _array(x), _array(lower), _array(upper), label, "solid", colour))

    def hline(self, y: float, *, label: str = "", style: str = "dashed", colour: str = "#b00000") -> None:
        """A horizontal line across the chart (a failure value, a horizon)."""
        self.items.append(_Item("hline", np.empty(0), np.array([float(y)]), None, label, style, colour))

    def vline(self, x: float, *, label: str = "", style: str = "dotted", colour: str = "#000000") -> None:
        """A vertical line (an alarm, the calibration's end)."""
        self.items.append(_Item("vline", np.array([float(x)]), np.empty(0), None, label, style, colour))

    # ------------------------------------------------------------------------------------------- writing

    def svg(self) -> str:
        """The chart as one ``<svg>`` element (text)."""
        left, right, top, bottom = 78, 16, 30, 46
        plot_w, plot_h = self.width - left - right, self.height - top - bottom
        (x0, x1), (y0, y1) = self._limits()
        x_ticks, y_ticks = nice_ticks(x0, x1, 6), nice_ticks(y0, y1, 5)
        if x_ticks:
            x0, x1 = min(x0, x_ticks[0]), max(x1, x_ticks[-1])
        if y_ticks:
            y0, y1 = min(y0, y_ticks[0]), max(y1, y_ticks[-1])

        def px(x):
            return left + (np.asarray(x, float) - x0) / (x1 - x0) * plot_w

        def py(y):
            return top + (y1 - np.asarray(y, float)) / (y1 - y0) * plot_h

        parts = [f'<svg xmlns="http://www.w3.org/2000/svg" class="chart" viewBox="0 0 {self.width} {self.height}" '
                 f'role="img" aria-label="{_escape(self.title)}">',
                 f'<text class="chart-title" x="{left}" y="18">{_escape(self.title)}</text>',
                 f'<rect class="plot-area" x="{left}" y="{top}" width="{plot_w}" height="{plot_h}" fill="none" '
                 'stroke="#999"/>']
        parts += _grid(x_ticks, y_ticks, px, py, left, top, plot_w, plot_h)
        clip = f"clip{abs(hash((self.title, self.y_label, len(self.items)))) % 10**8}"
        parts.append(f'<clipPath id="{clip}"><rect x="{left}" y="{top}" width="{plot_w}" height="{plot_h}"/>'
                     '</clipPath>')
        body = []
        for item in sorted(self.items, key=lambda i: i.kind != "band"):  # bands under everything
            body.append(_draw(item, px, py, left, top, plot_w, plot_h))
        parts.append(f'<g clip-path="url(#{clip})">' + "".join(body) + "</g>")
        parts.append(f'<text class="axis-label x-label" x="{left + plot_w / 2:.1f}" y="{self.height - 8}" '
                     f'text-anchor="middle">{_escape(self.x_label)}</text>')
        parts.append(f'<text class="axis-label y-label" x="14" y="{top + plot_h / 2:.1f}" text-anchor="middle" '
                     f'transform="rotate(-90 14 {top + plot_h / 2:.1f})">{_escape(self.y_label)}</text>')
        parts += _legend([i for i in self.items if i.label], left + plot_w - 6, top + 6)
        parts.append("</svg>")
        return "".join(parts)

    def _limits(self) -> tuple[tuple[float, float], tuple[float, float]]:
        xs = [i.x for i in self.items if i.kind != "hline"]
        ys = [i.y for i in self.items if i.kind != "vline"] + [i.y2 for i in self.items if i.y2 is not None]
        return _span(xs), _span(ys, pad=0.05)


def _array(values: ArrayLike) -> np.ndarray:
    return np.asarray(values, dtype=float).ravel()


def _span(arrays: list, pad: float = 0.0) -> tuple[float, float]:
    finite = np.concatenate([a[np.isfinite(a)] for a in arrays]) if arrays else np.empty(0)
    if not finite.size:
        return 0.0, 1.0
    low, high = float(finite.min()), float(finite.max())
    if high == low:
        spread = abs(low) * 0.1 or 1.0
        return low - spread, high + spread
    margin = (high - low) * pad
    return low - margin, high + margin


def _escape(text: str) -> str:
    return html.escape(str(text), quote=True)


def _grid(x_ticks, y_ticks, px, py, left, top, plot_w, plot_h) -> list[str]:
    parts = []
    for value in x_ticks:
        x = float(px(value))
        if left - 0.5 <= x <= left + plot_w + 0.5:
            parts.append(f'<line class="grid" x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + plot_h}" '
                         'stroke="#e5e5e5"/>'
                         f'<text class="tick" x="{x:.1f}" y="{top + plot_h + 16}" text-anchor="middle">'
                         f'{_number(value)}</text>')
    for value in y_ticks:
        y = float(py(value))
        if top - 0.5 <= y <= top + plot_h + 0.5:
            parts.append(f'<line class="grid" x1="{left}" y1="{y:.1f}" x2="{left + plot_w}" y2="{y:.1f}" '
                         'stroke="#e5e5e5"/>'
                         f'<text class="tick" x="{left - 6}" y="{y + 4:.1f}" text-anchor="end">{_number(value)}</text>')
    return parts


_DASH = {"solid": "", "dashed": ' stroke-dasharray="6 4"', "dotted": ' stroke-dasharray="2 3"'}


def _draw(item: _Item, px, py, left, top, plot_w, plot_h) -> str:
    title = f"<title>{_escape(item.label)}</title>" if item.label else ""
    if item.kind == "hline":
        y = float(py(item.y[0]))
        return (f'<line x1="{left}" y1="{y:.1f}" x2="{left + plot_w}" y2="{y:.1f}" stroke="{item.colour}" '
                f'stroke-width="1.2"{_DASH[item.style]}>{title}</line>')
    if item.kind == "vline":
        x = float(px(item.x[0]))
        return (f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + plot_h}" stroke="{item.colour}" '
                f'stroke-width="1.2"{_DASH[item.style]}>{title}</line>')
    if item.kind == "points":
        keep = np.isfinite(item.x) & np.isfinite(item.y)
        dots = "".join(f'<circle cx="{a:.1f}" cy="{b:.1f}" r="3"/>' for a, b in zip(px(item.x[keep]), py(item.y[keep])))
        return f'<g class="points" fill="{item.colour}">{title}{dots}</g>'
    if item.kind == "band":
        paths = []
        for run in _runs(item.x, item.y, item.y2):
            x, lo, hi = _thin(run[0], run[1], run[2], plot_w)
            upper = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px(x), py(hi)))
            lower = " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px(x[::-1]), py(lo[::-1])))
            paths.append(f'<polygon points="{upper} {lower}"/>')
        return f'<g class="band" fill="{item.colour}" fill-opacity="0.18" stroke="none">{title}{"".join(paths)}</g>'
    lines = []
    for run in _runs(item.x, item.y):
        x, y, _ = _thin(run[0], run[1], None, plot_w)
        lines.append('<polyline points="' + " ".join(f"{a:.1f},{b:.1f}" for a, b in zip(px(x), py(y))) + '"/>')
    return (f'<g class="line" fill="none" stroke="{item.colour}" stroke-width="1.4"{_DASH[item.style]}>'
            f'{title}{"".join(lines)}</g>')


def _runs(x: np.ndarray, y: np.ndarray, y2: np.ndarray | None = None) -> list[tuple]:
    """The stretches where every value is finite, each as (x, y, y2)."""
    finite = np.isfinite(x) & np.isfinite(y) & (np.isfinite(y2) if y2 is not None else True)
    runs, start = [], None
    for k, ok in enumerate(np.append(finite, False)):
        if ok and start is None:
            start = k
        elif not ok and start is not None:
            runs.append((x[start:k], y[start:k], None if y2 is None else y2[start:k]))
            start = None
    return runs


def _thin(x: np.ndarray, y: np.ndarray, y2: np.ndarray | None, columns: float) -> tuple:
    """At most two points per pixel column: the lowest and the highest (an envelope the eye cannot tell apart)."""
    buckets = int(columns)
    if x.size <= 2 * buckets:
        return x, y, y2
    edges = np.linspace(0, x.size, buckets + 1).astype(int)
    keep = []
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        chunk = y[a:b] if y2 is None else y2[a:b]
        low, high = a + int(np.argmin(y[a:b])), a + int(np.argmax(chunk))
        keep += sorted({low, high})
    index = np.array(keep)
    return x[index], y[index], None if y2 is None else y2[index]


def _legend(items: list, right: float, top: float) -> list[str]:
    if not items:
        return []
    width = 12 + 7 * max(len(i.label) for i in items)
    parts = [f'<g class="legend"><rect x="{right - width - 8:.1f}" y="{top}" width="{width + 8}" '
             f'height="{16 * len(items) + 6}" fill="#fff" fill-opacity="0.85" stroke="#ccc"/>']
    for k, item in enumerate(items):
        y = top + 14 + 16 * k
        x = right - width
        if item.kind == "band":
            mark = (f'<rect x="{x:.1f}" y="{y - 8}" width="14" height="9" fill="{item.colour}" '
                    'fill-opacity="0.3"/>')
        elif item.kind == "points":
            mark = f'<circle cx="{x + 7:.1f}" cy="{y - 4}" r="3" fill="{item.colour}"/>'
        else:
            mark = (f'<line x1="{x:.1f}" y1="{y - 4}" x2="{x + 14:.1f}" y2="{y - 4}" stroke="{item.colour}" '
                    f'stroke-width="1.6"{_DASH[item.style]}/>')
        parts.append(f'{mark}<text class="legend-label" x="{x + 20:.1f}" y="{y}">{_escape(item.label)}</text>')
    parts.append("</g>")
    return parts
