"""A residual read more often than its derivative window: the RUL resolves no finer than the window.

The torsion bar's clean exponential wear, simulated from the physics and run through ``bgphm prognose``
with a derivative window of 31 samples (0.31 s) read every 11 samples (0.11 s), as a user quietening a
differentiated residual would: its change is smoothed over the window, whatever the filter step.
"""

import pytest

from tests.wear.run import SYSTEMS, Scenario, run, score

WEAR = Scenario("torsion_bar", "b_Md", "exponential", "clean")


@pytest.mark.slow  # 100 s of the torsion bar's physics and bgphm prognose: about 10 s of CPU
def test_a_band_read_more_often_than_its_window_spans_the_window():
    dt = 11 * SYSTEMS["torsion_bar"].dt
    answer = run(WEAR, seed=20261127, particles=100, rul_every=10, method="resample-move", window=31,
                 extra=("--dt", f"{dt:g}"))
    assert answer["exit"] == 0, answer.get("error")
    assert answer["filter_step"] == pytest.approx(0.11)
    given = [p for p in answer["predictions"] if not p.get("withheld") and p["rul_p95"] is not None]
    assert len(given) > 20
    # each RUL sample spread over the 0.31 s window (a 5-95 % band of 0.28 s at least, less the sampling's
    # scatter), not over the 0.11 s step
    narrow = [p for p in given if p["rul_p95"] - p["rul_p5"] < 0.8 * 0.31]
    assert not narrow, narrow[:3]
    figures = score(WEAR, answer)
    assert figures["found"] and figures["coverage_90"] >= 0.85, figures
