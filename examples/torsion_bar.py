"""Jha et al. (2016) end to end on the torsion-bar mechatronic system.

    python examples/torsion_bar.py [--case b-md|mass-linear|mass-exponential]
                                   [--preset default|paper] [--seed 0] [--runs K] [--out DIR]
                                   [--datasheet true|wrong|wrong-uncalibrated]

1. builds the torsion-bar bond graph (Jha et al. (2016), Figs. 5-7, Table VI, k_m =
   3.89e-2 N.m/A per docs/design.md) and simulates the PI speed loop (omega_Md at
   30 rad/s, 12 V saturation) twice: nominal, and with the case's degradation;
2. derives the I-ARR of the monitorable part from the bond graph (ARR_1_1,
   eqs. 45-49; eqs. 57-58 with the suspended load), calibrates a noise margin
   on a separate nominal record, and detects the degradation with interval
   thresholds on noisy records (speeds with 0.01 rad/s noise, encoder angles
   at 2000 counts per revolution, the motor torque k_m i as known input);
3. starts the particle filter at detection (dt = 0.1 s, N = 500 or 50),
   estimates theta and gamma, and predicts the RUL at every filter step;
4. computes the figures of Jha et al. (2016), section 5, and prints them beside
   the paper's; with ``--out DIR`` writes ``results.json``, ``timeseries.csv``,
   ``prognosis.csv`` and, when matplotlib is installed, PNG plots like
   Fig. 8-12.

Cases (``--case``):

* ``b-md``: motor-disk friction b_Md,n exp(0.05 (t - 10)) from t = 10 s,
  failure at 0.45 N.m.s/rad (t = 99.8 s); section 6.3.
* ``mass-linear`` / ``mass-exponential``: the suspended load M of section 7
  (eqs. 54-64) grows linearly or exponentially up to M_fail = 1.5 / 1.8 kg.
  The paper's experiments are reproduced as simulations; where its numbers
  cannot all hold (gamma_2* = 0.005 kg/s cannot bring the load to 1.5 kg
  within its 60 s experiment), the time line is kept: see ``CASES``.

Presets (``--preset``): ``paper`` is the tuning Jha et al. (2016) report (section
6.3.4, 7.1.3, 7.2.2) with the sign of Table III corrected (docs/design.md); ``default`` is ours,
chosen with ``examples/torsion_bar_sweep.py`` (see docs/prognosis.md).

Datasheets (``--datasheet``, issue 35): ``true`` derives the ARRs from Table VI's values, the
simulation's own; ``wrong`` from a deliberately wrong datasheet (:data:`WRONG_DATASHEET`) calibrated
on the healthy calibration record (:func:`monitored_model`); ``wrong-uncalibrated`` from the wrong
datasheet as it is.  The simulation (the truth) is Table VI's physics in all three.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bgphm.plotting import band, pyplot, save_figure, write_figures
from bgphm.runs import run_main
from bondgraph import simulate
from bondgraph.scenarios import ANTIDERIVATIVES, ENCODER_COUNT, TORSION_DT, drift, encoder_angles, rig_signals
from bondgraph.library import (MASS_LOAD, OMEGA_M_REF, TORSION_BAR, U_MAX, torsion_bar, torsion_bar_controller,
                               torsion_bar_monitorable, with_suspended_load)
from diagnosis import derive_arrs, estimate_parameters
from diagnosis.detection import noise_margin
from diagnosis.records import add_noise, as_record
from prognosis import ExponentialDegradation, HealthMonitor, LinearDegradation, VarianceAdaptation
from prognosis.hypotheses import Hypothesis, rate_prior
from prognosis.isolation import IsolatingMonitor
from prognosis.health_monitor import MonitorResult
from prognosis.particle_filter import KernelSmoothing

DT_RECORD = TORSION_DT  # s, sampling of the simulated sensors
DT_FILTER = 0.1  # s, Jha et al. (2016), section 6.3.3
SPEED_NOISE = 0.01  # rad/s, Jha et al. (2016), section 6.3.1
TORQUE_NOISE = 0.01  # N.m, sigma_w of Jha et al. (2016), section 6.3.3, on the measured motor torque
MARGIN_SIGMAS = 3.0
PERSISTENCE = 10  # consecutive samples (0.1 s)
NOISES = {
    # the paper's level: its sigma_w = 0.01 is noise on the residual, i.e. on the measured torque
    "paper": {"omega_m": SPEED_NOISE, "omega_Ld": SPEED_NOISE, "tau_m": TORQUE_NOISE},
    # the first round's setting: an exact torque, the quantized encoders dominate (about 17x quieter)
    "quiet": {"omega_m": SPEED_NOISE, "omega_Ld": SPEED_NOISE},
}
NOISE = NOISES["paper"]
#: ``--datasheet wrong``: factors on Table VI's values, fixed beforehand (nothing of a seed's truth sets them).
#: The healthy record is a start-up (half a second) to a constant 30 rad/s at the motor disk.  What it shows well
#: is the viscous friction the motor works against at that speed, ``f_m + b_Md/k_belt**2`` in ARR_1_1 (b_s's
#: term cancels between rest and that speed, where the shaft does not twist), 99 % of it b_Md: b_Md's 95 %
#: interval is about +-0.5 %, and f_m is seen only in that combination (:func:`diagnosis.estimate_parameters`
#: reports it).  The rest is not seen: the inertias, b_s and b_Ld have intervals as wide as the prior, and the fit
#: shrinks the shaft's relation ARR_1_2 towards zero (k_s -97 %, J_Ld -88 %, with narrow intervals): at a
#: constant speed the twist rate and the load's acceleration are noise.  So the datasheet is wrong on that
#: combination, with both signs: b_Md 25 % low, f_m 30 % high (benchmarks/bench_case_calibration.py measures it).
WRONG_DATASHEET = {"b_Md": 0.75, "f_m": 1.3}
#: What ``--datasheet wrong`` fits on the healthy record: b_Md alone.  Fitted together with f_m, the
#: combination's carrier is the noise's pick (f_m carried it, at +4400 %, in 3 of 10 seeds), and f_m's
#: 30 % error is 0.2 % of b_Md, which b_Md then carries.
CALIBRATED = ("b_Md",)
DATASHEETS = ("true", "wrong", "wrong-uncalibrated")
KEYS = ("detection_time_s", "false_alarms_nominal", "rmse_theta", "rmse_gamma", "rmad_gamma", "ra", "rmad_rul",
        "alpha_lambda_pass_rate", "prognostic_horizon_s", "median_within_20pct", "band_holds_truth",
        "band50_holds_truth", "wall_time_s", "wall_time_per_step_s")
#: a band's coverage is judged against its level, not "higher is better": its worst is still the lowest seed's
HIGHER_IS_BETTER = {"ra", "alpha_lambda_pass_rate", "prognostic_horizon_s", "median_within_20pct", "band_holds_truth",
                    "band50_holds_truth"}


@dataclass(frozen=True)
class Case:
    """A degradation scenario: what degrades, how, when it fails, and what the paper reports."""

    name: str
    candidate: str  # "b_Md" or "M"
    law: str  # "exponential" or "linear"
    theta_n: float
    gamma: float  # true progression parameter gamma*
    onset: float  # s
    theta_fail: float
    n_particles: int
    after: float  # RA, RMAD and alpha-lambda over predictions from this time (s)
    alpha: float
    process_noise: float  # sigma_v of the degradation model
    paper_tuning: dict
    paper_figures: dict = field(default_factory=dict)
    theta_bounds: tuple | None = None  # eq. 39 start; None: the candidate's uncertainty interval in the ARR
    other_failures: dict = field(default_factory=dict)  # what else the user declares can fail (preset auto)

    def truth(self, t):
        """The true theta(t) the simulation uses (:func:`bondgraph.scenarios.drift`)."""
        return drift(self.theta_n, self.gamma, self.onset, self.law)(t)

    @property
    def eol(self) -> float:
        """True end of life: theta(t) = theta_fail."""
        if self.law == "exponential":
            return self.onset + math.log(self.theta_fail / self.theta_n) / self.gamma
        return self.onset + (self.theta_fail - self.theta_n) / self.gamma

    @property
    def t_end(self) -> float:
        return float(math.ceil(self.eol))

    def degradation_model(self):
        return (ExponentialDegradation if self.law == "exponential" else LinearDegradation)(self.process_noise)

    def bond_graphs(self, **datasheet: float):
        """(full model to simulate, monitorable part to derive the I-ARR from); ``datasheet`` overrides
        Table VI's values in the monitorable part only (the simulation keeps the true physics)."""
        if self.candidate == "M":
            return with_suspended_load(torsion_bar(), M=self.theta_n), with_suspended_load(
                torsion_bar_monitorable(**datasheet), M=self.theta_n)
        return torsion_bar(), torsion_bar_monitorable(**datasheet)


M_N = MASS_LOAD["M"]  # kg, the known load of the nominal run (mu is calibrated with it, section 7)
# what else a user of the b_Md cases declares can fail: the motor disk's inertia doubling, the load disk's
# bearing friction x10 (the first has b_Md's signature, the second does not)
OTHER_FAILURES = {"J_Md": 2 * TORSION_BAR["J_Md"][0], "b_Ld": 10 * TORSION_BAR["b_Ld"][0]}
TABLE_RATES = (0.03, 0.05, 0.08)  # gamma* of the linear b_Md table (N.m.s/rad per s)
CASES = {
    # Section 6.3: gamma_1* = 0.05 1/s; the paper's tuning of section 6.3.4 (Table III sign per docs/design.md).
    "b-md": Case("b-md", "b_Md", "exponential", TORSION_BAR["b_Md"][0], 0.05, 10.0, 0.45, 500, 52.0, 0.1, 1e-5,
                 paper_tuning={"gamma_std": 0.02, "gain": 0.001, "reference": 0.10, "band": (0.03, 0.07),
                               "noise_std": 0.01, "inflation": 4.0},
                 paper_figures={"rmse_theta": 0.0421, "rmse_gamma": 0.0302, "ra": 0.9715, "rmad_rul": 0.098,
                                "wall_time_s": 32 * 60.0},
                 other_failures=OTHER_FAILURES),
    # Section 7.1: M_fail = 1.5 kg reached at t = 60 s as in Fig. 18-21, so gamma_2* = 0.028 kg/s (the
    # printed 0.005 kg/s would take 280 s); the paper preset keeps the paper's printed band [3e-3, 7e-3]
    # and random-walk sigma 1e-3 (set around its 0.005), which our gamma_2* lies outside of: scaling
    # them to gamma_2* would take the preset from the truth.  sigma_w = 5e-3, 9x inflation.
    "mass-linear": Case("mass-linear", "M", "linear", M_N, 0.028, 10.0, 1.5, 50, 35.0, 0.2, 1e-3,
                        paper_tuning={"gamma_std": 1e-3, "gain": 0.007, "reference": 0.05,
                                      "band": (3e-3, 7e-3), "noise_std": 5e-3, "inflation": 9.0},
                        paper_figures={"rmse_theta": 0.0398, "ra": 0.9864, "rmad_rul": 0.094},
                        theta_bounds=(M_N, 1.2 * M_N)),  # M, a law constant, has no uncertainty interval
    # Section 7.2: gamma_3* = 0.05 1/s from the known load at t = 0, M_fail = 1.8 kg (t = 57.8 s);
    # sigma_xi,0^2 = 4e-6, P = 0.003, v* = 10 %, band [0.01, 0.09], sigma_v = 8e-4 kg.
    "mass-exponential": Case("mass-exponential", "M", "exponential", M_N, 0.05, 0.0, 1.8, 50, 32.0, 0.2, 8e-4,
                             paper_tuning={"gamma_std": 2e-3, "gain": 0.003, "reference": 0.10, "band": (0.01, 0.09),
                                           "noise_std": 5e-3, "inflation": 9.0},
                             paper_figures={"rmse_theta": 0.0378, "rmse_gamma": 0.076, "ra": 0.9702,
                                            "rmad_rul": 0.094},
                             theta_bounds=(M_N, 1.2 * M_N)),
}


def linear_case(gamma: float, onset: float = 25.0, fail: float = 0.3) -> Case:
    """b_Md growing linearly at ``gamma`` from ``onset``, failing at ``fail`` (one row of the ``--table`` run).

    Its figures are taken over the second half of the fault's life (``after``), an evaluation
    window only: nothing the monitor uses comes from it.
    """
    b_n = TORSION_BAR["b_Md"][0]
    eol = onset + (fail - b_n) / gamma
    return Case(f"linear-{gamma:g}", "b_Md", "linear", b_n, gamma, onset, fail, 500, onset + 0.5 * (eol - onset), 0.1,
                0.0, paper_tuning=CASES["b-md"].paper_tuning, other_failures=OTHER_FAILURES)


CASES.update({f"linear-{g:g}": linear_case(g) for g in TABLE_RATES})
PRESETS = ("auto", "named", "paper")


def tuning(case: Case, preset: str, residual_std: float, particles: int = 500, nominal: float | None = None) -> dict:
    """HealthMonitor settings of a preset (``residual_std``: calibrated residual noise, N.m; ``nominal``: the
    candidate's value in the monitored model, default the case's).

    ``paper``: the paper's numbers, the eq. 39 start, gamma starting at 0 and the random walk kept in
    the RUL prediction (Table IV).  ``named``: the candidate and its law are named, nothing else is
    given: the residual noise as calibrated on the nominal record with a 4x variance inflation,
    theta's start widened to explain the alarm's residual, the rate prior from the failure value
    (a life from nominal to failure log-uniform over 10 to 1e5 filter steps,
    :func:`prognosis.hypotheses.rate_prior`), kernel smoothing of the rate and gamma held in the RUL
    prediction.  ``auto`` is not a HealthMonitor setting: it runs :class:`~prognosis.isolation.IsolatingMonitor`
    (see :func:`run`).  examples/torsion_bar_sweep.py shows what each change from ``paper`` to
    ``named`` does.
    """
    paper = case.paper_tuning
    if preset == "paper":
        return {"gamma_std": paper["gamma_std"], "noise_std": paper["noise_std"], "inflation": paper["inflation"],
                "adaptation": VarianceAdaptation(band=paper["band"], reference=paper["reference"], gain=paper["gain"]),
                "start": "uncertainty_box", "gamma0": 0.0, "prediction_walk": 1.0}
    if preset == "named":
        hypothesis = Hypothesis(case.candidate, case.law, case.theta_fail, case.theta_n if nominal is None else nominal)
        rates = rate_prior(hypothesis, DT_FILTER, particles, np.random.default_rng(0))
        return {"gamma_std": 0.0, "noise_std": residual_std, "inflation": 4.0, "adaptation": KernelSmoothing(),
                "start": "residual", "gamma0": rates[None, :, None], "prediction_walk": 0.0}
    raise ValueError(f"unknown preset {preset!r}; choose one of {', '.join(PRESETS)}")


# -- simulation ------------------------------------------------------------------------------------

@dataclass
class Scenario:
    """Noise-free simulation of one case, nominal and degraded: plotted traces, sensor records, facts."""

    case: Case
    nominal: dict  # t, U, omega_Md, omega_Ld at the record's sampling
    degraded: dict
    clean_nominal: dict  # what the sensors give (see measured)
    clean_degraded: dict
    facts: dict
    seconds: float = 0.0  # wall time of the simulation


def simulate_case(case: Case, t_end: float | None = None) -> Scenario:
    """Simulate the full bond graph under PI control, nominal and with the case's degradation.

    The solver output is taken every ``DT_RECORD / 10`` so that the encoder angles come from an
    accurate integral of the speeds (an encoder reads the true angle; the trapezoidal rule on the
    10 ms samples misses 2.8 mrad of shaft twist in the start-up with Coulomb friction); the records
    are then sampled every ``DT_RECORD``.
    """
    start = time.perf_counter()
    full, _ = case.bond_graphs()
    integral = full.assign_causality("integral")
    equations = full.state_equations(integral)
    t_end = case.t_end if t_end is None else t_end
    every = 10
    t_eval = np.arange(0.0, t_end + DT_RECORD / (2 * every), DT_RECORD / every)
    t_end = max(t_end, float(t_eval[-1]))  # the last point may overshoot by a rounding error
    runs = [simulate(equations, (0.0, t_end), {"U": torsion_bar_controller()}, t_eval=t_eval, parameters=parameters)
            for parameters in ({}, {case.candidate: case.truth})]
    k_belt = TORSION_BAR["k_belt"][0]
    saturated = np.flatnonzero(runs[1]["U"] >= U_MAX - 1e-9)
    facts = {"states": [str(x) for x in equations.states], "dependent_storage": integral.dependent_storage,
             "omega_Md_end_nominal_rad_s": float(runs[0]["omega_m"][-1] / k_belt),
             "omega_Md_end_degraded_rad_s": float(runs[1]["omega_m"][-1] / k_belt),
             "saturation_time_s": float(runs[1].t[saturated[0]]) if saturated.size else None}
    traces = [{"t": r.t[::every], "U": r["U"][::every], "omega_Md": r["omega_m"][::every] / k_belt,
               "omega_Ld": r["omega_Ld"][::every]} for r in runs]
    return Scenario(case, *traces, rig_signals(runs[0], full, every), rig_signals(runs[1], full, every), facts,
                    time.perf_counter() - start)


def encoder(record: dict, rng: np.random.Generator) -> dict:
    """The record with each angle read by an encoder of 2000 counts per revolution, at a random phase.

    An encoder counts edges from wherever its disk stands at power-up (it reads 0 there), so the
    grid of its edges has a random offset in every run: records of different seeds carry different
    quantization errors (:func:`bondgraph.scenarios.encoder_angles`).
    """
    return encoder_angles(record, {angle: rng.uniform(0.0, ENCODER_COUNT) for angle in ANTIDERIVATIVES.values()})


# -- one run ---------------------------------------------------------------------------------------

@dataclass
class Run:
    case: Case
    preset: str
    seed: int
    scenario: Scenario
    arr: object
    margin: float
    evaluations: tuple  # (nominal, degraded)
    monitor: object
    figures: dict
    fit: object = None  # the ParameterEstimate of --datasheet wrong


def monitored_model(case: Case, datasheet: str, calibration):
    """The monitorable part the chain derives its ARRs from, and the calibration's estimate (or None).

    ``true``: Table VI.  ``wrong-uncalibrated``: :data:`WRONG_DATASHEET`.  ``wrong``: the wrong datasheet
    with :data:`CALIBRATED` estimated on the healthy ``calibration`` record alone (never the degraded one)
    by :func:`diagnosis.estimate_parameters`, with its own ARRs and defaults; every uncertainty box stays the
    datasheet's (relative to the calibrated value), so that the chain is built exactly as from the true model.
    """
    if datasheet not in DATASHEETS:
        raise ValueError(f"unknown datasheet {datasheet!r}; choose one of {', '.join(DATASHEETS)}")
    if datasheet == "true":
        return case.bond_graphs()[1], None
    _, wrong = case.bond_graphs(**{p: TORSION_BAR[p][0] * f for p, f in WRONG_DATASHEET.items()})
    if datasheet == "wrong-uncalibrated":
        return wrong, None
    fit = estimate_parameters(wrong, [calibration], list(CALIBRATED))
    return fit.model(wrong), fit


def detection_setup(case: Case, scenario: Scenario, seed: int, noise: dict = NOISE, datasheet: str = "true"):
    """The I-ARRs and the noisy records of one seed, with the noise margins calibrated on a record of its own.

    Each record (calibration, nominal, degraded) has its own sensor noise and encoder phase; the ARRs come
    from :func:`monitored_model` of ``datasheet`` (calibrated, with ``wrong``, on the calibration record).
    Returns ``(arrs, arr, detection options, nominal record, degraded record, calibration record, fit)``.
    """
    rng = np.random.default_rng([seed, 7])
    calibration, nominal, degraded = (add_noise(as_record(encoder(record, rng)), noise, seed=3 * seed + i)
                                      for i, record in enumerate((scenario.clean_nominal, scenario.clean_nominal,
                                                                  scenario.clean_degraded)))
    monitorable, fit = monitored_model(case, datasheet, calibration)
    arrs = derive_arrs(monitorable, complete=False, integrals="keep")
    arr = next(a for a in arrs if a.junction == "1_1")
    detection = {"antiderivatives": ANTIDERIVATIVES}
    margin = noise_margin(arr, calibration, k=MARGIN_SIGMAS, **detection)
    detection.update(margin=margin, persistence=PERSISTENCE)
    return arrs, arr, detection, nominal, degraded, calibration, fit


def run(case: str | Case = "b-md", preset: str = "auto", seed: int = 0, *, scenario: Scenario | None = None,
        t_end: float | None = None, n_particles: int | None = None, workers: int = 2, noise: str = "paper",
        datasheet: str = "true", **overrides) -> Run:
    """The whole chain for one noise seed; ``overrides`` replace HealthMonitor settings of the preset.

    ``auto`` is told only the failure values (the case's candidate and ``other_failures``): the
    candidate and the law come from the evidence (:class:`~prognosis.isolation.IsolatingMonitor`).
    ``datasheet``: the model the chain is built from (:func:`monitored_model`).
    """
    case = CASES[case] if isinstance(case, str) else case
    start = time.perf_counter()
    if scenario is None:
        scenario = simulate_case(case, t_end)
    else:  # a shared simulation counts in every run's wall time, as if each run simulated
        start -= scenario.seconds
    arrs, arr, detection, nominal, degraded, calibration, fit = detection_setup(case, scenario, seed, NOISES[noise],
                                                                                datasheet)
    margin = detection["margin"]
    quiet = arr.evaluate(nominal, **detection)
    n = n_particles or case.n_particles
    filter_start = time.perf_counter()
    if preset == "auto":
        result, found = _isolate(case, arrs, calibration, degraded, n, seed)
    else:
        settings = {**tuning(case, preset, margin / MARGIN_SIGMAS, n, nominal=arr.values.get(case.candidate)),
                    **overrides}
        monitor = HealthMonitor(arr, case.candidate, case.degradation_model(), theta_fail=case.theta_fail,
                                dt=DT_FILTER, n_particles=n, detection=detection, seed=seed,
                                theta_bounds=case.theta_bounds, **settings)
        result, found = monitor.run(degraded, workers=workers), {}
    filter_time = time.perf_counter() - filter_start
    faulty = result.evaluation  # residual and thresholds of the degraded record, as the monitor saw them
    figures = {"case": case.name, "preset": preset, "noise": noise, "seed": seed, "datasheet": datasheet,
               "detection_time_s": result.detection_time,
               "detection_delay_s": None if result.detection_time is None else result.detection_time - case.onset,
               "false_alarms_nominal": quiet.false_alarms(float(quiet.t[-1]) + 1.0),
               "eol_s": case.eol, "filter_steps": int(result.t.size), "noise_margin": margin,
               "arrs": [a.name for a in arrs], **found, **scenario.facts, **_threshold_widths(quiet),
               "model": {p: arr.values[p] for p in (*WRONG_DATASHEET, case.candidate) if p in arr.values},
               "calibration": None if fit is None else fit.as_dict()}
    if result.t.size:
        figures.update(result.metrics(case.truth, lambda t: case.gamma, eol=case.eol, after=case.after,
                                      alpha=case.alpha, beta=0.5))
        figures.update(_rul_hits(result, case))
    figures["wall_time_s"] = time.perf_counter() - start
    figures["wall_time_per_step_s"] = filter_time / max(result.t.size, 1)
    return Run(case, preset, seed, scenario, arr, margin, (quiet, faulty), result, figures, fit)


def arr_detection(arrs: list, calibration) -> tuple[dict, dict]:
    """Preset auto: every ARR's noise (one robust sd) from the calibration record, and its detection options."""
    options = {"antiderivatives": ANTIDERIVATIVES}
    noise = {a.name: noise_margin(a, calibration, k=1.0, **options) for a in arrs}
    return noise, {a.name: {**options, "margin": MARGIN_SIGMAS * noise[a.name], "persistence": PERSISTENCE}
                   for a in arrs}


def detect(case: str | Case, scenario: Scenario, seed: int = 0, noise: str = "paper", datasheet: str = "true") -> dict:
    """The detection figures of :func:`run` (preset auto) without the filter: the first alarm of any ARR
    on the degraded record, false alarms and threshold widths on the nominal one."""
    case = CASES[case] if isinstance(case, str) else case
    arrs, arr, detection, nominal, degraded, calibration, _ = detection_setup(case, scenario, seed, NOISES[noise],
                                                                              datasheet)
    quiet = arr.evaluate(nominal, **detection)
    _, options = arr_detection(arrs, calibration)
    evaluations = [a.evaluate(degraded, **options[a.name]) for a in arrs]
    alarms = [e.t[e.alarm][0] for e in evaluations if e.alarm.any()]
    detection_time = float(min(alarms)) if alarms else None
    return {"arrs": [a.name for a in arrs], "detection_time_s": detection_time,
            "detection_delay_s": None if detection_time is None else detection_time - case.onset,
            "false_alarms_nominal": quiet.false_alarms(float(quiet.t[-1]) + 1.0), **_threshold_widths(quiet)}


def _isolate(case: Case, arrs: list, calibration, degraded, n: int, seed: int):
    """Preset auto: every ARR's noise from the calibration record, then candidates and laws by evidence."""
    noise, detection = arr_detection(arrs, calibration)
    failures = {case.candidate: case.theta_fail, **case.other_failures}
    monitor = IsolatingMonitor(arrs, failures, noise_std=noise, dt=DT_FILTER, n_particles=n, rul_every=1,
                               detection=detection, seed=seed)  # its default horizon: nothing from the true life
    isolation = monitor.run(degraded)
    decision = isolation.decision
    if decision is None:
        return isolation.monitor_result() if isolation.t.size else _empty(isolation), {"found": None}
    found = {"found": decision.candidate, "status": decision.status, "law": decision.degradation,
             "law_decided": decision.degradation_decided, "candidate_ratio": min(decision.candidate_ratio, 1e300),
             "law_ratio": min(decision.degradation_ratio, 1e300), "rejected": sorted(isolation.rejected),
             "candidates": isolation.candidates}
    named = f"{case.candidate}/{decision.degradation}"
    chosen = named if named in decision.probabilities else None
    result = isolation.monitor_result(chosen)
    result.evaluation = isolation.evaluations[0]
    return result, found


def _empty(isolation):
    return MonitorResult(isolation.detection_time, evaluation=isolation.evaluations[0])


def _rul_hits(result, case: Case) -> dict:
    """Over the predictions from ``case.after`` to the end of life: the median within 20 % of the true RUL,
    and the 5-95 % and 25-75 % bands holding it (fractions of the predictions)."""
    keep = (result.rul_t >= case.after) & (result.rul_t < case.eol)
    if not keep.any():
        return {"median_within_20pct": None, "band_holds_truth": None, "band50_holds_truth": None}
    true = case.eol - result.rul_t[keep]
    q = result.rul_percentiles((5, 25, 50, 75, 95))[keep]
    return {"median_within_20pct": float(np.mean(np.abs(q[:, 2] - true) <= 0.2 * true)),
            "band_holds_truth": float(np.mean((q[:, 0] <= true) & (true <= q[:, 4]))),
            "band50_holds_truth": float(np.mean((q[:, 1] <= true) & (true <= q[:, 3])))}


def _threshold_widths(evaluation) -> dict:
    """Median widths of the interval and BG-LFT thresholds on the nominal record."""
    width = evaluation.upper - evaluation.lower
    decided = np.isfinite(width) & np.isfinite(evaluation.bglft)  # samples left undecided (input steps) aside
    return {"interval_width_median": float(np.median(width[decided])),
            "bglft_width_median": float(np.median(2 * evaluation.bglft[decided])),
            "interval_never_wider_than_bglft": bool(np.all(width[decided] <= 2 * evaluation.bglft[decided]
                                                           * (1 + 1e-12)))}


def summarize(figures: list[dict]) -> dict:
    """Mean of every figure over runs, with ``<key>_std`` (population standard deviation) and ``<key>_worst``.

    The worst is the lowest value of a figure where higher is better (RA, pass rates), else the highest.
    ``found_candidate`` and ``found_law`` count the runs that isolated the true candidate and law.
    """
    summary = {k: figures[0].get(k) for k in ("case", "preset", "datasheet")}
    summary["seeds"] = [f["seed"] for f in figures]
    for key in KEYS + ("detection_delay_s",):
        values = np.array([np.nan if f.get(key) is None else f[key] for f in figures], float)
        finite = values[np.isfinite(values)]
        summary[key] = float(finite.mean()) if finite.size else None
        summary[f"{key}_std"] = float(finite.std()) if finite.size else None
        worst = (finite.min() if key in HIGHER_IS_BETTER else finite.max()) if finite.size else None
        summary[f"{key}_worst"] = None if worst is None else float(worst)
        if finite.size < values.size:
            summary[f"{key}_missing"] = int(values.size - finite.size)
    if "found" in figures[0]:
        case = CASES.get(figures[0]["case"])
        summary["found_candidate"] = sum(f.get("found") == (case.candidate if case else None) for f in figures)
        summary["found_law"] = sum(f.get("law") == (case.law if case else None) for f in figures)
    summary["runs"] = figures
    return summary


# -- output ----------------------------------------------------------------------------------------

def table(figures: dict, case: Case) -> str:
    """Our figures beside the paper's (percent where the paper gives percent)."""
    rows = [("detection time (s)", "detection_time_s", 1, None),
            ("false alarms, nominal run", "false_alarms_nominal", 1, None),
            ("RMSE theta (%)", "rmse_theta", 100, "rmse_theta"), ("RMSE gamma (%)", "rmse_gamma", 100, "rmse_gamma"),
            ("mean RMAD gamma (%)", "rmad_gamma", 100, None),
            (f"RA after t = {case.after:g} s (%)", "ra", 100, "ra"),
            (f"mean RMAD RUL after t = {case.after:g} s (%)", "rmad_rul", 100, "rmad_rul"),
            (f"alpha-lambda pass rate (alpha = {case.alpha:g}) (%)", "alpha_lambda_pass_rate", 100, None),
            ("prognostic horizon (s)", "prognostic_horizon_s", 1, None),
            (f"median RUL within 20 % after t = {case.after:g} s (%)", "median_within_20pct", 100, None),
            (f"5-95 % band holds the RUL after t = {case.after:g} s (%)", "band_holds_truth", 100, None),
            (f"25-75 % band holds the RUL after t = {case.after:g} s (%)", "band50_holds_truth", 100, None),
            ("wall time of the run (s)", "wall_time_s", 1, "wall_time_s"),
            ("wall time per filter step (ms)", "wall_time_per_step_s", 1000, None)]
    lines = [f"  {'figure':<52} {'ours (mean)':>12} {'worst':>9} {'Jha et al. (2016)':>18}"]
    for label, key, scale, paper_key in rows:
        value, worst = figures.get(key), figures.get(f"{key}_worst")
        ours = "-" if value is None else f"{value * scale:.2f}"
        bad = "-" if worst is None else f"{worst * scale:.2f}"
        paper = case.paper_figures.get(paper_key) if paper_key else None
        lines.append(f"  {label:<52} {ours:>12} {bad:>9} {'-' if paper is None else f'{paper * scale:.2f}':>18}")
    if "found_candidate" in figures:
        lines.append(f"  isolated {case.candidate} in {figures['found_candidate']} of {len(figures['seeds'])} runs, "
                     f"the {case.law} law in {figures['found_law']}")
    elif figures.get("found") is not None:
        lines.append(f"  isolated {figures['found']} ({figures['status']}), law {figures['law']}"
                     + ("" if figures["law_decided"] else " (undecided)"))
    return "\n".join(lines)


def write(out: Path, figures: dict, first: Run) -> list[Path]:
    """results.json, timeseries.csv, prognosis.csv and (with matplotlib) the plots of the first run."""
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "results.json", out / "timeseries.csv", out / "prognosis.csv"]
    written[0].write_text(json.dumps(figures, indent=2))
    _write_csv(written[1], _timeseries(first))
    _write_csv(written[2], _prognosis(first))
    return written + write_figures(plot, out, first)


def _write_csv(path: Path, columns: dict) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        writer.writerows(zip(*columns.values()))


def _timeseries(r: Run) -> dict:
    columns = {"t": r.scenario.nominal["t"], "theta_true": r.case.truth(r.scenario.nominal["t"])}
    for label, traces, evaluation in (("nominal", r.scenario.nominal, r.evaluations[0]),
                                      ("degraded", r.scenario.degraded, r.evaluations[1])):
        for name in ("U", "omega_Md", "omega_Ld"):
            columns[f"{name}_{label}"] = traces[name]
        columns[f"minus_r_n_{label}"] = -evaluation.residual
        columns[f"B_lo_{label}"] = evaluation.lower - evaluation.margin
        columns[f"B_hi_{label}"] = evaluation.upper + evaluation.margin
        columns[f"alarm_{label}"] = evaluation.alarm.astype(int)
    return columns


PROGNOSIS_COLUMNS = ("t", "theta_true", "theta_mean", "theta_q05", "theta_q95", "gamma_mean", "gamma_rmad",
                     "gamma_q05", "gamma_q95", "rul_true", "rul_mean", "rul_q05", "rul_median", "rul_q95")


def _prognosis(r: Run) -> dict:
    m = r.monitor
    if not m.t.size:  # no detection, no filter steps
        return {name: [] for name in PROGNOSIS_COLUMNS}
    q_rul = m.rul_percentiles((5, 50, 95))
    columns = (m.t, r.case.truth(m.t), m.theta["mean"], m.theta["quantiles"][:, 0], m.theta["quantiles"][:, 2],
               m.gamma["mean"], m.gamma["rmad"], m.gamma["quantiles"][:, 0], m.gamma["quantiles"][:, 2],
               r.case.eol - m.rul_t, m.rul_mean, q_rul[:, 0], q_rul[:, 1], q_rul[:, 2])
    return dict(zip(PROGNOSIS_COLUMNS, columns))


def plot(out: Path, r: Run) -> list[Path]:
    """PNG plots like Jha et al. (2016), Figs. 8-12."""
    plt = pyplot("Agg")

    ts, pr, case = _timeseries(r), _prognosis(r), r.case
    name = "b_{Md}" if case.candidate == "b_Md" else "M"
    files = []

    def save(fig, filename):
        files.append(save_figure(fig, out / filename))

    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for label, style in (("nominal", "--"), ("degraded", "-")):
        axes[0].plot(ts["t"], ts[f"omega_Md_{label}"], style, label=label)
        axes[1].plot(ts["t"], ts[f"U_{label}"], style, label=label)
    axes[0].set_ylabel(r"$\omega_{Md}$ (rad/s)")
    axes[1].set_ylabel("U (V)")
    axes[1].axhline(U_MAX, color="grey", lw=0.8)
    axes[1].set_xlabel("t (s)")
    axes[0].legend()
    save(fig, "fig08_speed_voltage.png")

    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for ax, label in zip(axes, ("nominal", "degraded")):
        ax.plot(ts["t"], ts[f"minus_r_n_{label}"], lw=0.6, label=r"$-r_n$")
        ax.plot(ts["t"], ts[f"B_lo_{label}"], "r", lw=0.8, label="interval thresholds")
        ax.plot(ts["t"], ts[f"B_hi_{label}"], "r", lw=0.8)
        ax.set_ylabel(f"{label} (N.m)")
        settled = ts["t"] > 1.0  # the start-up transient would squash the scale
        values = np.concatenate([ts[f"{k}_{label}"][settled] for k in ("minus_r_n", "B_lo", "B_hi")])
        pad = 0.1 * (values.max() - values.min())
        ax.set_ylim(values.min() - pad, values.max() + pad)
    if r.monitor.detection_time is not None:
        axes[1].axvline(r.monitor.detection_time, color="k", ls=":", label="detection")
    axes[1].set_xlabel("t (s)")
    axes[0].legend(loc="upper right")
    axes[1].legend(loc="lower left")
    save(fig, "fig09_residual_thresholds.png")

    fig, ax = plt.subplots(figsize=(7, 4))
    band(ax, pr["t"], pr["theta_q05"], pr["theta_q95"], alpha=0.3, label="5-95 %")
    ax.plot(pr["t"], pr["theta_mean"], label="estimate (mean)")
    ax.plot(pr["t"], pr["theta_true"], "k--", label="true")
    ax.axhline(case.theta_fail, color="r", lw=0.8, label="failure value")
    ax.set(xlabel="t (s)", ylabel=f"${name}$")
    ax.legend()
    save(fig, "fig10_theta.png")

    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    band(axes[0], pr["t"], pr["gamma_q05"], pr["gamma_q95"], alpha=0.3, label="5-95 %")
    axes[0].plot(pr["t"], pr["gamma_mean"], label="estimate (mean)")
    axes[0].axhline(case.gamma, color="k", ls="--", label=r"$\gamma^*$")
    axes[0].set_ylabel(r"$\gamma$")
    axes[0].legend()
    axes[1].plot(pr["t"], 100 * np.asarray(pr["gamma_rmad"]))
    axes[1].set(xlabel="t (s)", ylabel=r"RMAD of $\gamma$ (%)", ylim=(0, 100))
    save(fig, "fig11_gamma.png")

    fig, ax = plt.subplots(figsize=(7, 4))
    t = r.monitor.rul_t
    true = case.eol - t
    band(ax, t, (1 - case.alpha) * true, (1 + case.alpha) * true, color="grey", alpha=0.25,
         label=rf"$\alpha$-cone ($\alpha$ = {case.alpha:g})")
    ax.plot(t, true, "k--", label="true RUL")
    band(ax, t, pr["rul_q05"], np.minimum(pr["rul_q95"], 2 * case.eol), alpha=0.3, label="5-95 %")
    ax.plot(t, pr["rul_median"], label="median")
    ax.axvline(case.after, color="k", ls=":", lw=0.8)
    ax.set(xlabel="t (s)", ylabel="RUL (s)", ylim=(0, 1.5 * (case.eol - t[0]) if t.size else 1))
    ax.legend()
    save(fig, "fig12_rul.png")
    return files


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description="Jha et al. (2016) end to end on the torsion bar: bond graph to RUL")
    parser.add_argument("--case", choices=sorted(CASES), default="b-md")
    parser.add_argument("--preset", choices=PRESETS, default="auto",
                        help="auto: told only the failure values (default); named: the candidate and its law "
                             "are named; paper: the tuning of Jha et al. (2016)")
    parser.add_argument("--noise", choices=sorted(NOISES), default="paper",
                        help="paper: 0.01 N.m on the measured torque (default); quiet: an exact torque")
    parser.add_argument("--seed", type=int, default=0, help="noise and filter seed (first seed with --runs)")
    parser.add_argument("--runs", type=int, default=1, help="repeat over this many seeds; report mean and worst")
    parser.add_argument("--table", action="store_true",
                        help=f"the linear b_Md cases, gamma* in {list(TABLE_RATES)}, over --runs seeds")
    parser.add_argument("--particles", type=int, help="number of particles (default: 500, or 50 for the mass cases)")
    parser.add_argument("--t-end", type=float, help="simulated horizon in s (default: just past the end of life)")
    parser.add_argument("--workers", type=int, default=2, help="processes for the RUL predictions (default 2)")
    parser.add_argument("--out", type=Path, help="directory for results.json, CSV files and plots")
    parser.add_argument("--datasheet", choices=DATASHEETS, default="true",
                        help="the model the chain is built from: true (Table VI, default); wrong (WRONG_DATASHEET "
                             "calibrated on the healthy record); wrong-uncalibrated (the wrong datasheet as is)")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    if args.table:
        return rate_table(args)
    figures, runs = over_runs(CASES[args.case], args)
    first = runs[0]
    facts = first.scenario.facts
    saturation = facts["saturation_time_s"]
    print(f"  simulation: omega_Md set-point {OMEGA_M_REF / TORSION_BAR['k_belt'][0]:.0f} rad/s; actuator saturates "
          f"{'never' if saturation is None else f'at t = {saturation:.1f} s'}; omega_Md at the end "
          f"{facts['omega_Md_end_degraded_rad_s']:.2f} rad/s")
    print(f"  {first.arr.name}: r_n = {first.arr.nominal}")
    print(table(figures, first.case))
    if args.out:
        for path in write(args.out, figures, first):
            print(f"  wrote {path}")
    return figures


def over_runs(case: Case, args) -> tuple[dict, list]:
    """``args.runs`` seeds of one case: (figures, or their summary over seeds; the runs)."""
    print(f"Jha et al. (2016) on the torsion bar, case {case.name} ({case.candidate} {case.law}, "
          f"failure at {case.theta_fail:g}, true end of life {case.eol:.1f} s), preset {args.preset}, "
          f"{args.noise} noise, {args.datasheet} datasheet")
    scenario, runs = None, []
    for i in range(args.runs):
        runs.append(run(case, args.preset, args.seed + i, t_end=args.t_end, n_particles=args.particles,
                        workers=args.workers, scenario=scenario, noise=args.noise, datasheet=args.datasheet))
        scenario = runs[0].scenario  # the simulation is deterministic: later seeds reuse it
        f = runs[-1].figures
        if f["datasheet"] != "true":
            print(f"  seed {f['seed']}: model {', '.join(f'{p} = {v:.4g}' for p, v in f['model'].items())}"
                  + ("" if f["calibration"] is None else " (calibrated on the healthy record)"))
        if args.runs > 1:
            within, band = (100 * (f.get(k) or np.nan) for k in ("median_within_20pct", "band_holds_truth"))
            print(f"  seed {f['seed']}: found {f.get('found', case.candidate)} / {f.get('law', case.law)}, "
                  f"RA {100 * f.get('ra', np.nan):.2f} %, median within 20 % {within:.0f} %, band {band:.0f} %")
    return (summarize([r.figures for r in runs]) if args.runs > 1 else runs[0].figures), runs


def rate_table(args) -> dict:
    """The linear b_Md cases over ``args.runs`` seeds: mean and worst per gamma*; ``table.json`` with ``--out``."""
    rows = {}
    for gamma in TABLE_RATES:
        figures, runs = over_runs(CASES[f"linear-{gamma:g}"], args)
        rows[f"{gamma:g}"] = figures if args.runs > 1 else summarize([r.figures for r in runs])
    print(f"\n  linear b_Md from t = 25 s, failure at 0.3, {args.preset} preset, {args.noise} noise, "
          f"{args.runs} seed(s): mean (worst)")
    print(f"  {'gamma*':>7} {'b_Md found':>10} {'linear':>7} {'median within 20 %':>19} {'band holds':>11} "
          f"{'50 % band':>11} {'RA':>13}")
    for gamma, f in rows.items():
        def pct(key):
            return "-" if f[key] is None else f"{100 * f[key]:.0f} ({100 * f[f'{key}_worst']:.0f})"
        print(f"  {gamma:>7} {f.get('found_candidate', '-'):>7}/{len(f['seeds']):<2} {f.get('found_law', '-'):>4}/"
              f"{len(f['seeds']):<2} {pct('median_within_20pct'):>19} {pct('band_holds_truth'):>11} "
              f"{pct('band50_holds_truth'):>11} {pct('ra'):>13}")
    if args.out:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "table.json").write_text(json.dumps(rows, indent=2))
        print(f"  wrote {args.out / 'table.json'}")
    return rows


if __name__ == "__main__":
    run_main(main)
