"""The scenario suite's scoring: the PIT histogram places the truth among the predicted quantiles."""

import numpy as np

from tests.wear.run import SYSTEMS, pit_histogram

ONSET, EOL = SYSTEMS["torsion_bar"].onset, SYSTEMS["torsion_bar"].eol


def test_the_truth_lands_in_the_bin_between_its_neighbouring_quantiles_of_its_quarter():
    quantiles = {"rul_p5": 10.0, "rul_p25": 20.0, "rul_median": 30.0, "rul_p75": 40.0, "rul_p95": 50.0}
    early, late = ONSET + 0.1 * (EOL - ONSET), ONSET + 0.9 * (EOL - ONSET)
    predictions = [{"t": early, **quantiles}, {"t": early, **quantiles}, {"t": late, **quantiles},
                   {"t": late, **{**quantiles, "rul_p95": None}}]   # an open upper end (beyond the horizon)
    counts = np.array(pit_histogram(predictions, np.array([5.0, 35.0, 45.0, 1e6]), onset=ONSET, eol=EOL))
    assert counts.shape == (4, 6) and counts.sum() == 4
    assert counts[0].tolist() == [1, 0, 0, 1, 0, 0]
    assert counts[3].tolist() == [0, 0, 0, 0, 2, 0]   # 45 lies in (40, 50]; 1e6 below an infinite 95 %
