"""The run report (``report.html`` of ``bgphm prognose`` and ``detect``) as Chromium renders it.

A worn DC motor made at the command line (``simulate --degrade --noise``), its prognosis with ``--truth``,
opened in headless Chromium and screenshotted; the rendered DOM must show typeset equations (no sympy text,
derivatives as fractions of d), units in every chart's axes and in the tables' headers, the truth drawn, and
nothing off the page.
"""

from __future__ import annotations

import json

import pytest

from bgphm.cli import main

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("run-reports")
    record = folder / "run.csv"
    assert main(["--quiet", "simulate", "dc-motor", "--degrade", "b=exp:0.8@1", "--noise", "omega=0.5", "--t-end", "4",
                 "--out", str(record)]) == 0
    truth = folder / "truth.json"
    truth.write_text(json.dumps({"eol": 1 + 2.995732273553991 / 0.8, "candidate": "b", "degradation": "exponential",
                                 "nominal": 1e-4, "rate": 0.8, "onset": 1.0}))
    assert main(["--quiet", "prognose", "dc-motor", str(record), "--fail", "b=2e-3", "--calibrate", "0.9",
                 "--truth", str(truth), "--out", str(folder / "prognose")]) == 0
    assert main(["--quiet", "detect", "dc-motor", str(record), "--calibrate", "0.9", "--out",
                 str(folder / "detect")]) == 0
    return folder


@pytest.mark.parametrize("command", ["prognose", "detect"])
def test_the_run_report_renders_equations_and_units(runs, open_page, tmp_path, command):
    page = open_page(runs / command / "report.html")
    assert page.screenshot(tmp_path / f"{command}.png").stat().st_size > 10_000
    text = page.text()
    for raw in ("Integral(", "Derivative(", "\u2146"):
        assert raw not in text
    # the mechanical ARR's derivative d omega / d t, as a fraction whose numerator holds d and omega
    numerators = page.evaluate("Array.from(document.querySelectorAll('math mfrac'), f => f.children[0].textContent)")
    assert any(n.replace(" ", "").startswith("d") and "ω" in n for n in numerators)
    assert page.count("math msub") > 0
    axes = page.texts("svg.chart .y-label")
    assert "\u2212r\u2099 (N*m)" in axes
    assert set(page.texts("svg.chart .x-label")) == {"t (s)"}
    headers = page.texts("th")
    assert "unit" in headers
    if command == "prognose":
        assert {"b (N*m*s/rad)", "RUL (s)", "probability"} <= set(axes)
        assert {"t (s)", "RUL median (s)", "RUL 5 % (s)"} <= set(headers)
        legend = page.texts("svg.chart .legend-label")
        assert "true RUL" in legend and "failure value 0.002 N*m*s/rad" in legend
        assert "Truth: end of life" in text
    charts = page.rects("svg.chart")
    assert charts and min(r["width"] for r in charts) >= 700
    width = page.page_width()
    assert width["scroll"] <= width["viewport"] and page.overflowing() == []
