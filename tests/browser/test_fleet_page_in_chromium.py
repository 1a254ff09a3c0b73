"""The fleet's overview page as Chromium renders it: 10^3 synthetic assets, ranking, counts, units, sort, filter,
an asset's page, and an asset id that tries to break out of the page.

The page is written by the same writer as ``bgphm fleet``'s (:func:`bgphm.fleet.fleet_page`) from a synthetic
fleet's tables (tests/cli/fleets.py: no filter runs).  The screenshots (the overview, an asset's page) are
written to the test's tmp_path.

The browser is the harness's (``open_page``, tests/browser/conftest.py: Debian's Chromium driven by playwright).
"""

from __future__ import annotations

import math

import pytest

from bgphm.fleet.page import fleet_page, read_page_data
from tests.cli.fleets import SYNTHETIC_HORIZON, SYNTHETIC_UNITS, synthetic_fleet

pytestmark = pytest.mark.slow

EVIL = "m-</script><script>window.pwned = 1</script>&\"'<b>#%"   # motor-00007's id here
ASSETS = 1000
SHOWN = 100   # the table's rows drawn at a time


@pytest.fixture(scope="module")
def overview(tmp_path_factory):
    """index.html of a synthetic fleet of 10^3 assets, and the data it embeds."""
    result, summary, assets = synthetic_fleet(ASSETS, rename={"motor-00007": EVIL})
    text = fleet_page(result, summary, assets=assets, units=SYNTHETIC_UNITS, horizon=SYNTHETIC_HORIZON)
    path = tmp_path_factory.mktemp("fleet-page") / "index.html"
    path.write_text(text, encoding="utf-8")
    return path, read_page_data(text)


def number(text: str) -> float:
    """A number as the page shows it (a true minus, infinity, a dash for none) back to a float."""
    text = text.replace("\u2212", "-")
    return math.inf if text == "\u221e" else math.nan if text == "\u2013" else float(text)


def table_column(page, key: str) -> list[str]:
    index = page.evaluate("(k) => Array.from(document.querySelectorAll('#assets th')).findIndex("
                          "th => th.dataset.key === k)", key)
    return page.evaluate("(i) => Array.from(document.querySelectorAll('#assets tbody tr'), "
                         "tr => tr.cells[i].textContent)", index)


def shown_assets(page) -> list[str]:
    return page.evaluate("Array.from(document.querySelectorAll('#assets tbody tr'), tr => tr.dataset.asset)")


def by_p95(row: list, descending: bool = False) -> tuple:
    """The table's order sorted by RUL p95: no value last either way, ties by rank (the data's order)."""
    p95 = row[1][6]
    value = math.inf if p95 == "inf" else p95
    return (p95 is None, 0.0 if p95 is None else (-value if descending else value), row[0])


def chart_labels(page, selector: str) -> list[list[str]]:
    """[x label, y label] of each chart matching ``selector``."""
    return page.evaluate("(s) => Array.from(document.querySelectorAll(s), f => [f.querySelector('.x-label')"
                         ".textContent, f.querySelector('.y-label').textContent])", selector)


def test_the_overview_ranks_counts_sorts_filters_and_opens_an_asset_page(overview, open_page, tmp_path):
    path, data = overview
    page = open_page(path)
    shot = page.screenshot(tmp_path / "overview.png")
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert page.evaluate("typeof window.pwned") == "undefined"   # the id's script never ran
    assert page.overflowing() == []   # nothing off the page sideways (the wide table scrolls in its box)
    text = page.text()
    for raw in ("Derivative(", "Integral(", "**", "r_n", "sqrt(", "Abs(", "undefined", "NaN"):
        assert raw not in text, f"raw text {raw!r} on the page"

    # the counts, the ranking (chart and table) in the data's order, the most urgent first
    cards = dict(zip(page.texts("#counts .card .name"), page.texts("#counts .card .value")))
    counts = data["counts"]
    assert cards["assets"] == str(ASSETS) == str(counts["assets"])
    assert cards["with an alarm"] == str(counts["with_alarm"]) and cards["with a RUL"] == str(counts["with_rul"])
    assert all(cards[status] == str(n) for status, n in counts["status"].items()) and cards["skipped"] == "10"
    ids = [row[0] for row in data["rows"]]
    assert page.evaluate("Array.from(document.querySelectorAll('a.rank-row'), a => a.dataset.asset)") == ids[:20]
    assert shown_assets(page) == ids[:SHOWN]
    p5 = [number(x) for x in table_column(page, "p5")]
    assert p5 == sorted(p5) and p5[0] == data["rows"][0][4]

    # units in the headers and on the axes
    headers = [h.replace("\u25b2", "").strip() for h in page.texts("#assets th")]
    for header in ("first alarm at t (s)", "last RUL at t (s)", "RUL p5 (s)", "RUL p50 (s)", "RUL p95 (s)"):
        assert header in headers
    assert chart_labels(page, "figure[data-kind=timeline]") == [["first alarm at t (s)", "assets"]]
    assert "RUL at the last prediction (s)" in page.texts("figure[data-kind=ranking] .x-label")[0]

    # sort by a column, both ways; filter by text, then by status
    rows = list(enumerate(data["rows"]))
    page.page.click("th[data-key=p95] button")
    assert shown_assets(page) == [r[1][0] for r in sorted(rows, key=by_p95)][:SHOWN]
    assert page.texts("th[aria-sort=ascending]") and "RUL p95 (s)" in page.texts("th[aria-sort=ascending]")[0]
    page.page.click("th[data-key=p95] button")
    assert shown_assets(page) == [r[1][0] for r in sorted(rows, key=lambda r: by_p95(r, True))][:SHOWN]
    page.page.fill("#filter", "motor-0012")
    assert shown_assets(page) == sorted((a for a in ids if "motor-0012" in a),
                                        key=lambda a: by_p95((ids.index(a), data["rows"][ids.index(a)]), True))
    assert page.texts("#shown")[0].startswith("10 shown of 10 matching")
    page.page.fill("#filter", "")
    page.page.select_option("#status", "rejected")
    rejected = counts["status"]["rejected"]
    assert rejected > SHOWN and page.texts("#shown")[0].startswith(f"{SHOWN} shown of {rejected} matching")
    page.page.click("#more")
    statuses = table_column(page, "status")
    assert set(statuses) == {"rejected"} and len(statuses) == rejected
    page.page.select_option("#status", "")

    # from the ranking to the most urgent asset's page: its alarms, estimate, RUL and residuals, axes with units
    page.page.locator("a.rank-row").first.click()
    page.page.wait_for_function("() => document.querySelector('#asset-view .asset-id')")
    assert page.evaluate("location.hash") == "#asset=" + ids[0]
    assert page.texts("#asset-view .asset-id") == [ids[0]] and page.evaluate("document.getElementById('overview')"
                                                                            ".hidden")
    assert chart_labels(page, "figure[data-kind=estimate]") == [["t (s)", "b (N*m*s/rad)"]]
    assert chart_labels(page, "figure[data-kind=rul]") == [["t (s)", "RUL (s)"]]
    assert chart_labels(page, "figure[data-kind=residual]") == [["t (s)", "\u2212r\u2099 (V)"],
                                                                 ["t (s)", "\u2212r\u2099 (N*m)"]]
    drawn = page.evaluate("Array.from(document.querySelectorAll('#asset-view figure.chart'), f => "
                          "[f.querySelectorAll('.x-tick').length, f.querySelectorAll('.y-tick').length, "
                          "Math.max(...Array.from(f.querySelectorAll('path'), p => p.getTotalLength()))])")
    assert len(drawn) == 4 and all(x >= 3 and y >= 3 and length > 100 for x, y, length in drawn)
    legend = " ".join(page.texts("#asset-view .legend"))
    assert "failure value 0.002 N*m*s/rad" in legend and "horizon 22 s" in legend and "first alarm at t = " in legend
    assert page.overflowing() == []
    page.screenshot(tmp_path / "asset.png")

    # back, then to the page of the id made to break out: shown as text, its script never run
    page.page.click("#back")
    page.page.wait_for_function("() => !document.getElementById('asset-view')")
    page.page.fill("#filter", "pwned")
    assert shown_assets(page) == [EVIL]
    page.page.locator("#assets tbody a").first.click()
    page.page.wait_for_function("() => document.querySelector('#asset-view .asset-id')")
    assert page.texts("#asset-view .asset-id") == [EVIL] and page.evaluate("typeof window.pwned") == "undefined"
    assert page.evaluate("decodeURIComponent(location.hash.slice(7))") == EVIL
