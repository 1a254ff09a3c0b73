"""Streaming benchmark: cost per sample and memory of diagnosis.StreamingEvaluation as a stream grows.

The torsion bar's ARR at junction 1_1 (shaft integral kept, read from the encoder angles), persistence
10 and a margin that about half of the samples exceed, on a synthetic 100 Hz record (speeds, torque,
quantized angles) of ``--samples`` samples (default 1e5).  The stream is fed one sample at a time,
then in batches of 100; the cost per sample is the mean over the second half of the samples before 1e3
and before ``--samples`` (slicing the batch out of the record's arrays included).  RSS is read from
/proc/self/statm at half and at the end of each run.  Beside it, the baseline: one ``evaluate()`` of
the record so far, which ``HealthMonitor.update`` runs at each filter step today
(``speedup_vs_reevaluate``: that call against one single-sample push).  Finally the batched
stream is compared with ``evaluate()`` on the whole record.

    python benchmarks/bench_streaming.py                    # table
    python benchmarks/bench_streaming.py --json             # one JSON line
    python benchmarks/bench_streaming.py --samples 20000    # a quicker run

Target: <= 20 us per sample at 1e5 samples, RSS growth < 1 % over the last half, the
same cost per sample at 1e5 as at 1e3.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np
from scipy.integrate import cumulative_trapezoid

from bondgraph.library import torsion_bar_monitorable
from diagnosis import StreamChunk, StreamingEvaluation, derive_arrs, evaluate

ANTIDERIVATIVES = {"omega_m": "theta_m", "omega_Ld": "theta_Ld"}
OPTIONS = {"antiderivatives": ANTIDERIVATIVES, "persistence": 10}  # and the margin, set by main()
DT = 0.01
ENCODER_COUNT = 2 * np.pi / 2000


def record(samples: int, seed: int = 0) -> dict:
    """A 100 Hz record of the torsion bar's sensors: noisy speeds and torque, quantized encoder angles."""
    t = np.arange(samples) * DT
    rng = np.random.default_rng(seed)
    columns = {"t": t, "omega_m": 50 * np.sin(0.2 * t) + 0.01 * rng.standard_normal(samples),
               "omega_Ld": 13 * np.sin(0.2 * t - 0.1) + 0.01 * rng.standard_normal(samples),
               "tau_m": 0.1 * np.cos(0.3 * t) + 0.01 * rng.standard_normal(samples)}
    for speed, angle in ANTIDERIVATIVES.items():
        columns[angle] = np.round(cumulative_trapezoid(columns[speed], t, initial=0.0) / ENCODER_COUNT) * ENCODER_COUNT
    return columns


def rss_bytes() -> int:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def feed(arr, data: dict, batch: int, marks: tuple) -> dict:
    """Push the record ``batch`` samples at a time; the time per sample over the half before each mark, RSS."""
    stream = StreamingEvaluation(arr, **OPTIONS)
    columns = stream.columns
    t, n = data["t"], data["t"].size
    windows = {mark: (mark // 2, mark) for mark in marks}
    spent = dict.fromkeys(marks, 0.0)
    rss = {}
    for start in range(0, n, batch):
        stop = min(start + batch, n)
        began = time.perf_counter()
        stream.push(t[start:stop], {c: data[c][start:stop] for c in columns})
        took = time.perf_counter() - began
        for mark, (lo, hi) in windows.items():
            if lo <= start < hi:
                spent[mark] += took
        if stop in (n // 2, n):
            rss[stop] = rss_bytes()
    per_sample = {mark: spent[mark] / (hi - lo) * 1e6 for mark, (lo, hi) in windows.items()}
    return {"us": per_sample, "rss": rss, "buffer": stream.state()["buffer"].shape[1]}


def growth(rss: dict, n: int) -> float:
    """RSS growth over the second half of the stream, in percent."""
    return (rss[n] - rss[n // 2]) / rss[n // 2] * 100


def reevaluate_ms(arr, data: dict, n: int, repeats: int = 3) -> float:
    """One evaluate() of the first n samples (the best of a few), in ms."""
    head = {c: v[:n] for c, v in data.items()}
    best = np.inf
    for _ in range(repeats):
        began = time.perf_counter()
        evaluate(arr, head, **OPTIONS)
        best = min(best, time.perf_counter() - began)
    return best * 1e3


def agreement(arr, data: dict) -> dict:
    """The batched stream against evaluate() on the whole record."""
    stream = StreamingEvaluation(arr, **OPTIONS)
    n = data["t"].size
    chunks = [stream.push(data["t"][a:a + 100], {c: data[c][a:a + 100] for c in stream.columns})
              for a in range(0, n, 100)]
    joined = StreamChunk.concatenate([*chunks, stream.flush()])
    batch = evaluate(arr, data, **OPTIONS)
    scale = np.nanmax(np.abs(batch.residual))
    return {"max_residual_diff_rel": float(np.nanmax(np.abs(joined.residual - batch.residual)) / scale),
            "alarms_equal": bool(np.array_equal(joined.alarm, batch.alarm)), "alarms": int(batch.alarm.sum())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000, help="length of the stream (default 1e5)")
    parser.add_argument("--json", action="store_true", help="print one JSON line")
    args = parser.parse_args()
    n = args.samples
    if n < 2000:
        parser.error("--samples must be at least 2000")
    arr = next(a for a in derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")
               if a.junction == "1_1")
    data = record(n)
    # the synthetic record does not satisfy the ARR: a margin at the median |r_n| gives violations and alarms
    # on about half of the samples (which also builds the lambdified functions before any timing)
    OPTIONS["margin"] = float(np.median(np.abs(evaluate(arr, data, **OPTIONS).residual)))
    one = feed(arr, data, 1, (1000, n))
    hundred = feed(arr, data, 100, (1000, n))
    big = "1e5" if n == 100_000 else str(n)
    figures = {
        "samples": n,
        "us_per_sample_at_1e3": one["us"][1000],
        f"us_per_sample_at_{big}": one["us"][n],
        "us_per_sample_at_1e3_batch100": hundred["us"][1000],
        f"us_per_sample_at_{big}_batch100": hundred["us"][n],
        "rss_growth_pct_last_half": growth(one["rss"], n),
        "rss_growth_pct_last_half_batch100": growth(hundred["rss"], n),
        "rss_mib": one["rss"][n] / 2**20,
        "buffer_samples": one["buffer"],
        "reevaluate_ms_at_1e3": reevaluate_ms(arr, data, 1000),
        f"reevaluate_ms_at_{big}": reevaluate_ms(arr, data, n),
        **agreement(arr, data),
    }
    figures[f"speedup_vs_reevaluate_at_{big}"] = figures[f"reevaluate_ms_at_{big}"] * 1e3 / figures[
        f"us_per_sample_at_{big}"]
    if args.json:
        print(json.dumps(figures))
        return
    for key, value in figures.items():
        print(f"{key:40s} {value:.4g}" if isinstance(value, float) else f"{key:40s} {value}")


if __name__ == "__main__":
    main()
