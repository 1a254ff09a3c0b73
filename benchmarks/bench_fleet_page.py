"""The fleet's overview page (index.html) at 10^3 and 10^4 assets: its size, and the time to write it.

    python benchmarks/bench_fleet_page.py                       # 1000 and 10000 assets, a table
    python benchmarks/bench_fleet_page.py --assets 1000 --json  # one JSON line per fleet size
    python benchmarks/bench_fleet_page.py --browser             # also: the time Chromium takes to show it

A synthetic fleet (``tests/cli/fleets.py: synthetic_fleet``: no filter runs) of DC motors, two ARRs with
their 64-bucket residual traces for every asset, 3/4 of them alarmed with 30 RUL rows and 30 estimate rows
of each of two hypotheses, 2 % alarmed without a RUL, 1 % skipped) is written as ``bgphm fleet`` writes it:
its tables to Parquet in shards of 1000 assets (``write_shard``), then what ``run_fleet`` adds at the end,
timed: the staged tables read back and checked (``read_tables``), the page built (``fleet_page``) and
written (``write_text``).  Printed per size: the page's bytes (and per asset), the assets whose charts it
holds (``kept``), the tables' bytes, the seconds of each step.  With ``--browser``: the seconds from
Chromium's navigation to the page's table drawn, and to an asset's page drawn (Debian's
``/usr/bin/chromium`` through playwright).

Target: 10^4 assets within 20 MB (``PAGE_BYTES``), every asset's charts kept.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bgphm.files import write_text  # noqa: E402
from bgphm.fleet import fleet_page, read_page_data  # noqa: E402
from bgphm.fleet.store import read_tables, write_shard  # noqa: E402
from prognosis.fleet import FleetResult  # noqa: E402
from tests.cli.fleets import SYNTHETIC_HORIZON, SYNTHETIC_UNITS, synthetic_fleet  # noqa: E402

SHARD = 1000
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run"]


def shards(result: FleetResult, assets: list, size: int = SHARD):
    """The result cut into shards of ``size`` consecutive assets, as the engine's tasks write them."""
    tables = {name: result.table(name) for name in ("alarms", "estimates", "rul", "residuals")}
    for start in range(0, len(assets), size):
        mine = assets[start:start + size]
        part = FleetResult()
        for name, table in tables.items():
            keep = np.isin(table["asset"].astype(str), mine)
            part.add(name, **{column: values[keep] for column, values in table.items()})
        yield start // size, part


def measure(count: int, folder: Path, browser: bool) -> dict:
    result, summary, assets = synthetic_fleet(count)
    staging = folder / ".staging"
    files = {}
    for shard, part in shards(result, assets):
        files.update(write_shard(part, staging, shard)[1])
    tables_bytes = sum((staging / path).stat().st_size for path in files)
    start = time.perf_counter()
    tables = read_tables(staging, files)
    read = time.perf_counter()
    text = fleet_page(tables, summary, assets=assets, units=SYNTHETIC_UNITS, horizon=SYNTHETIC_HORIZON)
    built = time.perf_counter()
    page = write_text(folder / "index.html", text)
    written = time.perf_counter()
    data = read_page_data(text)
    out = {"assets": count, "page_bytes": page.stat().st_size, "page_mb": round(page.stat().st_size / 2**20, 2),
           "bytes_per_asset": round(page.stat().st_size / count), "kept": data["kept"],
           "with_details_possible": count - data["counts"]["skipped"], "tables_bytes": tables_bytes,
           "read_s": round(read - start, 2), "build_s": round(built - read, 2), "write_s": round(written - built, 3),
           "page_s": round(written - start, 2)}
    if browser:
        out.update(open_in_chromium(page, data["rows"][0][0]))
    return out


def open_in_chromium(page: Path, asset: str) -> dict:
    """Seconds from navigation to the overview's table drawn, and from a click in the ranking to an asset's page."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path="/usr/bin/chromium", headless=True, args=ARGS)
        tab = chromium.new_page(viewport={"width": 1400, "height": 900})
        start = time.perf_counter()
        tab.goto(page.resolve().as_uri(), wait_until="load")
        tab.wait_for_selector("#assets tbody tr")
        shown = time.perf_counter()
        tab.locator("a.rank-row").first.click()
        tab.wait_for_selector("#asset-view figure[data-kind=residual]")
        opened = time.perf_counter()
        heap = tab.evaluate("performance.memory ? performance.memory.usedJSHeapSize : null")
        chromium.close()
    return {"browser_overview_s": round(shown - start, 2), "browser_asset_s": round(opened - shown, 2),
            "browser_heap_mb": None if heap is None else round(heap / 2**20, 1), "browser_first_asset": asset}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--assets", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--json", action="store_true", help="one JSON line per fleet size")
    parser.add_argument("--browser", action="store_true", help="also time the page in headless Chromium")
    args = parser.parse_args()
    for count in args.assets:
        with tempfile.TemporaryDirectory() as folder:
            row = measure(count, Path(folder), args.browser)
        if args.json:
            print(json.dumps(row))
        else:
            print("  ".join(f"{k}={v}" for k, v in row.items()))


if __name__ == "__main__":
    main()
