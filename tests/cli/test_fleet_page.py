"""The fleet's overview page (index.html) as written: the data it embeds, its escaping, its size bound.

The page as Chromium renders it is test_fleet_page_in_chromium.py's (slow tier); a real run of the command
writing it is test_fleet_cli.py's.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from bgphm.fleet.page import (LEVELS, PAGE_BYTES, SERIES_POINTS, STATUSES, decode_series, encode_series, fleet_page,
                              page_data, read_page_data)
from prognosis.fleet import FleetResult

from .fleets import SYNTHETIC_HORIZON, SYNTHETIC_UNITS, synthetic_fleet

UNITS = {"t": "s", "parameters": {"R": "Ohm"}, "residuals": {"ARR_J1": "V", "ARR_J0": "A"}}
SUMMARY = {"spec": {"model": "rlc", "failures": {"R": 20.0}}, "records": "CSV directory /data/rlc",
           "skipped": {"e": "column 'i' has no value"}}


def rul_rows(result: FleetResult, asset: str, t: list, p5: list, status: str, p95=None) -> None:
    """RUL rows of one asset (p50 = 2 p5, p95 = 3 p5 unless given)."""
    p5 = np.asarray(p5, float)
    result.add("rul", asset=[asset] * len(t), step=np.arange(len(t)), t=t, mean=2 * p5, p5=p5, p50=2 * p5,
               p95=3 * p5 if p95 is None else p95, censored=np.zeros(len(t)), hypothesis=["R/linear"] * len(t),
               probability=np.full(len(t), 0.75), status=[status] * len(t))


@pytest.fixture(scope="module")
def small():
    """Six assets: three with a RUL (a: urgent at its last row only, b: censored p95, c), d alarmed without a
    RUL, e skipped, f healthy."""
    result = FleetResult()
    result.add("alarms", asset=["a", "b", "c", "c", "d"], t=[1.0, 1.5, 0.5, 0.5, 2.0],
               arr=["ARR_J1", "ARR_J1", "ARR_J0", "ARR_J1", "ARR_J1"])
    rul_rows(result, "a", [1.1, 1.2, 1.3], [9.0, 5.0, 0.4], "isolated")   # the last row decides: p5 = 0.4
    rul_rows(result, "b", [1.6], [3.0], "indistinguishable", p95=[np.inf])
    rul_rows(result, "c", [0.6, 0.7], [0.5, 0.7], "undecided")          # first row lower than a's last, not the last
    return result, page_data(result, SUMMARY, assets=list("abcdef"), units=UNITS, horizon=25.0,
                                 provenance={"date": "now"})


def test_the_ranking_orders_by_the_last_p5_then_alarms_healthy_and_skipped(small):
    _, data = small
    assert [row[0] for row in data["rows"]] == ["a", "c", "b", "d", "f", "e"]
    a, c, b, d, f, e = data["rows"]
    assert a[3:7] == [1.3, 0.4, 0.8, 1.2] and c[4] == 0.7   # the last RUL row of each asset
    assert b[6] == "inf"                                    # a censored p95 is not lost in JSON
    assert [row[9] for row in data["rows"]] == ["isolated", "undecided", "indistinguishable", STATUSES["no_rul"],
                                                STATUSES["healthy"], STATUSES["skipped"]]
    assert c[1:3] == [0.5, "ARR_J0 ARR_J1"] and f[1:8] == [None, "", None, None, None, None, ""]


def test_the_counts_add_up(small):
    _, data = small
    assert data["counts"] == {"assets": 6, "monitored": 5, "with_alarm": 4, "with_rul": 3, "skipped": 1,
                              "status": {"isolated": 1, "indistinguishable": 1, "undecided": 1, "alarm, no RUL": 1,
                                         "no alarm": 1, "skipped": 1}}
    assert sum(data["timeline"]["counts"]) == 4 and data["timeline"]["edges"][0] == 0.5
    assert data["timeline"]["edges"][-1] == 2.0


def test_the_page_states_its_units_and_settings(small):
    _, data = small
    assert data["units"]["t"] == data["units"]["rul"] == "s" and data["units"]["parameters"]["R"] == "Ohm"
    assert data["arrs"] == ["ARR_J1", "ARR_J0"] and data["horizon"] == 25.0 and data["failures"] == {"R": 20.0}
    settings = dict(data["settings"])
    assert settings["failure values"] == "R = 20 Ohm" and settings["ARRs"] == "ARR_J1 (V), ARR_J0 (A)"
    assert settings["RUL horizon (s)"] == "25" and data["provenance"] == {"date": "now"}


def test_a_series_reads_back_within_a_level_of_its_range():
    rng = np.random.default_rng(3)
    values = np.concatenate([rng.normal(5.0, 2.0, 200), [np.inf, -np.inf, np.nan]])
    coded = encode_series(values)
    assert isinstance(coded[2], str) and len(coded[2]) == 2 * values.size
    assert re.fullmatch(r"[A-Za-z0-9_-]*", coded[2])   # nothing to escape in JSON, HTML or a URL
    back = np.array(decode_series(coded))
    span = values[:200].max() - values[:200].min()
    assert np.max(np.abs(back[:200] - values[:200])) <= span / (LEVELS - 1)
    assert back[200] == np.inf and back[201] == -np.inf and np.isnan(back[202])
    assert encode_series(np.linspace(2.0, 3.0, 64)) == [2.0, 3.0, 64]   # evenly spaced times: three numbers
    assert decode_series(encode_series([7.5, 7.5])) == [7.5, 7.5] and encode_series([]) == []


def test_an_asset_s_details_are_its_last_hypothesis_estimate_rul_and_residuals():
    result, summary, assets = synthetic_fleet(8, rul_rows=300)
    data = read_page_data(fleet_page(result, summary, assets=assets, units=SYNTHETIC_UNITS, horizon=22.0))
    index = [row[0] for row in data["rows"]].index("motor-00003")
    detail = data["details"][index]
    alarm = result.for_asset("motor-00003").alarms["t"][0]
    assert detail["h"] == "b/exponential" and detail["a"] == [[pytest.approx(alarm, rel=1e-3), "ARR_1_m"]]
    rul = result.for_asset("motor-00003").rul
    t = np.array(decode_series(detail["r"][0]))
    p5, p50, p95 = np.array(decode_series(detail["r"][1])).reshape(3, -1)
    assert SERIES_POINTS / 2 <= t.size <= SERIES_POINTS + 1 < rul["t"].size   # every k-th row, and the last
    assert t[-1] == pytest.approx(rul["t"][-1], rel=1e-7)
    keep = np.abs(rul["t"][None, :] - t[:, None]).argmin(axis=1)
    assert np.all(np.diff(keep) == keep[1] - keep[0]) or np.all(np.diff(keep)[:-1] == keep[1] - keep[0])
    scale = np.nanmax(rul["p50"]) - np.nanmin(rul["p5"])
    assert np.max(np.abs(p50 - rul["p50"][keep])) <= 2 * scale / (LEVELS - 1)
    assert np.array_equal(np.isinf(p95), np.isinf(rul["p95"][keep]))   # censored stays censored
    estimates = result.for_asset("motor-00003").estimates
    mine = estimates["hypothesis"] == "b/exponential"
    mean = np.array(decode_series(detail["e"][1])).reshape(3, -1)[0]
    assert mean[-1] == pytest.approx(estimates["theta_mean"][mine][-1], rel=1e-2)
    t, traces = detail["x"]
    assert len(decode_series(t)) == 64 and len(traces) == 2
    low, high, band_low, band_high = np.array(decode_series(traces[1])).reshape(4, -1)
    residuals = result.for_asset("motor-00003").residuals
    high_m = residuals["high"][residuals["arr"] == "ARR_1_m"]
    assert np.max(np.abs(high - high_m)) <= (high_m.max() - low.min()) / 1000


def test_asset_ids_and_names_cannot_break_out_of_the_page():
    evil = ["</script><script>window.pwned = 1</script>", "<!--", "a&b\"c'd", "line\u2028sep", "<b>x</b>"]
    result = FleetResult()
    result.add("alarms", asset=evil, t=[1.0] * 5, arr=["ARR_J1"] * 5)
    summary = {"spec": {"model": "</title><script>alert(1)</script>", "failures": {}}, "records": "<i>r</i>"}
    text = fleet_page(result, summary, assets=evil, units=UNITS)
    assert text.count("</script>") == 2 and text.lower().count("<script") == 2   # the data block and the script
    assert "<!--" not in text and "<b>" not in text and "<i>" not in text and "\u2028" not in text
    assert "<title>Fleet overview: &lt;/title&gt;&lt;script&gt;alert(1)&lt;/script&gt;</title>" in text
    data = read_page_data(text)
    assert sorted(row[0] for row in data["rows"]) == sorted(evil)   # the ids read back exactly
    assert data["model"] == summary["spec"]["model"] and data["records"] == "<i>r</i>"


@pytest.mark.slow   # a second of CPU: the fast tier stays under a minute
def test_a_thousand_assets_fit_a_tenth_of_the_bound_and_the_bound_holds():
    result, summary, assets = synthetic_fleet(1000)
    text = fleet_page(result, summary, assets=assets, units=SYNTHETIC_UNITS, horizon=SYNTHETIC_HORIZON)
    size = len(text.encode("utf-8"))
    data = read_page_data(text)
    assert size <= PAGE_BYTES / 10   # 10^4 assets within 20 MB
    assert data["kept"] == 990 and data["details"].count(None) == 10   # every asset but the skipped ones
    budget = size // 2
    halved = fleet_page(result, summary, assets=assets, units=SYNTHETIC_UNITS, horizon=SYNTHETIC_HORIZON,
                        budget=budget)
    kept = read_page_data(halved)
    assert len(halved.encode("utf-8")) <= budget and len(kept["rows"]) == 1000
    details = kept["details"]
    assert 0 < kept["kept"] < 990 and all(details[:kept["kept"]]) and not any(details[kept["kept"]:])
    # the most urgent keep their charts: a prefix of the ranking
    assert json.dumps(kept["rows"]) == json.dumps(data["rows"])
