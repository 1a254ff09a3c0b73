"""Gasperin et al. (2011): gearbox fault trend and prognosis from an online-identified state-space model.

    python examples/gearbox.py [--out results/gearbox] [--seeds 5] [--seed 0] [--hours 180] [--fault-gain 6e-5]
                               [--workers 2] [--quiet]

The paper's test-bed data are not public, so this example generates a record in the paper's setting
(section 4) and runs the paper's method (sections 3.4, 5.1, 5.2) on it:

1. synthetic record, one sample every 5 min for 180 h: torque (piecewise-constant load, a random level
   between 40 and 100 N m every 2-6 h), oil temperature (a first-order lag, 1.5 h, following the
   torque plus a 22 C ambient with a 1 C daily swing) and one vibration feature (sideband energy);
2. the feature comes from a 2-state linear Gaussian model (the paper's eqs. 2-3, see ``TRUTH``): a load mode
   (pole 0.9) and a damage mode driven by the torque.  The damage pole is 0.6 until the fault onset at
   55 h and 1.003 after (3.7 % growth per hour): the feature starts to grow slowly, faster under load;
3. ``OnlineEM`` re-identifies a model with n = 2 states, r = 2 inputs, m = 1 output on the last N = 200
   samples (16.7 h, section 5) every hour, with 5 EM steps warm-started from the previous model;
4. trend detection (section 5.1): alarm when the spectral radius of A has stayed above 1 for 3
   consecutive identifications; the alarm time is compared with the onset and no alarm may occur before;
5. long-term prediction (section 5.2) with the model available at 44 h (before the fault: predicted
   stable) and at 78 h (after: predicted growing) under the known future load profile, with the 95 %
   interval of ``predict_feature``; its empirical coverage over the later synthetic feature values.  A
   window whose identified model predicts an impossible feature (non-finite, or a negative sideband energy:
   ``divergence``) is counted as a failure of that window, and the change at constant load is summarized
   over the other windows only;
6. the same predictions with the posterior predictive over the window's parameters
   (``prognosis.sample_posterior``), and its coverage.  ``--fault-gain 6e-6`` gives the subtle fault of
   docs/gearbox.md, whose window at 78 h does not reveal the unstable pole.

The figures are reported as mean, min and max over ``--seeds`` record seeds (load profile, noises).
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from bgphm.plotting import band, pyplot, save_figure, write_figures
from bgphm.runs import over_seeds, progress_line, run_main
from prognosis.identification import (FeaturePrediction, IdentificationWarning, LinearGaussianModel, OnlineEM,
                                      detect_trend, fault_trend, predict_feature)
from prognosis.identification.predictive import PosteriorPrediction, sample_posterior

# Gasperin et al. (2011), section 4: one acquisition every 5 min, about 180 h, fault around 55 h
STEP_H = 5.0 / 60.0
DURATION_H = 180.0
ONSET_H = 55.0

# Operating conditions (our choice: the paper shows its load profile only as a figure)
TORQUE_NM = (40.0, 100.0)  # range of the random load levels
SEGMENT_H = (2.0, 6.0)  # each level lasts a uniform random time in this range
AMBIENT_C = 22.0
AMBIENT_SWING_C = 1.0  # daily sinusoid
THERMAL_LAG_H = 1.5
HEATING_C_PER_NM = 0.25  # steady-state oil temperature rise per N m of torque
TEMPERATURE_NOISE_C = 0.05  # random disturbance of the temperature per step

# The truth: state (load-induced sideband energy s, damage d), inputs (torque, temperature), per 5-min step
TRUTH = {
    "load_pole": 0.9,  # s settles in about 50 min after a load change
    "load_gain": 0.001,  # s_{t+1} = 0.9 s_t + 0.001 torque_t: s = 0.01 per N m at steady state
    "fault_pole_before": 0.6,  # damage mode well inside the unit circle before the onset
    "fault_pole_after": 1.003,  # slightly outside after it
    "fault_gain": 6e-5,  # torque drive of the damage (per N m): the damage is visible at 78 h, as in the paper
    "temperature_gain": 0.01,  # direct effect of the temperature on the feature (per C)
    "load_noise": 0.005,  # std of w on s
    "fault_noise": 0.003,  # std of w on d
    "measurement_noise": 0.02,  # std of v
}

# The method (the paper's section 5: n = 2, r = 2, m = 1, N = 200; cadence and EM steps are our choice)
IDENTIFICATION = {"n_states": 2, "window": 200, "every": 12, "iterations": 5, "initial_iterations": 200}
DETECTION = {"threshold": 1.0, "persistence": 3}
PREDICT_AT_H = (44.0, 78.0)  # the paper's Figs. 5-7
# The posterior predictive over the window's parameters (prognosis.identification.predictive, not in the paper).
# The oil temperature (input 1) changes the feature's level directly (D), it does not drive the damage:
# declared so, it cannot act as a free drift of the growing mode, which biased its growth rate low
# (--temperature-in-state gives the paper's general B back, for comparison).
POSTERIOR = {"particles": 2000, "moves": 5, "target_ess": 0.7, "max_radius": 1.05, "direct_inputs": (1,)}
HORIZON_H = 42.0  # to 120 h from 78 h, the end of the paper's Figs. 6-7
# The feature is a sideband *energy*: a predicted mean below it is impossible, whatever the fault.  An identified
# model whose prediction goes there (e.g. an unstable complex pole pair, an oscillation of growing amplitude) has
# failed on its window; a real pole above 1 (a growing damage) is the fault trend and stays admissible.
FEATURE_MIN = 0.0
LEVEL = 0.95
LEAD_BANDS_H = ((0.0, 1.0), (1.0, 6.0), (6.0, 12.0), (12.0, 24.0), (24.0, 42.0))


def samples(hours: float) -> int:
    """Number of 5-min samples in ``hours`` (sample i is at i * STEP_H hours)."""
    return int(round(hours / STEP_H))


def load_profile(rng: np.random.Generator, steps: int) -> np.ndarray:
    """Torque (N m): piecewise constant, a uniform random level held for a uniform random 2-6 h."""
    torque = np.empty(steps)
    start = 0
    while start < steps:
        length = samples(rng.uniform(*SEGMENT_H))
        torque[start:start + length] = rng.uniform(*TORQUE_NM)
        start += length
    return torque


def oil_temperature(torque: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Temperature (C): first-order lag (THERMAL_LAG_H) towards ambient + HEATING_C_PER_NM * torque."""
    hours = STEP_H * np.arange(torque.size)
    target = AMBIENT_C + AMBIENT_SWING_C * np.sin(2 * np.pi * hours / 24.0) + HEATING_C_PER_NM * torque
    alpha = STEP_H / THERMAL_LAG_H
    temperature = np.empty(torque.size)
    theta = target[0]
    for t in range(torque.size):
        temperature[t] = theta
        theta += alpha * (target[t] - theta) + TEMPERATURE_NOISE_C * rng.standard_normal()
    return temperature


def true_model(faulty: bool, mu1=None, P1=None, fault_gain: float | None = None) -> LinearGaussianModel:
    """The 2-state truth before (``faulty=False``) or after the onset, as a LinearGaussianModel."""
    fault_pole = TRUTH["fault_pole_after" if faulty else "fault_pole_before"]
    gain = TRUTH["fault_gain"] if fault_gain is None else fault_gain
    return LinearGaussianModel(
        A=np.diag([TRUTH["load_pole"], fault_pole]),
        B=[[TRUTH["load_gain"], 0.0], [gain, 0.0]],
        C=[[1.0, 1.0]], D=[[0.0, TRUTH["temperature_gain"]]],
        Q=np.diag([TRUTH["load_noise"] ** 2, TRUTH["fault_noise"] ** 2]), R=[[TRUTH["measurement_noise"] ** 2]],
        mu1=mu1, P1=np.zeros((2, 2)) if P1 is None else P1)


@dataclass
class Record:
    """One synthetic run (row i is time i * STEP_H hours)."""

    seed: int
    hours: np.ndarray  # (T,)
    inputs: np.ndarray  # (T, 2) torque (N m), temperature (C)
    feature: np.ndarray  # (T,) y
    states: np.ndarray  # (T, 2) true s, d
    onset: int  # first sample whose transition uses the unstable damage pole
    fault_gain: float  # torque drive of the damage (TRUTH["fault_gain"] unless changed)


def simulate(seed: int, hours: float = DURATION_H, fault_gain: float | None = None) -> Record:
    """Inputs, true states and feature: the pre-fault model up to the onset sample, the faulty one after.

    The full DURATION_H record is drawn and cut to ``hours``, so a shorter record is the start of the long one.
    """
    rng = np.random.default_rng(seed)
    keep = samples(hours)
    steps = max(keep, samples(DURATION_H))
    torque = load_profile(rng, steps)
    inputs = np.column_stack([torque, oil_temperature(torque, rng)])
    onset = min(samples(ONSET_H), steps - 1)
    gain = TRUTH["fault_gain"] if fault_gain is None else fault_gain
    steady = np.array([TRUTH["load_gain"] / (1 - TRUTH["load_pole"]),
                       gain / (1 - TRUTH["fault_pole_before"])]) * torque[0]
    healthy = true_model(False, mu1=steady, fault_gain=gain)
    x, y = healthy.simulate(inputs[:onset + 1], rng)
    if onset + 1 < steps:  # x_{onset+1} = A_faulty x_onset + B u_onset + w: its mean and covariance start the rest
        faulty = true_model(True, fault_gain=gain)
        start = faulty.A @ x[-1] + faulty.B @ inputs[onset]
        x2, y2 = replace(faulty, mu1=start, P1=faulty.Q).simulate(inputs[onset + 1:], rng)
        x, y = np.vstack([x, x2]), np.vstack([y, y2])
    return Record(seed, STEP_H * np.arange(keep), inputs[:keep], y[:keep, 0], x[:keep], onset, gain)


@dataclass
class Identified:
    """The online identification of one record."""

    times: np.ndarray  # (K,) sample index of the newest sample of each identification window
    radii: np.ndarray  # (K,) spectral radius of A
    eigenvalues: np.ndarray  # (K, 2)
    predictions: dict  # "44h" -> Prediction
    seconds: float


@dataclass
class Prediction:
    at: int  # sample index of the prediction time T (the feature is predicted from T + 1)
    model: LinearGaussianModel
    load: FeaturePrediction  # under the known future load profile
    constant: FeaturePrediction  # under the load and temperature held at their values at T (the paper's Fig. 5)
    oracle: FeaturePrediction  # the true model (the one in force at T) from the true state at T, known load
    posterior: PosteriorPrediction  # posterior predictive over the window's parameters, known load
    radii: np.ndarray  # posterior draws of rho(A)
    posterior_seconds: float


def identify(record: Record, posterior: dict = POSTERIOR) -> Identified:
    """OnlineEM over the record, with the long-term predictions made on the way at PREDICT_AT_H.

    ``posterior``: the settings of ``sample_posterior`` for the posterior predictive.
    """
    online = OnlineEM(**IDENTIFICATION)
    steps = record.feature.size
    horizon = samples(HORIZON_H)
    origins = {f"{h:g}h": samples(h) for h in PREDICT_AT_H if samples(h) < steps - 1}
    predictions = {}
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentificationWarning)  # counted below instead
        for t in range(steps):
            online.update(record.feature[t], record.inputs[t])
            for name, at in origins.items():
                if t == at and online.model is not None:
                    predictions[name] = predict_from(online, record, at, horizon, posterior)
    seconds = time.perf_counter() - start
    return Identified(np.array([h.time for h in online.history]), np.array([h.spectral_radius for h in online.history]),
                      np.array([h.eigenvalues for h in online.history]), predictions, seconds)


def predict_from(online: OnlineEM, record: Record, at: int, horizon: int, posterior: dict = POSTERIOR
                 ) -> Prediction:
    """Gasperin et al. (2011), section 5.2: the filtered state at T through the current model under future inputs."""
    smoothed = online.smoother()
    future = record.inputs[at + 1:at + 1 + horizon]  # shorter than the horizon near the end of the record
    held = np.repeat(record.inputs[at:at + 1], future.shape[0], axis=0)
    model = online.model
    truth = true_model(at >= record.onset, fault_gain=record.fault_gain)
    oracle = predict_feature(truth, truth.A @ record.states[at] + truth.B @ record.inputs[at], truth.Q, future, LEVEL)
    start = time.perf_counter()
    y_window, u_window = online.window_data()
    window = sample_posterior(y_window, u_window, IDENTIFICATION["n_states"], seed=record.seed, **posterior)
    predictive = window.predict(future, LEVEL)
    return Prediction(at, model,
                      predict_feature(model, smoothed.next_mean, smoothed.next_covariance, future, LEVEL),
                      predict_feature(model, smoothed.next_mean, smoothed.next_covariance, held, LEVEL), oracle,
                      predictive, window.spectral_radii, time.perf_counter() - start)


def coverage(prediction: FeaturePrediction | PosteriorPrediction, truth: np.ndarray, first: int = 0,
             last: int | None = None) -> float | None:
    """Fraction of ``truth`` (the feature from T + 1 on) inside the interval, over leads first..last - 1."""
    lower, upper = (np.reshape(b, (b.shape[0], -1))[:, 0] for b in (prediction.lower, prediction.upper))
    last = min(lower.size, truth.size) if last is None else min(last, truth.size)
    if last <= first:
        return None
    y = truth[first:last]
    return float(np.mean((y >= lower[first:last]) & (y <= upper[first:last])))


def divergence(*means: np.ndarray) -> str | None:
    """Why a window's predicted feature means are impossible, or None when they are admissible.

    Parameters
    ----------
    *means : ndarray
        Predicted mean paths of the feature (e.g. under the known load and at constant load).

    Returns
    -------
    str or None
        ``"non-finite"`` when a mean overflows, ``"below FEATURE_MIN (min ...)"`` when it predicts a
        negative energy, None otherwise.

    Examples
    --------
    >>> divergence(np.array([1.0, 2.0, 40.0])) is None
    True
    >>> divergence(np.array([1.0, np.inf]))
    'non-finite'
    >>> divergence(np.array([1.0, 0.5]), np.array([1.0, -429.3]))
    'below FEATURE_MIN (min -429.3)'
    """
    values = np.concatenate([np.ravel(m) for m in means])
    if not np.all(np.isfinite(values)):
        return "non-finite"
    if values.size and values.min() < FEATURE_MIN:
        return f"below FEATURE_MIN (min {values.min():.4g})"
    return None


def change_statistics(rows: list[dict], seeds: list[int]) -> dict:
    """The constant-load change over the admissible windows, the divergent ones counted as failures.

    Parameters
    ----------
    rows : list of dict
        ``prediction_figures`` of one prediction time, one per record (``"constant_load_change"`` and
        ``"divergent"``: the reason, or None).
    seeds : list of int
        The record seed of each row.

    Returns
    -------
    dict
        ``mean, median, min, max`` over the admissible windows (None if there are none), ``n`` their number,
        ``of`` the number of windows, ``divergent`` the number of failures and ``divergent_seeds`` theirs.

    Examples
    --------
    >>> rows = [{"constant_load_change": c, "divergent": d} for c, d in ((1.0, None), (-429.0, "below"), (3.0, None))]
    >>> out = change_statistics(rows, [0, 1, 2])
    >>> out["median"], out["n"], out["of"], out["divergent"], out["divergent_seeds"]
    (2.0, 2, 3, 1, [1])
    """
    kept = [r["constant_load_change"] for r in rows if r["divergent"] is None]
    failed = [seed for r, seed in zip(rows, seeds) if r["divergent"] is not None]
    values = np.array(kept, float)
    figures = {"mean": float(values.mean()), "median": float(np.median(values)), "min": float(values.min()),
               "max": float(values.max())} if values.size else {"mean": None, "median": None, "min": None,
                                                                  "max": None}
    return {**figures, "n": int(values.size), "of": len(rows), "divergent": len(failed), "divergent_seeds": failed}


def prediction_figures(p: Prediction, record: Record) -> dict:
    """Coverage over the horizon, by lead-time band and (before the onset) over the pre-fault part."""
    truth = record.feature[p.at + 1:p.at + 1 + p.load.mean.shape[0]]
    bands = {f"{a:g}-{b:g}h": coverage(p.load, truth, samples(a), samples(b)) for a, b in LEAD_BANDS_H}
    out = {
        "time_h": p.at * STEP_H, "spectral_radius": p.model.spectral_radius,
        "eigenvalues": [str(np.round(v, 5)) for v in p.model.eigenvalues],
        "fault_trend": fault_trend(p.model), "horizon_h": truth.size * STEP_H,
        "constant_load_change": float(p.constant.mean[-1, 0] - p.constant.mean[0, 0]),
        "constant_load_change_first_half": float(p.constant.mean[truth.size // 2, 0] - p.constant.mean[0, 0]),
        "divergent": divergence(p.load.mean[:, 0], p.constant.mean[:, 0]),
        "coverage": coverage(p.load, truth), "coverage_by_lead": bands,
        "mean_abs_error_end": float(abs(truth[-1] - p.load.mean[truth.size - 1, 0])) if truth.size else None,
        "interval_half_width_end": float(p.load.upper[truth.size - 1, 0] - p.load.mean[truth.size - 1, 0])
        if truth.size else None,
    }
    # the same interval from the true model and state: how much of the miss is identification error
    valid = truth.size if p.at >= record.onset else min(truth.size, record.onset - p.at)
    out["oracle_coverage"] = coverage(p.oracle, truth, 0, valid)
    if p.at < record.onset:
        out["coverage_before_onset"] = coverage(p.load, truth, 0, record.onset - p.at)
    # the posterior predictive over the window's parameters
    posterior = {
        "coverage": coverage(p.posterior, truth),
        "coverage_by_lead": {f"{a:g}-{b:g}h": coverage(p.posterior, truth, samples(a), samples(b))
                             for a, b in LEAD_BANDS_H},
        "spectral_radius_quantiles": np.quantile(p.radii, [0.05, 0.5, 0.95]).tolist(),
        "probability_unstable": float(np.mean(p.radii > 1.0)),
        # posterior mass below the true rho(A) of the window (the truth at T): uniform over records if calibrated
        "true_radius_rank": float(np.mean(p.radii < true_model(p.at >= record.onset).spectral_radius)),
        "interval_half_width_end": float(0.5 * (p.posterior.upper[truth.size - 1] - p.posterior.lower[truth.size - 1]))
        if truth.size else None,
        "seconds": p.posterior_seconds,
    }
    if p.at < record.onset:
        posterior["coverage_before_onset"] = coverage(p.posterior, truth, 0, record.onset - p.at)
    out["posterior"] = posterior
    return out


def run_seed(seed: int, hours: float = DURATION_H, keep: bool = False, fault_gain: float | None = None,
             posterior: dict = POSTERIOR) -> dict:
    """Simulate, identify online, detect the trend and predict, for one record seed."""
    record = simulate(seed, hours, fault_gain)
    found = identify(record, posterior)
    onset_h = record.onset * STEP_H
    before = found.times < record.onset
    alarm = detect_trend(found.radii, **DETECTION)
    early = detect_trend(found.radii[before], **DETECTION) if before.any() else None
    detection_h = None if alarm is None else float(found.times[alarm] * STEP_H)
    result = {
        "seed": seed, "onset_h": onset_h, "identifications": int(found.times.size),
        "first_identification_h": float(found.times[0] * STEP_H) if found.times.size else None,
        "detection_time_h": detection_h, "detection_delay_h": None if detection_h is None else detection_h - onset_h,
        "alarm_before_onset": early is not None,
        "max_radius_before_onset": float(found.radii[before].max()) if before.any() else None,
        "fraction_above_one_after_detection": float(np.mean(found.radii[alarm:] > DETECTION["threshold"]))
        if alarm is not None else None,
        "seconds": found.seconds,
        "predictions": {name: prediction_figures(p, record) for name, p in found.predictions.items()},
    }
    if keep:
        result["record"], result["identified"] = record, found
    return result


def summarize(results: list[dict]) -> dict:
    """Mean, min and max over seeds of the detection and coverage figures."""
    def stats(values):
        values = [v for v in values if v is not None]
        if not values:
            return None
        return {"mean": float(np.mean(values)), "median": float(np.median(values)), "min": float(np.min(values)),
                "max": float(np.max(values)), "n": len(values)}

    delays = [r["detection_delay_h"] for r in results]
    summary = {
        "seeds": [r["seed"] for r in results],
        "detected_in": sum(d is not None for d in delays), "of": len(results),
        "alarms_before_onset": sum(r["alarm_before_onset"] for r in results),
        "detection_time_h": stats([r["detection_time_h"] for r in results]),
        "detection_delay_h": stats(delays),
        "max_radius_before_onset": stats([r["max_radius_before_onset"] for r in results]),
        "seconds_per_seed": stats([r["seconds"] for r in results]),
        "predictions": {},
    }
    for name in results[0]["predictions"]:
        seeds = [r["seed"] for r in results if name in r["predictions"]]
        rows = [r["predictions"][name] for r in results if name in r["predictions"]]
        entry = {
            "spectral_radius": stats([p["spectral_radius"] for p in rows]),
            "fault_trend_in": sum(p["fault_trend"] for p in rows),
            # a divergent window is a failure of the identification, not a sample of the change
            "constant_load_change": change_statistics(rows, seeds),
            "coverage": stats([p["coverage"] for p in rows]),
            "oracle_coverage": stats([p["oracle_coverage"] for p in rows]),
            "coverage_by_lead": {band: stats([p["coverage_by_lead"][band] for p in rows])
                                 for band in rows[0]["coverage_by_lead"]},
        }
        if "coverage_before_onset" in rows[0]:
            entry["coverage_before_onset"] = stats([p["coverage_before_onset"] for p in rows])
        posterior = [p["posterior"] for p in rows]
        entry["posterior"] = {
            "coverage": stats([p["coverage"] for p in posterior]),
            "coverage_by_lead": {band: stats([p["coverage_by_lead"][band] for p in posterior])
                                 for band in posterior[0]["coverage_by_lead"]},
            "coverage_at_least_0.9_in": sum(p["coverage"] is not None and p["coverage"] >= 0.9 for p in posterior),
            "probability_unstable": stats([p["probability_unstable"] for p in posterior]),
            "median_spectral_radius": stats([p["spectral_radius_quantiles"][1] for p in posterior]),
            "true_radius_rank": stats([p["true_radius_rank"] for p in posterior]),
            "true_radius_rank_above_0.95_in": sum(p["true_radius_rank"] > 0.95 for p in posterior),
            "seconds": stats([p["seconds"] for p in posterior]),
        }
        if "coverage_before_onset" in posterior[0]:
            entry["posterior"]["coverage_before_onset"] = stats([p["coverage_before_onset"] for p in posterior])
        summary["predictions"][name] = entry
    return summary


def write(out: Path, summary: dict, results: list[dict], first: dict, seconds: float,
          posterior: dict = POSTERIOR) -> list[Path]:
    """results.json and, with matplotlib, the figures of the first seed."""
    out.mkdir(parents=True, exist_ok=True)
    gain = first["record"].fault_gain
    truth = {"healthy": _matrices(true_model(False, fault_gain=gain)),
             "faulty": _matrices(true_model(True, fault_gain=gain))}
    payload = {
        "setting": {"step_h": STEP_H, "duration_h": first["record"].hours[-1] + STEP_H, "onset_h": ONSET_H,
                    "torque_nm": TORQUE_NM, "segment_h": SEGMENT_H, "ambient_c": AMBIENT_C,
                    "ambient_swing_c": AMBIENT_SWING_C, "thermal_lag_h": THERMAL_LAG_H,
                    "heating_c_per_nm": HEATING_C_PER_NM, "truth": {**TRUTH, "fault_gain": gain},
                    "identification": IDENTIFICATION, "detection": DETECTION, "predict_at_h": PREDICT_AT_H,
                    "horizon_h": HORIZON_H, "level": LEVEL, "posterior": posterior},
        "true_models": truth,
        "summary": summary,
        "run_seconds": seconds,
        "per_seed": [{k: v for k, v in r.items() if k not in ("record", "identified")} for r in results],
    }
    paths = [out / "results.json"]
    paths[0].write_text(json.dumps(payload, indent=2, default=_json))
    return paths + write_figures(plot, out, first)


def plot(out: Path, first: dict) -> list[Path]:
    """fig00 record, fig01 spectral radius, fig02/fig03 the predictions at 44 h and 78 h (first seed)."""
    plt = pyplot("Agg")

    record, found = first["record"], first["identified"]
    onset_h, detection_h = record.onset * STEP_H, first["detection_time_h"]
    paths = []

    fig, (ax_u, ax_t, ax_y) = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    ax_u.plot(record.hours, record.inputs[:, 0], lw=1)
    ax_u.set_ylabel("torque (N m)")
    ax_t.plot(record.hours, record.inputs[:, 1], lw=1, color="tab:red")
    ax_t.set_ylabel("temperature (C)")
    ax_y.plot(record.hours, record.feature, ".", ms=1.5, color="k")
    ax_y.set_ylabel("sideband energy")
    ax_y.set_xlabel("time (h)")
    for ax in (ax_u, ax_t, ax_y):
        ax.axvline(onset_h, color="tab:orange", ls="--", lw=1, label="fault onset")
        if detection_h is not None:
            ax.axvline(detection_h, color="tab:green", ls=":", lw=1.5, label="trend detected")
    ax_y.legend(loc="upper left")
    paths.append(save_figure(fig, out / "fig00_record.png"))

    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(found.times * STEP_H, found.radii, lw=1.2, label="spectral radius of A")
    ax.axhline(DETECTION["threshold"], color="r", lw=1, label="threshold")
    ax.axvline(onset_h, color="tab:orange", ls="--", lw=1, label="fault onset")
    if detection_h is not None:
        ax.axvline(detection_h, color="tab:green", ls=":", lw=1.5, label=f"alarm at {detection_h:.1f} h")
    ax.set_xlabel("time (h)")
    ax.set_ylabel("rho(A)")
    ax.legend(fontsize=8)
    paths.append(save_figure(fig, out / "fig01_spectral_radius.png"))

    for number, (name, p) in enumerate(found.predictions.items(), start=2):
        fig, ax = plt.subplots(figsize=(8, 3.8))
        lead = record.hours[p.at] + STEP_H * np.arange(1, p.load.mean.shape[0] + 1)
        shown = (record.hours >= max(0.0, record.hours[p.at] - 20.0)) & (record.hours <= lead[-1])
        ax.plot(record.hours[shown], record.feature[shown], ".", ms=2, color="0.4", label="feature (synthetic)")
        ax.plot(lead, p.load.mean[:, 0], color="tab:blue", label="predicted mean, known load")
        band(ax, lead, p.load.lower[:, 0], p.load.upper[:, 0], color="tab:blue", alpha=0.2,
             label=f"{LEVEL:.0%} interval (identified model)")
        ax.plot(lead, p.posterior.median, color="tab:green", lw=1, label="posterior predictive median")
        band(ax, lead, p.posterior.lower, p.posterior.upper, color="tab:green", alpha=0.15,
             label=f"{LEVEL:.0%} posterior predictive interval")
        ax.plot(lead, p.constant.mean[:, 0], color="tab:purple", ls="--", lw=1, label="predicted mean, constant load")
        ax.axvline(record.hours[p.at], color="k", lw=1)
        if record.hours[p.at] - 20.0 <= onset_h <= lead[-1]:
            ax.axvline(onset_h, color="tab:orange", ls="--", lw=1, label="fault onset")
        ax.set_title(f"prediction at T = {name} (rho(A) = {p.model.spectral_radius:.4f})")
        ax.set_xlabel("time (h)")
        ax.set_ylabel("sideband energy")
        ax.legend(fontsize=8, loc="upper left")
        paths.append(save_figure(fig, out / f"fig{number:02d}_prediction_{name}.png"))
    return paths


def _matrices(model: LinearGaussianModel) -> dict:
    return {name: getattr(model, name).tolist() for name in ("A", "B", "C", "D", "Q", "R")}


def _json(value):
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serializable: {type(value).__name__}")


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description="Gasperin et al. (2011) on a synthetic gearbox record: online EM "
                                                 "identification, fault-trend detection and long-term prediction")
    parser.add_argument("--out", type=Path, default=Path("results/gearbox"),
                        help="directory for results.json and the figures (default results/gearbox)")
    parser.add_argument("--seed", type=int, default=0, help="first record seed (default 0)")
    parser.add_argument("--seeds", type=int, default=5, help="number of record seeds (default 5)")
    parser.add_argument("--hours", type=float, default=DURATION_H,
                        help=f"record length in hours (default {DURATION_H:g}; shorter for a quick check)")
    parser.add_argument("--fault-gain", type=float, default=TRUTH["fault_gain"],
                        help=f"torque drive of the damage per N m (default {TRUTH['fault_gain']:g}; 6e-6 is the "
                             "subtle fault of docs/gearbox.md)")
    parser.add_argument("--temperature-in-state", action="store_true",
                        help="let the oil temperature drive the state in the posterior predictive's model too "
                             "(the paper's general B; by default it acts on the feature through D only)")
    parser.add_argument("--workers", type=int, default=2, help="processes over seeds (default 2)")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be at least 1")
    if not (np.isfinite(args.fault_gain) and args.fault_gain >= 0):
        parser.error(f"--fault-gain must be a finite non-negative number, got {args.fault_gain}")
    minimum = (IDENTIFICATION["window"] + 1) * STEP_H
    if not args.hours > minimum:
        parser.error(f"--hours must exceed one identification window ({minimum:.1f} h)")
    seeds = list(range(args.seed, args.seed + args.seeds))
    print(f"Gasperin et al. (2011) on a synthetic gearbox record: {args.hours:g} h at {STEP_H * 60:g} min, "
          f"fault onset at {ONSET_H:g} h, damage drive {args.fault_gain:g} per N m, "
          f"window N = {IDENTIFICATION['window']}, {len(seeds)} seeds")
    start = time.perf_counter()
    posterior = {**POSTERIOR, "direct_inputs": ()} if args.temperature_in_state else POSTERIOR
    results = over_seeds(run_seed, [(seed, args.hours, i == 0, args.fault_gain, posterior)
                                    for i, seed in enumerate(seeds)],
                         workers=max(1, args.workers), progress=progress_line(args.quiet))
    seconds = time.perf_counter() - start
    summary = summarize(results)
    summary["run_seconds"] = seconds
    _report(summary)
    if args.out:
        for path in write(args.out, summary, results, results[0], seconds, posterior):
            print(f"  wrote {path}")
    return summary


def _change_text(change: dict) -> str:
    """The constant-load change over the admissible windows, and the divergent ones named as failures."""
    if change["n"]:
        text = (f"change at constant load median {change['median']:+.3f} ({change['min']:+.3f} to "
                f"{change['max']:+.3f}) over {change['n']} of {change['of']} windows")
    else:
        text = f"change at constant load: no admissible window of {change['of']}"
    if change["divergent"]:
        seeds = ", ".join(str(s) for s in change["divergent_seeds"])
        plural = "s" if change["divergent"] > 1 else ""
        text += (f"; {change['divergent']} divergent window{plural} (seed{plural} {seeds}) "
                 f"reported as a failure")
    return text


def _report(summary: dict) -> None:
    delay = summary["detection_delay_h"]
    print(f"  trend detected in {summary['detected_in']}/{summary['of']} records"
          + ("" if delay is None else f", {delay['mean']:.1f} h after the onset (min {delay['min']:.1f}, "
                                      f"max {delay['max']:.1f})")
          + f"; alarms before the onset: {summary['alarms_before_onset']}")
    radius = summary["max_radius_before_onset"]
    if radius is not None:
        print(f"  largest spectral radius before the onset: {radius['max']:.4f}")
    for name, p in summary["predictions"].items():
        cov = p["coverage"]
        line = (f"  prediction at {name}: rho(A) {p['spectral_radius']['mean']:.4f} (fault trend in "
                f"{p['fault_trend_in']}/{p['spectral_radius']['n']}), {_change_text(p['constant_load_change'])}; "
                f"{LEVEL:.0%} coverage over the horizon "
                f"{cov['mean']:.2f} (min {cov['min']:.2f})")
        if "coverage_before_onset" in p and p["coverage_before_onset"] is not None:
            line += f", before the onset {p['coverage_before_onset']['mean']:.2f}"
        if p["oracle_coverage"] is not None:
            line += f"; true model and state: {p['oracle_coverage']['mean']:.2f}"
        print(line)
        print("    by lead time: " + ", ".join(f"{band} {s['mean']:.2f}" for band, s in p["coverage_by_lead"].items()
                                              if s is not None))
        post = p["posterior"]
        coverage = post["coverage"]
        line = (f"    posterior predictive: coverage {coverage['mean']:.2f} (min {coverage['min']:.2f}, "
                f">= 0.9 in {post['coverage_at_least_0.9_in']}/{post['coverage']['n']})")
        if post.get("coverage_before_onset") is not None:
            line += f", before the onset {post['coverage_before_onset']['mean']:.2f}"
        line += (f"; P(rho(A) > 1) {post['probability_unstable']['mean']:.2f}; true rho(A)'s rank in the posterior "
                 f"{post['true_radius_rank']['mean']:.2f} ({post['true_radius_rank']['min']:.2f}-"
                 f"{post['true_radius_rank']['max']:.2f}, > 0.95 in {post['true_radius_rank_above_0.95_in']})")
        print(line)
        by_lead = post["coverage_by_lead"].items()
        print("      by lead time: " + ", ".join(f"{band} {s['mean']:.2f}" for band, s in by_lead if s is not None))
    print(f"  run time {summary['run_seconds']:.1f} s")


if __name__ == "__main__":
    run_main(main)
