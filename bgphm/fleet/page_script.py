"""The style and the script of the fleet page (:mod:`bgphm.fleet.page`), inlined into ``index.html``.

The script reads the page's data block (JSON), builds the overview and each asset's page in the DOM (every
text as a text node or an attribute value, never parsed as markup) and draws the charts as SVG; the URL
fragment selects the view (``#asset=<id>``, the id URI-encoded), so the browser's back button goes back
to the overview.  It uses nothing outside the page.

>>> "</script" in SCRIPT.lower(), "http:" in STYLE + SCRIPT.replace("http://www.w3.org/2000/svg", "")
(False, False)
"""

from __future__ import annotations

__all__ = ["SCRIPT", "STYLE"]

STYLE = """
:root { --ink: #1f2328; --muted: #59636e; --line: #d0d7de; --soft: #f6f8fa; --accent: #0b5cad; }
* { box-sizing: border-box; }
body { margin: 0; font: 15px/1.45 system-ui, -apple-system, "Segoe UI", "DejaVu Sans", sans-serif; color: var(--ink);
  background: #fff; }
main { max-width: 1320px; margin: 0 auto; padding: 18px 24px 48px; }
h1 { font-size: 24px; margin: 4px 0 6px; }
h2 { font-size: 18px; margin: 0 0 10px; }
a { color: var(--accent); }
.meta, .note { color: var(--muted); margin: 4px 0 10px; }
.provenance { color: var(--muted); font-size: 13px; margin: 0 0 8px; overflow-wrap: anywhere; }
.provenance code { font-size: 12px; }
.panel { border: 1px solid var(--line); border-radius: 8px; padding: 14px 16px; margin: 16px 0; }
details.settings { margin: 8px 0 4px; }
details.settings summary { cursor: pointer; color: var(--accent); }
table { border-collapse: collapse; }
.kv td { padding: 2px 14px 2px 0; vertical-align: top; }
.kv td:first-child { color: var(--muted); white-space: nowrap; }
.cards { display: flex; flex-wrap: wrap; gap: 10px; margin: 14px 0; }
.card { border: 1px solid var(--line); border-radius: 8px; padding: 8px 14px; min-width: 120px;
  background: var(--soft); }
.card .value { display: block; font-size: 22px; font-weight: 650; }
.card .name { color: var(--muted); font-size: 13px; }
.controls { display: flex; flex-wrap: wrap; gap: 10px; align-items: center; margin-bottom: 10px; }
.controls input, .controls select { font: inherit; padding: 5px 8px; border: 1px solid var(--line);
  border-radius: 6px; }
.controls input { width: 340px; max-width: 100%; }
.table-wrap { overflow-x: auto; max-height: 70vh; overflow-y: auto; border: 1px solid var(--line); border-radius: 6px; }
#assets { width: 100%; font-size: 14px; }
#assets th, #assets td { padding: 5px 8px; border-bottom: 1px solid var(--line); text-align: left;
  white-space: nowrap; }
#assets th { white-space: normal; vertical-align: bottom; }
#assets th { position: sticky; top: 0; background: var(--soft); z-index: 1; }
#assets th button { font: inherit; font-weight: 600; border: 0; background: none; cursor: pointer; padding: 0;
  color: var(--ink); }
#assets th[aria-sort="ascending"] button::after { content: " \\25B2"; font-size: 10px; }
#assets th[aria-sort="descending"] button::after { content: " \\25BC"; font-size: 10px; }
#assets td.num, #assets th.num { text-align: right; font-variant-numeric: tabular-nums; }
#assets td.asset { max-width: 260px; overflow: hidden; text-overflow: ellipsis; }
#assets tbody tr:hover { background: #f0f6fc; }
.status { display: inline-block; padding: 0 8px; border-radius: 10px; font-size: 12.5px; background: #eaeef2; }
.status-isolated { background: #ffd8d3; }
.status-indistinguishable { background: #ffe8bf; }
.status-undecided { background: #fff3c4; }
.status-rejected { background: #e4dcf5; }
.status-no-alarm { background: #dcf2e3; }
button.more { margin-top: 10px; font: inherit; padding: 5px 12px; border: 1px solid var(--line); border-radius: 6px;
  background: var(--soft); cursor: pointer; }
.facts { display: grid; grid-template-columns: max-content auto; gap: 2px 16px; margin: 10px 0 14px; }
.facts dt { color: var(--muted); }
.facts dd { margin: 0; }
.alarms td, .alarms th { padding: 3px 14px 3px 0; text-align: left; }
.charts { display: grid; grid-template-columns: repeat(auto-fill, minmax(600px, 1fr)); gap: 16px; }
figure.chart { margin: 0; border: 1px solid var(--line); border-radius: 8px; padding: 10px 12px 6px; }
figure.chart figcaption { font-weight: 600; margin-bottom: 4px; }
svg.plot { width: 100%; height: auto; display: block; }
svg.plot text { font: 12px system-ui, "DejaVu Sans", sans-serif; fill: #333; }
svg.plot text.axis-label { font-size: 13px; font-weight: 600; fill: var(--ink); }
svg.plot .grid line { stroke: #e6e9ec; }
svg.plot .axis { stroke: #57606a; }
svg.plot .band-estimate { fill: #4c78a8; fill-opacity: 0.25; }
svg.plot .line-estimate { stroke: #1f4e8c; fill: none; stroke-width: 2; }
svg.plot .band-rul { fill: #f58518; fill-opacity: 0.25; }
svg.plot .line-rul { stroke: #b35806; fill: none; stroke-width: 2; }
svg.plot .band-threshold { fill: #e45756; fill-opacity: 0.16; }
svg.plot .band-residual { fill: #1f4e8c; fill-opacity: 0.55; }
svg.plot .bars { fill: #4c78a8; }
svg.plot .failure, svg.plot .horizon { stroke: #c0392b; stroke-dasharray: 6 4; stroke-width: 1.5; }
svg.plot .alarm { stroke: #222; stroke-dasharray: 2 3; stroke-width: 1.3; }
svg.plot .mark { fill: #c0392b; }
svg.plot .rank-bar { fill: #f58518; fill-opacity: 0.45; }
svg.plot .rank-median { fill: #b35806; }
svg.plot a text { fill: var(--accent); text-decoration: underline; }
.legend { display: flex; flex-wrap: wrap; gap: 14px; font-size: 12.5px; color: var(--muted); margin: 2px 0 4px; }
.legend i { display: inline-block; width: 18px; height: 10px; margin-right: 5px; vertical-align: middle; }
.legend i.band-estimate { background: rgba(76, 120, 168, 0.35); }
.legend i.line-estimate { background: #1f4e8c; height: 3px; }
.legend i.band-rul { background: rgba(245, 133, 24, 0.35); }
.legend i.line-rul { background: #b35806; height: 3px; }
.legend i.band-threshold { background: rgba(228, 87, 86, 0.25); }
.legend i.band-residual { background: rgba(31, 78, 140, 0.6); }
.legend i.failure, .legend i.horizon { border-top: 2px dashed #c0392b; height: 0; }
.legend i.alarm { border-top: 2px dotted #222; height: 0; }
"""

SCRIPT = r"""
(function () {
"use strict";
const DATA = JSON.parse(document.getElementById("fleet-data").textContent);
const SVGNS = "http://www.w3.org/2000/svg";
const ALPHABET = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_";
const CODE = {};
for (let i = 0; i < ALPHABET.length; i++) CODE[ALPHABET[i]] = i;
const LEVELS = DATA.levels;
const PAGE_ROWS = 100;  // table rows drawn at a time: 10^4 rows in the DOM would make every sort slow
const RANKED = 20;      // assets in the ranking chart
const U = DATA.units || {};
// a key of the data, never one of every object's (an asset named "constructor" is not skipped)
const own = (object, key) => (object && Object.prototype.hasOwnProperty.call(object, key) ? object[key] : undefined);
const unitOf = (kind, name) => own(own(U, kind), name) || "";
const label = (name, unit) => (unit ? name + " (" + unit + ")" : name);
const MINUS_R = "\u2212r\u2099";  // -r_n, typeset

// ---------------------------------------------------------------------------------------- DOM and numbers
function build(make, tag, attrs, children) {
  const e = make(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (v !== undefined && v !== null && v !== false) e.setAttribute(k, String(v));
  }
  for (const c of [].concat(children === undefined ? [] : children)) {
    if (c !== null && c !== undefined) e.append(c instanceof Node ? c : String(c));  // a string is a text node
  }
  return e;
}
const h = (tag, attrs, children) => build((t) => document.createElement(t), tag, attrs, children);
const s = (tag, attrs, children) => build((t) => document.createElementNS(SVGNS, t), tag, attrs, children);
const num = (v) => (v === "inf" ? Infinity : v === "-inf" ? -Infinity : v === null || v === undefined ? NaN : v);
const finite = (v) => typeof v === "number" && Number.isFinite(v);

function fmt(v) {
  if (typeof v !== "number" || Number.isNaN(v)) return "\u2013";
  if (v === Infinity) return "\u221e";
  if (v === -Infinity) return "\u2212\u221e";
  if (v === 0) return "0";
  const a = Math.abs(v);
  const text = a >= 1e-3 && a < 1e6 ? String(Number(v.toPrecision(4))) : v.toExponential(3).replace(/\.?0+e/, "e");
  return text.replace("-", "\u2212");
}

function decode(series) {
  if (!series || !series.length) return [];
  const [lo, hi, codes] = series;
  const out = [];
  if (typeof codes === "number") {
    for (let k = 0; k < codes; k++) out.push(codes > 1 ? lo + (hi - lo) * k / (codes - 1) : lo);
    return out;
  }
  for (let k = 0; k < codes.length; k += 2) {
    const q = CODE[codes[k]] * 64 + CODE[codes[k + 1]];
    out.push(q === 4095 ? NaN : q === 4094 ? Infinity : q === 4093 ? -Infinity : lo + (hi - lo) * q / (LEVELS - 1));
  }
  return out;
}

function parts(coded, count) {  // the series of one chart, coded one after the other
  const values = decode(coded), n = values.length / count;
  return Array.from({length: count}, (_, i) => values.slice(i * n, (i + 1) * n));
}

const assetHref = (id) => "#asset=" + encodeURIComponent(id);
const slug = (text) => String(text).toLowerCase().replace(/[^a-z0-9]+/g, "-").replace(/^-|-$/g, "");

// ---------------------------------------------------------------------------------------- the rows
const ROWS = DATA.rows.map((r, i) => ({
  rank: i + 1, asset: r[0], alarm: num(r[1]), arrs: r[2], t: num(r[3]), p5: num(r[4]), p50: num(r[5]),
  p95: num(r[6]), hypothesis: r[7], probability: num(r[8]), status: r[9], detail: DATA.details[i]}));
const BY_ID = new Map(ROWS.map((r) => [r.asset, r]));
const COLUMNS = [
  {key: "rank", title: "rank", numeric: true},
  {key: "asset", title: "asset"},
  {key: "alarm", title: label("first alarm at t", U.t), numeric: true},
  {key: "arrs", title: "ARRs in alarm"},
  {key: "t", title: label("last RUL at t", U.t), numeric: true},
  {key: "p5", title: label("RUL p5", U.rul), numeric: true},
  {key: "p50", title: label("RUL p50", U.rul), numeric: true},
  {key: "p95", title: label("RUL p95", U.rul), numeric: true},
  {key: "hypothesis", title: "hypothesis"},
  {key: "probability", title: "probability", numeric: true},
  {key: "status", title: "status"},
];

// ---------------------------------------------------------------------------------------- charts
function ticks(a, b, n) {
  const span = b - a;
  if (!(span > 0)) return [a];
  const raw = span / n;
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const f = raw / mag;
  const step = (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * mag;
  const out = [];
  for (let k = Math.ceil(a / step - 1e-9); k * step <= b + step * 1e-9; k++) {
    out.push(Number((k * step).toPrecision(12)));
  }
  return out;
}

function extent(values, zero) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values) if (finite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (zero && lo > 0) lo = 0;
  if (lo === Infinity) return null;
  if (hi === lo) { const d = Math.abs(lo) * 0.1 || 0.5; lo -= d; hi += d; }
  return [lo, hi];
}

function runs(n, ok) {  // [start, stop) of each run of consecutive indices where ok(i)
  const out = [];
  let start = -1;
  for (let i = 0; i <= n; i++) {
    if (i < n && ok(i)) { if (start < 0) start = i; } else if (start >= 0) { out.push([start, i]); start = -1; }
  }
  return out;
}

let clipCount = 0;
function chart(o) {
  const W = o.width || 620, H = o.height || 270, L = 78, R = 22, T = 22, B = 50;
  const xs = [], ys = [];
  for (const layer of o.layers) {
    for (const v of layer.x) xs.push(v);
    for (const key of ["y", "lo", "hi"]) if (layer[key]) for (const v of layer[key]) ys.push(v);
    if (layer.counts) { for (const v of layer.counts) ys.push(v); ys.push(0); }
  }
  for (const line of o.hlines || []) ys.push(line.y);
  const figure = h("figure", {class: "chart", "data-kind": o.kind}, h("figcaption", {}, o.title));
  const xr = extent(xs), yr = extent(ys, o.yzero);
  if (!xr || !yr) { figure.append(h("p", {class: "note"}, "No values to draw.")); return figure; }
  const pad = (yr[1] - yr[0]) * 0.06;
  const [x0, x1] = xr, y0 = o.yzero && yr[0] >= 0 ? yr[0] : yr[0] - pad, y1 = yr[1] + pad;
  const sx = (x) => L + (x - x0) / (x1 - x0) * (W - L - R);
  const sy = (y) => H - B - (y - y0) / (y1 - y0) * (H - T - B);
  const clip = "clip-" + (++clipCount);
  const root = s("svg", {class: "plot", viewBox: "0 0 " + W + " " + H, role: "img", "aria-label": o.title,
                         style: "max-width: " + W + "px"});  // text at its size, not blown up to the page's width
  root.append(s("defs", {}, s("clipPath", {id: clip}, s("rect", {x: L, y: T, width: W - L - R, height: H - T - B}))));
  const grid = s("g", {class: "grid"});
  for (const v of ticks(x0, x1, 7)) {
    grid.append(s("line", {x1: sx(v), x2: sx(v), y1: T, y2: H - B}));
    root.append(s("text", {class: "tick x-tick", x: sx(v), y: H - B + 16, "text-anchor": "middle"}, fmt(v)));
  }
  for (const v of ticks(y0, y1, 5)) {
    grid.append(s("line", {x1: L, x2: W - R, y1: sy(v), y2: sy(v)}));
    root.append(s("text", {class: "tick y-tick", x: L - 6, y: sy(v) + 4, "text-anchor": "end"}, fmt(v)));
  }
  root.insertBefore(grid, root.children[1]);
  const plot = s("g", {"clip-path": "url(#" + clip + ")"});
  for (const layer of o.layers) plot.append(drawLayer(layer, sx, sy));
  for (const line of o.hlines || []) {
    if (!finite(line.y)) continue;
    plot.append(s("line", {class: line.cls, x1: L, x2: W - R, y1: sy(line.y), y2: sy(line.y)}));
  }
  for (const line of o.vlines || []) {
    if (!finite(line.x)) continue;
    plot.append(s("line", {class: line.cls, x1: sx(line.x), x2: sx(line.x), y1: T, y2: H - B}));
  }
  root.append(plot);
  root.append(s("line", {class: "axis", x1: L, x2: W - R, y1: H - B, y2: H - B}));
  root.append(s("line", {class: "axis", x1: L, x2: L, y1: T, y2: H - B}));
  root.append(s("text", {class: "axis-label x-label", x: (L + W - R) / 2, y: H - 10, "text-anchor": "middle"},
                o.xlabel));
  root.append(s("text", {class: "axis-label y-label", x: 0, y: 0, "text-anchor": "middle",
                         transform: "translate(16," + ((T + H - B) / 2) + ") rotate(-90)"}, o.ylabel));
  figure.append(root);
  const legend = h("div", {class: "legend"});
  for (const item of [...o.layers, ...(o.hlines || []), ...(o.vlines || [])]) {
    if (item.name) legend.append(h("span", {}, [h("i", {class: item.cls}), item.name]));
  }
  if (legend.childNodes.length) figure.append(legend);
  return figure;
}

function drawLayer(layer, sx, sy) {
  const x = layer.x;
  if (layer.type === "bars") {
    const g = s("g", {class: layer.cls});
    for (let i = 0; i < layer.counts.length; i++) {
      if (!layer.counts[i]) continue;
      const left = sx(x[i]), right = sx(x[i + 1]), top = sy(layer.counts[i]);
      g.append(s("rect", {x: left + 0.5, y: top, width: Math.max(1, right - left - 1), height: sy(0) - top},
                 s("title", {}, layer.counts[i] + " asset(s), t in [" + fmt(x[i]) + ", " + fmt(x[i + 1]) + "] s")));
    }
    return g;
  }
  let d = "";
  if (layer.type === "band") {
    for (const [a, b] of runs(x.length, (i) => finite(x[i]) && finite(layer.lo[i]) && finite(layer.hi[i]))) {
      const top = [], bottom = [];
      for (let i = a; i < b; i++) {
        top.push(sx(x[i]) + "," + sy(layer.hi[i]));
        bottom.push(sx(x[i]) + "," + sy(layer.lo[i]));
      }
      if (b - a === 1) {  // a lone point: a sliver, visible
        top.push((sx(x[a]) + 2) + "," + sy(layer.hi[a]));
        bottom.push((sx(x[a]) + 2) + "," + sy(layer.lo[a]));
      }
      d += "M" + top.join("L") + "L" + bottom.reverse().join("L") + "Z";
    }
  } else {
    for (const [a, b] of runs(x.length, (i) => finite(x[i]) && finite(layer.y[i]))) {
      const points = [];
      for (let i = a; i < b; i++) points.push(sx(x[i]) + "," + sy(layer.y[i]));
      d += "M" + points.join("L");
    }
  }
  return s("path", {class: layer.cls, d: d || "M0,0"});
}

function rankingChart() {
  const top = ROWS.filter((r) => !Number.isNaN(r.p5)).slice(0, RANKED);
  const figure = h("figure", {class: "chart", "data-kind": "ranking"},
                   h("figcaption", {}, "The " + top.length + " most urgent assets: RUL at their last prediction"));
  if (!top.length) { figure.append(h("p", {class: "note"}, "No asset has a RUL.")); return figure; }
  const W = 1100, L = 220, R = 40, T = 12, B = 50, ROW = 22, H = T + B + ROW * top.length;
  const values = [];
  for (const r of top) for (const v of [r.p5, r.p50, r.p95]) if (finite(v)) values.push(v);
  const x1 = values.length ? Math.max(...values) * 1.05 || 1 : 1;
  const sx = (x) => L + Math.min(x, x1) / x1 * (W - L - R);
  const root = s("svg", {class: "plot", viewBox: "0 0 " + W + " " + H, role: "img", "aria-label": "ranking",
                         style: "max-width: " + W + "px"});
  const grid = s("g", {class: "grid"});
  for (const v of ticks(0, x1, 8)) {
    grid.append(s("line", {x1: sx(v), x2: sx(v), y1: T, y2: H - B}));
    root.append(s("text", {class: "tick x-tick", x: sx(v), y: H - B + 16, "text-anchor": "middle"}, fmt(v)));
  }
  root.append(grid);
  top.forEach((r, i) => {
    const y = T + ROW * i + ROW / 2;
    const name = r.asset.length > 26 ? r.asset.slice(0, 25) + "\u2026" : r.asset;
    const link = s("a", {href: assetHref(r.asset), class: "rank-row", "data-asset": r.asset},
                   [s("text", {x: L - 8, y: y + 4, "text-anchor": "end"}, r.rank + ". " + name),
                    s("title", {}, r.asset)]);
    const right = finite(r.p95) ? sx(r.p95) : W - R;
    const left = finite(r.p5) ? sx(r.p5) : W - R - 6;
    const bar = s("rect", {class: "rank-bar", x: left, y: y - 6, width: Math.max(2, right - left), height: 12},
                  s("title", {}, r.asset + ": RUL p5 " + fmt(r.p5) + " s, p50 " + fmt(r.p50) + " s, p95 "
                                 + fmt(r.p95) + " s"));
    root.append(link, bar);
    if (finite(r.p50)) root.append(s("circle", {class: "rank-median", cx: sx(r.p50), cy: y, r: 4}));
    if (!finite(r.p95)) root.append(s("text", {x: W - R + 4, y: y + 4}, "\u2192"));
  });
  root.append(s("line", {class: "axis", x1: L, x2: W - R, y1: H - B, y2: H - B}));
  root.append(s("text", {class: "axis-label x-label", x: (L + W - R) / 2, y: H - 10, "text-anchor": "middle"},
                label("RUL at the last prediction", U.rul) + ": 5\u201395 % bar, median dot, \u2192 beyond"));
  figure.append(root);
  return figure;
}

// ---------------------------------------------------------------------------------------- the overview
const state = {key: "rank", dir: 1, query: "", status: "", limit: PAGE_ROWS};

function compare(key, numeric, dir) {
  return (a, b) => {
    const x = a[key], y = b[key];
    let c;
    if (numeric) {
      const nx = Number.isNaN(x), ny = Number.isNaN(y);
      c = nx || ny ? (nx === ny ? 0 : nx ? 1 : -1) : x === y ? 0 : (x < y ? -dir : dir);  // no value last
    } else {
      c = !x || !y ? (!x === !y ? 0 : !x ? 1 : -1) : dir * String(x).localeCompare(String(y));
    }
    return c || a.rank - b.rank;
  };
}

function matching() {
  const query = state.query.trim().toLowerCase();
  const rows = ROWS.filter((r) => (!state.status || r.status === state.status) && (!query
    || (r.asset + "\n" + r.hypothesis + "\n" + r.arrs + "\n" + r.status).toLowerCase().includes(query)));
  const column = COLUMNS.find((c) => c.key === state.key);
  return rows.sort(compare(column.key, column.numeric, state.dir));
}

function rowElement(r) {
  const cells = COLUMNS.map((c) => {
    if (c.key === "asset") {
      return h("td", {class: "asset"}, h("a", {href: assetHref(r.asset), title: r.asset}, r.asset));
    }
    if (c.key === "status") return h("td", {}, h("span", {class: "status status-" + slug(r.status)}, r.status));
    if (!c.numeric) return h("td", {}, r[c.key]);
    return h("td", {class: "num"}, c.key === "rank" ? r.rank : fmt(r[c.key]));
  });
  return h("tr", {"data-asset": r.asset}, cells);
}

let table, shown, more;
function renderTable() {
  const rows = matching();
  table.tBodies[0].replaceChildren(...rows.slice(0, state.limit).map(rowElement));
  shown.textContent = Math.min(state.limit, rows.length) + " shown of " + rows.length + " matching ("
    + ROWS.length + " assets)";
  more.hidden = rows.length <= state.limit;
  for (const th of table.tHead.rows[0].cells) {
    th.setAttribute("aria-sort", th.dataset.key === state.key ? (state.dir > 0 ? "ascending" : "descending") : "none");
  }
}

function overview() {
  const c = DATA.counts;
  const main = h("main", {id: "overview"});
  main.append(h("h1", {}, "Fleet overview: " + DATA.model));
  main.append(h("p", {class: "meta", id: "meta"}, c.assets + " assets \u00b7 " + DATA.records));
  main.append(h("p", {class: "provenance", id: "provenance"}, Object.entries(DATA.provenance).flatMap(([k, v], i) =>
    [i ? " \u00b7 " : "", k + ": ", h("code", {}, v)])));
  const settings = h("table", {class: "kv"},
                     DATA.settings.map(([k, v]) => h("tr", {}, [h("td", {}, k), h("td", {}, v)])));
  main.append(h("details", {class: "settings"}, [h("summary", {}, "Run settings"), settings]));
  const cards = [["assets", c.assets], ["monitored", c.monitored], ["with an alarm", c.with_alarm],
                 ["with a RUL", c.with_rul]];
  for (const [status, count] of Object.entries(c.status)) cards.push([status, count]);
  if (!("skipped" in c.status)) cards.push(["skipped", c.skipped]);
  main.append(h("section", {id: "counts", class: "cards"}, cards.map(([name, value]) =>
    h("div", {class: "card", "data-count": name},
      [h("span", {class: "value"}, value), h("span", {class: "name"}, name)]))));
  const tl = DATA.timeline;
  const timeline = h("section", {class: "panel", id: "timeline"}, h("h2", {}, "First alarms over time"));
  timeline.append(chart({kind: "timeline", title: c.with_alarm + " first alarm(s)",
    xlabel: label("first alarm at t", U.t), ylabel: "assets", yzero: true, width: 1100, height: 240,
    layers: [{type: "bars", x: tl.edges.map(num), counts: tl.counts, cls: "bars"}]}));
  main.append(timeline);
  const ranking = h("section", {class: "panel", id: "ranking"}, h("h2", {}, "Ranking"));
  ranking.append(h("p", {class: "note"}, "Assets by their lower RUL percentile (p5) at their last prediction, the "
    + "lowest first; assets without a RUL follow in the table. A name opens the asset's page."));
  ranking.append(rankingChart());
  main.append(ranking);
  const section = h("section", {class: "panel", id: "table"}, h("h2", {}, "All assets"));
  const filter = h("input", {id: "filter", type: "search", placeholder: "filter: asset, hypothesis, ARR, status",
                             "aria-label": "filter the assets by text"});
  const statuses = Object.keys(c.status);
  const select = h("select", {id: "status", "aria-label": "filter the assets by status"},
                   [h("option", {value: ""}, "every status"), ...statuses.map((x) => h("option", {value: x}, x))]);
  shown = h("span", {id: "shown", class: "note"});
  section.append(h("div", {class: "controls"}, [filter, select, shown]));
  table = h("table", {id: "assets"}, [h("thead", {}, h("tr", {}, COLUMNS.map((col) =>
    h("th", {"data-key": col.key, class: col.numeric ? "num" : null, scope: "col"},
      h("button", {type: "button"}, col.title))))), h("tbody")]);
  section.append(h("div", {class: "table-wrap"}, table));
  more = h("button", {id: "more", class: "more", type: "button"}, "show " + PAGE_ROWS + " more");
  section.append(more);
  main.append(section);
  filter.addEventListener("input", () => { state.query = filter.value; state.limit = PAGE_ROWS; renderTable(); });
  select.addEventListener("change", () => { state.status = select.value; state.limit = PAGE_ROWS; renderTable(); });
  more.addEventListener("click", () => { state.limit += PAGE_ROWS; renderTable(); });
  table.tHead.addEventListener("click", (event) => {
    const th = event.target.closest("th");
    if (!th) return;
    state.dir = state.key === th.dataset.key ? -state.dir : 1;
    state.key = th.dataset.key;
    state.limit = PAGE_ROWS;
    renderTable();
  });
  renderTable();
  return main;
}

// ---------------------------------------------------------------------------------------- an asset's page
function estimateChart(d) {
  const parameter = d.h.split("/")[0], unit = unitOf("parameters", parameter);
  const failure = num(own(DATA.failures, parameter));
  const t = decode(d.e[0]), [mean, p5, p95] = parts(d.e[1], 3);
  return chart({kind: "estimate", title: "Estimate of " + parameter + " (" + d.h + ")", xlabel: label("t", U.t),
    ylabel: label(parameter, unit), layers: [
      {type: "band", x: t, lo: p5, hi: p95, cls: "band-estimate", name: "5\u201395 %"},
      {type: "line", x: t, y: mean, cls: "line-estimate", name: "mean"}],
    hlines: finite(failure)
      ? [{y: failure, cls: "failure", name: "failure value " + fmt(failure) + (unit ? " " + unit : "")}] : []});
}

function rulChart(d) {
  const horizon = num(DATA.horizon);
  const cap = (v) => (v === Infinity ? (finite(horizon) ? horizon : NaN) : v);
  const t = decode(d.r[0]), [p5, p50, p95] = parts(d.r[1], 3);
  return chart({kind: "rul", title: "Remaining useful life", xlabel: label("t", U.t), ylabel: label("RUL", U.rul),
    yzero: true, layers: [
      {type: "band", x: t, lo: p5.map(cap), hi: p95.map(cap), cls: "band-rul",
       name: "5\u201395 % (capped at the horizon)"},
      {type: "line", x: t, y: p50.map(cap), cls: "line-rul", name: "median"}],
    hlines: finite(horizon) ? [{y: horizon, cls: "horizon", name: "horizon " + fmt(horizon) + " " + U.rul}] : []});
}

function residualCharts(d) {
  const t = decode(d.x[0]);
  const alarm = d.a && d.a.length ? num(d.a[0][0]) : NaN;
  const out = [];
  DATA.arrs.forEach((arr, k) => {
    const trace = d.x[1][k];
    if (!trace) return;
    const [low, high, bandLow, bandHigh] = parts(trace, 4);
    out.push(chart({kind: "residual", title: "Residual of " + arr, xlabel: label("t", U.t),
      ylabel: label(MINUS_R, unitOf("residuals", arr)), layers: [
        {type: "band", x: t, lo: bandLow, hi: bandHigh, cls: "band-threshold",
         name: "threshold band (margin included)"},
        {type: "band", x: t, lo: low, hi: high, cls: "band-residual",
         name: MINUS_R + ", least and greatest per bucket"}],
      vlines: finite(alarm) ? [{x: alarm, cls: "alarm", name: "first alarm at t = " + fmt(alarm) + " " + U.t}] : []}));
  });
  return out;
}

function assetPage(id) {
  const main = h("main", {id: "asset-view"}, h("nav", {}, h("a", {href: "#", id: "back"}, "\u2190 fleet overview")));
  const r = BY_ID.get(id);
  if (!r) { main.append(h("h1", {}, "No asset " + id + " in this fleet")); return main; }
  main.append(h("h1", {}, ["Asset ", h("span", {class: "asset-id"}, r.asset)]));
  const facts = [["status", r.status], ["rank", r.rank + " of " + ROWS.length],
                 [label("first alarm at t", U.t), fmt(r.alarm)], ["ARRs in alarm", r.arrs || "\u2013"],
                 [label("last RUL at t", U.t), fmt(r.t)],
                 [label("RUL p5 / p50 / p95", U.rul), fmt(r.p5) + " / " + fmt(r.p50) + " / " + fmt(r.p95)],
                 ["hypothesis", r.hypothesis || "\u2013"], ["probability", fmt(r.probability)]];
  const skipped = own(DATA.skipped, r.asset);
  if (skipped !== undefined) facts.push(["record skipped", skipped]);
  main.append(h("dl", {class: "facts"}, facts.flatMap(([k, v]) => [h("dt", {}, k), h("dd", {}, v)])));
  const d = r.detail;
  if (!d) {
    if (skipped === undefined) {
      main.append(h("p", {class: "note", id: "not-kept"}, "This asset's charts are not on the page: it holds those of "
        + "the first " + DATA.kept + " assets of the ranking within its size bound. Its rows are in the Parquet "
        + "tables (bgphm.fleet.read_fleet)."));
    }
    return main;
  }
  if (d.a && d.a.length) {
    main.append(h("section", {}, [h("h2", {}, "Alarms"), h("table", {class: "alarms"}, [
      h("thead", {}, h("tr", {}, [h("th", {}, label("t", U.t)), h("th", {}, "ARR"), h("th", {}, "residual unit")])),
      h("tbody", {}, d.a.map(([t, arr]) => h("tr", {}, [h("td", {}, fmt(num(t))), h("td", {}, arr),
        h("td", {}, unitOf("residuals", arr) || "\u2013")])))])]));
  } else {
    main.append(h("p", {class: "note"}, "No alarm."));
  }
  const charts = h("section", {class: "charts"});
  if (d.e) charts.append(estimateChart(d));
  else if (d.r) charts.append(h("p", {class: "note"}, "No estimate: every hypothesis was rejected."));
  if (d.r) charts.append(rulChart(d));
  if (d.x) charts.append(...residualCharts(d));
  main.append(charts);
  return main;
}

// ---------------------------------------------------------------------------------------- the views
const app = document.getElementById("app");
const home = overview();
let page = null;
const title = document.title;
function route() {
  const hash = location.hash;
  if (page) { page.remove(); page = null; }
  if (hash.startsWith("#asset=")) {
    let id = hash.slice(7);
    try { id = decodeURIComponent(id); } catch (error) { /* a hand-made fragment: the text as it is */ }
    page = assetPage(id);
    home.hidden = true;
    app.append(page);
    document.title = id + " \u00b7 " + title;
    window.scrollTo(0, 0);
  } else {
    home.hidden = false;
    document.title = title;
  }
}
app.append(home);
window.addEventListener("hashchange", route);
route();
})();
"""
