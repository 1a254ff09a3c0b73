"""What a fleet keeps of each asset's residuals: a short trace per ARR for a chart, not the samples.

A record of 10^4 samples per ARR is 10^8 numbers for 10^4 assets; a fleet's overview page shows each
residual in a chart a few hundred pixels wide.  :func:`residual_trace` cuts the samples into
:data:`TRACE_BUCKETS` buckets of consecutive samples and keeps, per bucket, the envelope of ``-r_n``
(its least and greatest value: a spike within a bucket stays visible, which every k-th sample would
miss) and the mean of the threshold band on ``-r_n``, margin included (what ``bgphm detect`` plots).
:class:`~prognosis.fleet.FleetMonitor` adds these rows to its ``residuals`` table.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TRACE_BUCKETS", "residual_trace"]

#: Buckets per residual trace: a point per 10 px of a 640 px chart, and about 1 KB per asset and ARR on the page.
TRACE_BUCKETS = 64


def residual_trace(evaluation, buckets: int = TRACE_BUCKETS) -> dict:
    """The residual of an evaluation in ``buckets`` buckets of consecutive samples, for a chart.

    Parameters
    ----------
    evaluation : diagnosis.detection.Evaluation
        An ARR evaluated over a record.
    buckets : int
        Buckets at most (a record of fewer samples gives one bucket per sample).

    Returns
    -------
    dict of ndarray
        ``t`` (the middle of each bucket's first and last sample times), ``low`` and ``high`` (the least
        and greatest ``-r_n`` of the bucket's samples, NaN samples left out; NaN when all are NaN), and
        ``band_low`` and ``band_high`` (the mean over the bucket of the band ``[B_lo - m, B_hi + m]`` on
        ``-r_n``, ``m`` the noise margin).  A residual inside the band over a bucket shows inside the
        mean band unless the band moves by more than the residual's distance to it within the bucket.

    Examples
    --------
    >>> from diagnosis.detection import Evaluation
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> r = np.zeros(11)
    >>> r[4] = -3.0                                    # -r_n = 3 at one sample: a spike
    >>> flags = np.zeros(11, bool)
    >>> e = Evaluation("ARR_1", t, r, lower=np.full(11, -1.0), upper=np.full(11, 1.0), bglft=np.ones(11),
    ...                margin=0.5, persistence=1, violation=flags, alarm=flags)
    >>> trace = residual_trace(e, buckets=3)
    >>> trace["t"].round(2).tolist(), trace["high"].tolist(), trace["band_high"].tolist()
    ([0.1, 0.45, 0.85], [0.0, 3.0, 0.0], [1.5, 1.5, 1.5])
    """
    if isinstance(buckets, bool) or not isinstance(buckets, (int, np.integer)) or buckets < 1:
        raise ValueError(f"buckets must be a whole number >= 1, got {buckets!r}")
    t = np.asarray(evaluation.t, float)
    count = min(int(buckets), t.size)
    if count == 0:
        return {name: np.empty(0) for name in ("t", "low", "high", "band_low", "band_high")}
    starts = (np.arange(count) * t.size) // count  # equal counts, each bucket at least one sample
    ends = np.append(starts[1:], t.size) - 1
    value = 0.0 - np.asarray(evaluation.residual, float)  # -r_n, without a -0.0 for a zero
    return {"t": 0.5 * (t[starts] + t[ends]),
            # fmin/fmax skip NaN: a bucket is NaN only when every sample of it is
            "low": np.fmin.reduceat(value, starts), "high": np.fmax.reduceat(value, starts),
            "band_low": _bucket_mean(np.asarray(evaluation.lower, float) - evaluation.margin, starts),
            "band_high": _bucket_mean(np.asarray(evaluation.upper, float) + evaluation.margin, starts)}


def _bucket_mean(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """The mean of each bucket's non-NaN values (NaN for a bucket without one); an infinite value stays infinite."""
    known = ~np.isnan(values)
    total = np.add.reduceat(np.where(known, values, 0.0), starts)
    count = np.add.reduceat(known.astype(float), starts)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1.0), np.nan)
