"""Small fleets for the fleet tests: noisy RLC circuits whose resistance drifts up (or not), as CSV files."""

from __future__ import annotations

import builtins
from pathlib import Path

import numpy as np

from bgphm.files import csv_text
from bondgraph import simulate
from bondgraph.library import rlc_circuit
from diagnosis import add_noise, as_record

#: Drift onsets (s) of R (10 ohm, drifting at 4 ohm/s, failing at 20 ohm); None stays healthy.
ONSETS = {"c0": 0.3, "c1": None, "c2": 0.6, "c3": 0.5, "c4": None, "c5": 0.7}
T_END = 2.0  # s, at 1 kHz
NOISE = {"i": 1e-4, "v_C": 1e-3}


def rlc_record(onset: float | None, seed: int, t_end: float = T_END):
    """A noisy record of the RLC circuit, R drifting from ``onset`` (V, i, v_C at 1 kHz)."""
    t = np.linspace(0.0, t_end, int(t_end * 1000) + 1)
    drift = (lambda t: 10.0 + 4.0 * max(0.0, t - onset)) if onset is not None else None
    run = simulate(rlc_circuit(), (0.0, t_end), {"V": lambda t: 5 + np.sin(7 * t)}, t_eval=t,
                   parameters={"R": drift} if drift else {})
    return add_noise(as_record(run.record()), NOISE, seed=seed)


def write_fleet(folder: Path, onsets: dict = ONSETS) -> Path:
    """One CSV per asset in ``folder`` (created); returns it."""
    folder.mkdir(parents=True, exist_ok=True)
    for seed, (asset, onset) in enumerate(onsets.items()):
        record = rlc_record(onset, seed)
        (folder / f"{asset}.csv").write_text(csv_text({"t": record.t, **record.columns}))
    return folder


def spec(**settings):
    """A cheap job on these records: both ARRs of the RLC circuit, R failing at 20 ohm, a linear law."""
    from bgphm.fleet import FleetSpec

    options = {"noise_std": {"ARR_J1": 2.8e-3, "ARR_J0": 2.6e-4}, "laws": ["linear"], "dt": 0.05, "n_particles": 100,
               "rul_every": 4, "detection": {"ARR_J1": {"margin": 0.011}, "ARR_J0": {"margin": 1.1e-3}},
               "healthy_until": 0.2, **settings}
    return FleetSpec("rlc", {"R": 20.0}, **options)


def without_dask(monkeypatch) -> None:
    """Make ``import dask`` and ``import distributed`` fail for the rest of the test (a machine without the extra)."""
    real_import = builtins.__import__

    def without_distributed(name, *args, **kwargs):
        if name.split(".")[0] in ("dask", "distributed"):
            raise ImportError(f"No module named {name!r}")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", without_distributed)


# ------------------------------------------------------------------------------------------ synthetic outputs

#: The page's shape of a synthetic fleet: DC motors whose friction b wears (failing at 2e-3 N*m*s/rad), two ARRs.
SYNTHETIC_UNITS = {"t": "s", "signals": {"U": "V", "i": "A", "omega": "rad/s"},
                   "parameters": {"b": "N*m*s/rad", "J": "kg*m^2"}, "residuals": {"ARR_1_e": "V", "ARR_1_m": "N*m"}}
SYNTHETIC_HORIZON = 22.0
STATUS_CYCLE = ("isolated", "indistinguishable", "undecided", "isolated", "rejected")


def synthetic_fleet(count: int, *, rul_rows: int = 30, samples: int = 4001, seed: int = 0,
                    rename: dict | None = None):
    """The tables of a fleet of ``count`` assets as a run would write them, without running a filter.

    Asset ``k`` (id ``motor-00007``) stays healthy when ``k % 4 == 0``, alarms without a RUL when ``k % 50 == 1``,
    and its record is skipped when ``k % 100 == 2``; the others alarm at a time of their own and get
    ``rul_rows`` RUL rows and as many estimate rows of each of the two hypotheses (b/linear, b/exponential),
    from the alarm to the record's end (4 s), the first few with a censored p95.  Every monitored asset has both
    ARRs' residual traces (:func:`prognosis.fleet.traces.residual_trace` of a noisy ``samples``-sample record).

    ``rename`` gives some assets other ids (``{"motor-00007": "a </script> id"}``).  Returns ``(result, summary,
    assets)``: a :class:`~prognosis.fleet.FleetResult`, the summary (spec, records, skipped) and every asset id.
    """
    from diagnosis.detection import Evaluation
    from prognosis.fleet import FleetResult
    from prognosis.fleet.traces import residual_trace

    rng = np.random.default_rng(seed)
    assets = [(rename or {}).get(f"motor-{k:05d}", f"motor-{k:05d}") for k in range(count)]
    skipped = {a: "column 'i' has no value (every cell is empty or NaN)" for k, a in enumerate(assets) if k % 100 == 2}
    result = FleetResult()
    t = np.linspace(0.0, 4.0, samples)
    flags = np.zeros(samples, bool)
    for k, asset in enumerate(assets):
        if asset in skipped:
            continue
        onset = None if k % 4 == 0 else 1.0 + 1.5 * rng.random()
        for m, (arr, noise) in enumerate((("ARR_1_e", 0.02), ("ARR_1_m", 0.01))):
            drift = 0.0 if onset is None or m == 0 else np.maximum(0.0, t - onset) ** 2 * 0.05
            band = 0.05 + 0.02 * np.sin(3 * t + k)
            evaluation = Evaluation(arr, t, -(drift + noise * rng.standard_normal(samples)), lower=-band, upper=band,
                                    bglft=band, margin=0.03, persistence=5, violation=flags, alarm=flags)
            trace = residual_trace(evaluation)
            result.add("residuals", asset=[asset] * trace["t"].size, arr=[arr] * trace["t"].size, **trace)
        if onset is None:
            continue
        alarm = onset + 0.3
        result.add("alarms", asset=[asset], t=[alarm], arr=["ARR_1_m"])
        if k % 50 == 1:
            continue
        _synthetic_rows(result, asset, alarm, rul_rows, STATUS_CYCLE[k % len(STATUS_CYCLE)], rng)
    summary = {"records": f"synthetic ({count} assets)", "skipped": skipped, "assets": count,
               "spec": {"model": "dc-motor", "failures": {"b": 2e-3}, "laws": ["linear", "exponential"],
                        "noise_std": {"ARR_1_e": 0.023, "ARR_1_m": 0.0124}, "n_particles": 500, "dt": 0.011,
                        "rul_every": 10, "healthy_until": 0.9, "seed": 0}}
    return result, summary, assets


def _synthetic_rows(result, asset: str, alarm: float, rows: int, status: str, rng) -> None:
    """Estimates of both hypotheses and the RUL of one asset from its alarm: b grows towards 2e-3."""
    times = np.linspace(alarm, 4.0, rows)  # to the record's end
    step = 10 * np.arange(rows)
    life = 4.0 - alarm + 0.2 + 4.0 * rng.random()  # s from the alarm: beyond the last prediction
    p50 = life - (times - alarm)
    spread = 0.2 + 0.5 * rng.random()
    p95 = p50 * (1.0 + 2.0 * spread)
    p95[: rows // 6] = np.inf  # the first predictions: more than 5 % of the particles beyond the horizon
    for law in ("linear", "exponential"):
        mean = 2e-4 + 1.6e-3 * (times - alarm) / (life + times[-1] - alarm) + 2e-5 * rng.standard_normal(rows)
        result.add("estimates", asset=[asset] * rows, hypothesis=[f"b/{law}"] * rows, step=step, t=times,
                   theta_mean=mean, theta_p5=mean * 0.9, theta_p50=mean, theta_p95=mean * 1.1, gamma_mean=mean,
                   gamma_p5=mean, gamma_p50=mean, gamma_p95=mean, ess=np.full(rows, 300.0),
                   log_evidence=np.cumsum(rng.standard_normal(rows)))
    result.add("rul", asset=[asset] * rows, step=step, t=times, mean=p50 * 1.1, p5=p50 * (1.0 - spread), p50=p50,
               p95=p95, censored=np.where(np.isinf(p95), 0.1, 0.0), hypothesis=["b/exponential"] * rows,
               probability=np.linspace(0.5, 0.95, rows), status=[status] * rows)
