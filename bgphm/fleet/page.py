"""``index.html`` of a fleet run: an overview page that works offline, for 10^4 assets within 20 MB.

One self-contained file (its style and script inline, no network: a ``Content-Security-Policy`` forbids
any fetch), published with the tables (:mod:`bgphm.fleet.outdir`).  It shows the run (model, records,
settings, date), the counts (assets, alarms, each RUL status, skipped records), a histogram of the first
alarms over time, the ranking (assets by their last lower RUL percentile, p5: the most urgent first;
assets without a RUL after), a table sortable by each column and filterable by text and status, and a
page per asset (``index.html#asset=<id>``): its alarms, the estimate of the reported hypothesis over time
(mean, 5-95 % band, failure value), its RUL over time (median, 5-95 %, horizon) and each ARR's residual
with its threshold band.  The charts are SVG drawn by the page's script from the data embedded in it.

The data (:func:`page_data`, read back by :func:`read_page_data`) is JSON in a ``<script
type="application/json">`` block, ``<``, ``>`` and ``&`` written as ``\\u003c``..., so no text of it (an
asset id with ``</script>``) can end the block; the script puts every text in the page as text (DOM
``textContent``), never as markup.  Numbers of the table are rounded to 4 significant digits; the
charts' series are 12-bit codes (:func:`encode_series`: two characters a value, 1/4092 of the series'
range), what keeps 10^4 assets within :data:`PAGE_BYTES`.  The details of the assets (their charts) are
written in the ranking's order while the page stays within that bound; the assets beyond it keep their
row in the table, and the page says that their charts are in the Parquet tables only.
"""

from __future__ import annotations

import html
import json
import math
import re
from collections.abc import Mapping, Sequence

import numpy as np

from bondgraph.provenance import DISTRIBUTION, generated_at, tool_version

from .page_script import SCRIPT, STYLE

__all__ = ["FORMAT", "LEVELS", "PAGE_BYTES", "SERIES_POINTS", "STATUSES", "decode_series", "encode_series",
           "fleet_page", "page_data", "read_page_data"]

FORMAT = "bgphm fleet page"
VERSION = 1
PAGE_BYTES = 20 * 2**20  # the page's size bound: assets' details in ranking order while it holds
SERIES_POINTS = 120  # points of an estimate or RUL series at most (every k-th row, the last kept)
TIMELINE_BINS = 40  # bars of the histogram of first alarms at most
TIME_DIGITS = 10  # significant digits of the ends of a coded time series
LEVELS = 4093  # the codes 0..4092 of a value; 4093 -inf, 4094 +inf, 4095 no value (NaN)
ALPHABET = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_"  # nothing to escape in JSON or HTML
#: The status of an asset's row besides a RUL decision's (isolated, indistinguishable, undecided, rejected).
STATUSES = {"no_rul": "alarm, no RUL", "healthy": "no alarm", "skipped": "skipped"}
_ORDER = ("isolated", "indistinguishable", "undecided", "rejected", *STATUSES.values())  # of the counts
_LETTERS = np.frombuffer(ALPHABET.encode("ascii"), np.uint8)
_DATA = re.compile(r'<script id="fleet-data" type="application/json">(.*?)</script>', re.S)


# ------------------------------------------------------------------------------------------ numbers

def _number(value) -> float | str | None:
    """A value of the table: 4 significant digits, ``"inf"``/``"-inf"`` for infinities, None for NaN/none."""
    if value is None:
        return None
    value = float(value)
    if math.isnan(value):
        return None
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return float(f"{value:.4g}")


def _exact(value: float, digits: int) -> float:
    """An end of a coded series to ``digits`` significant digits."""
    return float(f"{value:.{digits}g}")


def encode_series(values: Sequence[float], digits: int = 6) -> list:
    """A series for the page's charts, compact: ``[first, last, n]`` if evenly spaced, else ``[low, high, codes]``.

    ``codes`` holds two characters of :data:`ALPHABET` per value: a level ``0..4092`` between ``low`` and
    ``high`` (an error of at most 1/8184 of the range), 4093 for -inf, 4094 for +inf (a censored RUL), 4095
    for no value.  An empty series is ``[]``.  The ends have ``digits`` significant digits: the page codes
    times with 10, so that an absolute time (1.7e9 s) keeps its tenths of a second.

    >>> encode_series([0.0, 0.5, 1.0]), encode_series([])
    ([0.0, 1.0, 3], [])
    >>> coded = encode_series([1.0, 3.0, float("inf"), float("nan"), 2.0])
    >>> coded
    [1.0, 3.0, 'AA_8_-__f-']
    >>> decode_series(coded)
    [1.0, 3.0, inf, nan, 2.0]
    """
    v = np.asarray(values, float).ravel()
    if not v.size:
        return []
    finite = np.isfinite(v)
    if finite.all() and v.size > 1:
        line = np.linspace(v[0], v[-1], v.size)
        spread = max(float(v.max() - v.min()), abs(float(v[0])) * 1e-12)
        if np.max(np.abs(v - line)) <= spread / (2 * (LEVELS - 1)):
            return [_exact(v[0], digits), _exact(v[-1], digits), int(v.size)]
    low, high = (_exact(v[finite].min(), digits), _exact(v[finite].max(), digits)) if finite.any() else (0.0, 0.0)
    scale = (LEVELS - 1) / (high - low) if high > low else 0.0
    with np.errstate(invalid="ignore"):
        level = np.clip(np.rint((v - low) * scale), 0, LEVELS - 1)
    code = np.where(finite, level, np.where(np.isnan(v), 4095, np.where(v > 0, 4094, 4093))).astype(int)
    text = np.empty(2 * code.size, np.uint8)
    text[0::2], text[1::2] = _LETTERS[code >> 6], _LETTERS[code & 63]
    return [low, high, text.tobytes().decode("ascii")]


def decode_series(coded: Sequence) -> list[float]:
    """The values of :func:`encode_series` (what the page's script computes), as floats.

    >>> decode_series([0.0, 1.0, 5])
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    if not coded:
        return []
    low, high, codes = coded
    if isinstance(codes, int):
        return np.linspace(low, high, codes).tolist() if codes > 1 else [float(low)]
    index = {c: i for i, c in enumerate(ALPHABET)}
    out = []
    for k in range(0, len(codes), 2):
        code = index[codes[k]] * 64 + index[codes[k + 1]]
        special = {4093: -math.inf, 4094: math.inf, 4095: math.nan}
        out.append(special[code] if code in special else low + (high - low) * code / (LEVELS - 1))
    return out


def _every(n: int, most: int = SERIES_POINTS) -> np.ndarray:
    """Indices of every k-th of ``n`` rows, k the least that keeps ``most`` of them at most, and the last row."""
    index = np.arange(0, n, max(1, math.ceil(n / most)))
    return index if index[-1] == n - 1 else np.append(index, n - 1)


# ------------------------------------------------------------------------------------------ the data

def _groups(table: Mapping) -> dict[str, np.ndarray]:
    """Asset id -> the indices of its rows, in their order in the table."""
    assets = np.asarray(table["asset"]).astype(str)
    if not assets.size:
        return {}
    order = np.argsort(assets, kind="stable")
    ids, starts = np.unique(assets[order], return_index=True)
    return dict(zip(ids.tolist(), np.split(order, starts[1:])))


def page_data(result, summary: Mapping, *, assets: Sequence[str], units: Mapping, horizon: float | None,
              provenance: Mapping[str, str] | None = None) -> dict:
    """What the page embeds, without the assets' details: header, settings, units, counts, timeline, ranked rows.

    Parameters
    ----------
    result : prognosis.fleet.FleetResult
        The run's tables.
    summary : mapping
        The run's ``summary.json`` (its ``spec``, ``records``, ``skipped``, ``notes``...).
    assets : sequence of str
        Every asset of the run, skipped ones included.
    units : mapping
        The ``units`` block (:func:`bgphm.units.units_of`).
    horizon : float, optional
        The RUL horizon (s) of the monitor.
    provenance : mapping of str to str, optional
        What made the page, shown as it is (``bgphm.run_report.provenance``: the tool's version, the date, the
        model's SHA-256); default: the tool's version and the date (now, or ``SOURCE_DATE_EPOCH``,
        :func:`bondgraph.provenance.generated_at`).

    Returns
    -------
    dict
        ``rows`` in ranking order, each ``[asset, first alarm t, ARRs in alarm, t of the last RUL, p5, p50,
        p95, hypothesis, probability, status]``, and ``counts``, ``timeline``, ``settings``, ``units``...

    Examples
    --------
    >>> from prognosis.fleet import FleetResult
    >>> result = FleetResult()
    >>> result.add("alarms", asset=["a", "b"], t=[1.0, 2.0], arr=["ARR_1", "ARR_1"])
    >>> result.add("rul", asset=["a", "b"], step=[0, 0], t=[1.5, 2.5], mean=[9.0, 2.0], p5=[7.0, 1.0],
    ...            p50=[8.0, 2.0], p95=[np.inf, 3.0], censored=[0.2, 0.0], hypothesis=["R/linear"] * 2,
    ...            probability=[1.0, 1.0], status=["isolated"] * 2)
    >>> data = page_data(result, {"spec": {"model": "rlc"}, "skipped": {"d": "no column 'i'"}},
    ...                  assets=["a", "b", "c", "d"], units={"t": "s"}, horizon=20.0, provenance={"date": "today"})
    >>> [row[0] for row in data["rows"]], [row[-1] for row in data["rows"]]
    (['b', 'a', 'c', 'd'], ['isolated', 'isolated', 'no alarm', 'skipped'])
    >>> data["counts"]["with_alarm"], data["counts"]["status"]["isolated"], data["rows"][1][6]
    (2, 2, 'inf')
    """
    spec = summary.get("spec", {})
    skipped = dict(summary.get("skipped", {}))
    alarms, rul = result.table("alarms"), result.table("rul")
    first = {}
    for asset, t, arr in zip(alarms["asset"].astype(str).tolist(), alarms["t"].tolist(), alarms["arr"].tolist()):
        first.setdefault(asset, [t, []])[1].append(str(arr))
    last = {asset: index[-1] for asset, index in _groups(rul).items()}
    rows = [_row(str(asset), first.get(str(asset)), rul, last.get(str(asset)), str(asset) in skipped)
            for asset in assets]
    rows.sort(key=_urgency)
    found = [row[9] for row in rows]
    statuses = {status: found.count(status) for status in _ORDER if status in found}
    statuses.update({status: found.count(status) for status in sorted(set(found) - set(_ORDER))})
    return {"format": FORMAT, "version": VERSION, "model": str(spec.get("model", "")),
            "records": str(summary.get("records", "")),
            "provenance": {str(k): str(v) for k, v in (provenance or _made()).items()},
            "units": {"t": "s", "rul": "s", **dict(units)}, "horizon": _number(horizon),
            "failures": {str(k): _number(v) for k, v in spec.get("failures", {}).items()},
            # the ARRs in the monitor's order (the units block's), then any other the table holds
            "arrs": list(dict.fromkeys([*units.get("residuals", {}),
                                        *sorted(set(result.table("residuals")["arr"].astype(str).tolist()))])),
            "settings": _settings(summary, units, horizon),
            "counts": {"assets": len(rows), "monitored": len(rows) - len(skipped), "with_alarm": len(first),
                       "with_rul": len(last), "skipped": len(skipped), "status": statuses},
            "timeline": _timeline([t for t, _ in first.values()]),
            "skipped": {str(k): str(v) for k, v in skipped.items()}, "levels": LEVELS, "rows": rows}


def _row(asset: str, alarm, rul: Mapping, last, skipped: bool) -> list:
    alarm_t, arrs = (alarm[0], " ".join(alarm[1])) if alarm else (None, "")
    if last is None:
        status = STATUSES["skipped"] if skipped else STATUSES["no_rul"] if alarm else STATUSES["healthy"]
        return [asset, _number(alarm_t), arrs, None, None, None, None, "", None, status]
    return [asset, _number(alarm_t), arrs, _number(rul["t"][last]), _number(rul["p5"][last]),
            _number(rul["p50"][last]), _number(rul["p95"][last]), str(rul["hypothesis"][last]),
            _number(rul["probability"][last]), str(rul["status"][last])]


def _urgency(row: list) -> tuple:
    """The ranking: a RUL first, by its last p5 (an infinite p5 after the finite ones), then an alarm without a
    RUL, no alarm, skipped; ties by asset id."""
    p5 = row[4]
    if row[3] is not None:
        return (0, math.inf if p5 in ("inf", None) else float(p5), row[0])
    kind = [STATUSES["no_rul"], STATUSES["healthy"], STATUSES["skipped"]].index(row[9])
    return (1 + kind, 0.0, row[0])


def _timeline(times: list) -> dict:
    """A histogram of the first alarms: ``edges`` (s) and ``counts``."""
    t = np.asarray([x for x in times if x is not None and math.isfinite(x)], float)
    if not t.size:
        return {"edges": [], "counts": []}
    low, high = float(t.min()), float(t.max())
    if high <= low:
        low, high = low - 0.5, high + 0.5
    bins = int(min(TIMELINE_BINS, max(1, math.ceil(math.sqrt(t.size)) * 2)))
    counts, edges = np.histogram(t, bins=bins, range=(low, high))
    return {"edges": [_number(e) for e in edges], "counts": counts.tolist()}


def _settings(summary: Mapping, units: Mapping, horizon) -> list[list[str]]:
    """The run's settings as (label, value) texts, each quantity with its unit."""
    spec = summary.get("spec", {})
    parameters, residuals = units.get("parameters", {}), units.get("residuals", {})

    def valued(value, unit: str | None) -> str:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return f"{value:.4g}" + (f" {unit}" if unit else "")
        return str(value)

    failures = ", ".join(f"{p} = {valued(v, parameters.get(p))}" for p, v in spec.get("failures", {}).items())
    noise = ", ".join(f"{a}: {valued(v, residuals.get(a))}" for a, v in spec.get("noise_std", {}).items())
    notes = summary.get("notes", {})
    rows = [["model", str(spec.get("model", ""))], ["records", str(summary.get("records", ""))],
            ["failure values", failures], ["laws", ", ".join(spec.get("laws") or [])],
            ["candidates", ", ".join(spec.get("candidates") or []) or "every parameter with a failure value"],
            ["ARRs", ", ".join(f"{a} ({u})" if u else a for a, u in residuals.items())],
            ["residual noise (std)", noise],
            ["particles per hypothesis", str(spec.get("n_particles", ""))],
            ["filter step dt (s)", str(spec.get("dt", ""))],
            ["RUL every (filter steps)", str(spec.get("rul_every", ""))],
            ["RUL horizon (s)", "" if horizon is None else f"{horizon:g}"],
            ["alarms start nothing before t (s)", str(spec.get("healthy_until", ""))],
            ["seed", str(spec.get("seed", ""))]]
    if notes.get("assets"):
        rows.append(["calibrated on", f"{len(notes['assets'])} record(s), t <= {notes.get('until')} s"])
    if "wall_s" in summary:
        rows.append(["run", f"{summary.get('scheduler', '')}, {summary.get('shards', '')} shard(s), "
                            f"{summary['wall_s']:.1f} s"])
    return rows


def _made() -> dict:
    """The provenance of a page made without a model: the tool's version and the date."""
    return {DISTRIBUTION: tool_version(), "date": generated_at()}


# ------------------------------------------------------------------------------------------ details

def _detail(asset: str, tables: dict, arrs: list) -> dict:
    """The charts' data of one asset: alarms, the reported hypothesis' estimate, the RUL, the residual traces.

    ``tables``: name -> (table, indices of this asset's rows).  Keys are short (10^4 of them on a page):
    ``a`` the alarms ``[[t, arr], ...]``; ``h`` the hypothesis reported last; ``e`` its estimate ``[t, mean
    + p5 + p95]``; ``r`` the RUL ``[t, p5 + p50 + p95]``; ``x`` the residuals ``[t, [low + high + band_low +
    band_high, or None, per ARR of the page]]``.  The series of one chart are coded together (``+``: one after
    the other, on the chart's scale: :func:`encode_series`), the times apart.
    """
    out = {}
    alarms, index = tables["alarms"]
    if index is not None:
        out["a"] = [[_number(alarms["t"][i]), str(alarms["arr"][i])] for i in index]
    rul, index = tables["rul"]
    if index is not None:
        named = [str(h) for h in rul["hypothesis"][index] if str(h)]
        out["h"] = named[-1] if named else ""
        keep = index[_every(index.size)]
        out["r"] = _chart(rul, keep, ("p5", "p50", "p95"))
        estimates, rows = tables["estimates"]
        if out["h"] and rows is not None:
            mine = rows[np.asarray(estimates["hypothesis"][rows]).astype(str) == out["h"]]
            if mine.size:
                out["e"] = _chart(estimates, mine[_every(mine.size)], ("theta_mean", "theta_p5", "theta_p95"))
    residuals, index = tables["residuals"]
    if index is not None:
        names = np.asarray(residuals["arr"][index]).astype(str)
        traces, t = [], None
        for arr in arrs:
            mine = index[names == arr]
            t = residuals["t"][mine] if t is None and mine.size else t
            traces.append(_chart(residuals, mine, ("low", "high", "band_low", "band_high"))[1] if mine.size else None)
        if t is not None:
            out["x"] = [encode_series(t, TIME_DIGITS), traces]
    return out


def _chart(table: Mapping, rows: np.ndarray, columns: Sequence[str]) -> list:
    """``[t, the columns one after the other]`` of ``rows``, coded: a chart's series on one scale."""
    return [encode_series(table["t"][rows], TIME_DIGITS),
            encode_series(np.concatenate([table[c][rows] for c in columns]))]


# ------------------------------------------------------------------------------------------ the page

def _json(value) -> str:
    """JSON that can sit in an HTML ``<script>`` data block: no ``<``, ``>`` or ``&`` (nor U+2028/9) as such."""
    text = json.dumps(value, ensure_ascii=True, separators=(",", ":"), allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def fleet_page(result, summary: Mapping, *, assets: Sequence[str], units: Mapping, horizon: float | None = None,
               budget: int = PAGE_BYTES, provenance: Mapping[str, str] | None = None) -> str:
    """The text of ``index.html`` for a fleet run's tables (see the module's docstring).

    Parameters
    ----------
    result : prognosis.fleet.FleetResult
    summary : mapping
        The run's ``summary.json``.
    assets : sequence of str
        Every asset of the run, skipped ones included.
    units : mapping
        The ``units`` block (:func:`bgphm.units.units_of`).
    horizon : float, optional
        The monitor's RUL horizon (s), marked on the RUL charts.
    budget : int
        The page's size bound in bytes: the assets' details go in ranking order while the page holds
        within it (the overview itself always goes in).
    provenance : mapping of str to str, optional
        What made the page (see :func:`page_data`).

    Examples
    --------
    >>> from prognosis.fleet import FleetResult
    >>> result = FleetResult()
    >>> result.add("alarms", asset=["</script><b>x"], t=[1.0], arr=["ARR_1"])
    >>> text = fleet_page(result, {"spec": {"model": "rlc"}}, assets=["</script><b>x"], units={"t": "s"})
    >>> text.count("</script>"), read_page_data(text)["rows"][0][0]
    (2, '</script><b>x')
    """
    data = page_data(result, summary, assets=assets, units=units, horizon=horizon, provenance=provenance)
    tables = {name: result.table(name) for name in ("alarms", "estimates", "rul", "residuals")}
    groups = {name: _groups(table) for name, table in tables.items()}
    head = _head(str(data["model"]))
    tail = "</script>\n<script>" + SCRIPT + "</script>\n</body>\n</html>\n"
    overview = _json({**data, "details": None})
    used = sum(len(part.encode("utf-8")) for part in (head, overview, tail)) + 16  # 16: the "kept" count
    details, full = [], False
    for row in data["rows"]:
        asset = row[0]
        piece = "null"
        if not full and row[9] != STATUSES["skipped"]:
            piece = _json(_detail(asset, {name: (tables[name], groups[name].get(asset)) for name in tables},
                                  data["arrs"]))
            # the details are ASCII (ensure_ascii): characters are bytes.  Once one does not fit, none after it
            # goes in: the charts on the page are those of the most urgent assets, a prefix of the ranking
            full = used + len(piece) + 1 + 5 * (len(data["rows"]) - len(details)) > budget
            piece = "null" if full else piece
        details.append(piece)
        used += len(piece) + 1
    kept = sum(piece != "null" for piece in details)
    body = overview[:-len('"details":null}')] + f'"kept":{kept},"details":[' + ",".join(details) + "]}"
    return head + body + tail


def _head(model: str) -> str:
    title = html.escape(f"Fleet overview: {model}")
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            # offline by construction: the page may load nothing, from anywhere
            "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; script-src 'unsafe-inline'; "
            "style-src 'unsafe-inline'; img-src data:\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n"
            "<noscript><p>This page draws its tables and charts with JavaScript: allow scripts for this file "
            "(nothing is fetched from the network).</p></noscript>\n"
            "<div id=\"app\"></div>\n<script id=\"fleet-data\" type=\"application/json\">")


def read_page_data(text: str) -> dict:
    """The data a page embeds (:func:`fleet_page`), details included, as the page's script reads it.

    >>> from prognosis.fleet import FleetResult
    >>> data = read_page_data(fleet_page(FleetResult(), {"spec": {}}, assets=["a"], units={}))
    >>> data["rows"], data["details"]
    ([['a', None, '', None, None, None, None, '', None, 'no alarm']], [{}])
    """
    match = _DATA.search(text)
    if match is None:
        raise ValueError("not a fleet page: no fleet-data block")
    return json.loads(match.group(1))
