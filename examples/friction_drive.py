"""Rodriguez Obando et al. (2021): deterioration estimation, RUL prediction and RUL control of a friction drive.

    python examples/friction_drive.py [--seeds 4] [--workers 2] [--speedup 1] [--out DIR]

1. builds the roller-on-tire drive as a bond graph (``friction_drive``: J1, B1,
   TF r1, the contact R element alpha, TF 1/r2, J2, B2; eqs. 1-5, Table 1),
   takes its state equations in the speeds omega1, omega2 (eq. 13) and appends
   the energy-driven deterioration of the contact element from the bond
   graph's own power variables: D = energy dissipated by alpha, alpha decays
   with D at the rate m (eqs. 8-12, 14-19);
2. closes the PI speed loop of eq. 59 on the measured omega2 (omega2_ref =
   20 rad/s) and simulates the truth (RK4) with the noises of eq. 54; m jumps
   from 1e-6 to 2e-6 at 4 h (section 6.1);
3. runs the EKF of eqs. 23-35 on [omega1, omega2, alpha, m, D] (Euler as in eq.
   28, sympy Jacobians), P_0 from the bounds of eq. 57 by eq. 44 (c = 10),
   Chebyshev bounds of eqs. 37-43 on every state, Q of eq. 55;
4. supervises its innovations (section 4.3): when they stop being consistent
   (bias or NIS over a sliding window) the EKF is restarted with a new P_0 for
   alpha and m (section 6.1); a twin EKF without restart runs beside it;
5. predicts the RUL by Monte Carlo over the estimate (eq. 46) at 4.3 h without
   restart (prediction scenario 1) and at 5.0 h with restart (scenario 2);
6. from 5.0 h, lets the RUL controller (eqs. 47-53) lower the speed reference so
   that Pr(RUL <= RUL_ref) <= eta, re-deciding every 30 min, and runs the
   controlled drive to its end of life (scenario 3); a decision the controller
   could not converge on (its fallback applied) is counted and reported;
7. on a second truth whose m is random (``RANDOM_M``), runs the same EKF with
   restart, unchanged (dm/dt = 0 in its model), and predicts the RUL at 5.0 h
   as in scenario 2 (scenario 4).

Scenario 4's truth (the paper says only that m is "a random variable with a
normal distribution", with its mean in the estimated interval): every 10 min
of story time m is drawn anew, independently, from N(mu(t), (0.25 mu(t))^2),
mu = 1e-6 before 4 h and 2e-6 after as in the estimation scenario, and
clipped at 0.1 mu so that it stays positive (the clip lies 3.6 standard
deviations below the mean: about one draw in 6000).  Why this law: a rate drawn
anew at every 1 s sample would be averaged away by the contact within seconds
and the scenario would not differ from scenario 2; 10 min is the supervisor's
window, long enough for a draw to move alpha by about its own estimation
error, short enough for about 40 draws per life.  A quarter of the mean keeps
m's excursions inside the bounds the restart gives m (+-2e-6), so the
EKF's box can follow them.  The draws have their own random stream, the
measurement noise another, both from the seed.

Failure (Definition 2): alpha reaches 0 or D reaches D_max = 5e6 J (the paper
does not give D_max).  Sampling: 1 s; the EKF's Euler step runs in 10
substeps of 0.1 s (the contact mode is at about -17 1/s, so a 1 s Euler step
would be unstable); the paper does not give t_s.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import sys
import time
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

# 5 x 5 matrices: BLAS threads only add contention when seeds run in parallel.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy as np  # noqa: E402
import sympy as sp  # noqa: E402

from bgphm.plotting import band, pyplot, save_figure, write_figures  # noqa: E402
from bgphm.runs import over_seeds, run_main  # noqa: E402
from bondgraph.library import friction_drive  # noqa: E402
from prognosis.lifecontrol import (RULController, chebyshev_intervals, covariance_from_bounds,  # noqa: E402
                                   energy_deterioration, monte_carlo_rul)
from prognosis.statespace import (ExtendedKalmanFilter, InnovationMonitor, discretize,  # noqa: E402
                                  innovation_consistency)

HOUR = 3600.0
DT = 1.0                      # s, sampling period (not given in the paper)
SUBSTEPS = 10                 # integration steps per sample (EKF Euler, truth RK4)
R = np.diag([33.33, 0.33])    # eq. 54
Q = np.diag([0.1, 0.001, 0.0, 0.0, 0.0])  # eq. 55
C = 10.0                      # Chebyshev scale: 1 - 5/c^2 = 95 %
X0_ESTIMATE = np.array([0.0, 0.0, 11.0, 1.1e-6, 0.0])    # eq. 57
X0_BOUNDS = np.array([23.0, 2.0, 5.0, 1e-6, 5e5])        # eq. 57
X0_TRUE = np.array([0.0, 0.0, 10.0, 1e-6, 0.0])          # inside the bounds
OMEGA2_REF = 20.0             # rad/s
PI_GAINS = (0.0048, 0.0048)   # eq. 59
D_MAX = 5e6                   # J, maximal admissible deterioration (not given in the paper)
ALPHA_MIN = 0.0
MONTE_CARLO = {"n_samples": 1000, "dt": 30.0, "horizon": 12 * HOUR}
CONTROL = {"rul_ref": 3.0 * HOUR, "eta": 0.05, "gain": 1e-3, "lower": -15.0, "period": 0.5 * HOUR, "tolerance": 36.0,
           "max_iterations": 60}
MONITOR = {"window": 600, "threshold": 5.0, "persistence": 30}
RESTART_BOUNDS = {"alpha": 2.0, "m": 2e-6}   # new expected bounds after a model change (eq. 44)
# Scenario 4's truth: m drawn anew every period from N(mu, (std_fraction mu)^2), at least floor_fraction mu
RANDOM_M = {"period": 600.0, "std_fraction": 0.25, "floor_fraction": 0.1}
STATES = ("omega1", "omega2", "alpha", "m", "D")


@dataclass(frozen=True)
class Scenario:
    """Times and rates of section 6 (``speedup`` > 1 compresses them for quick runs)."""

    m_initial: float = 1e-6
    m_after: float = 2e-6
    change: float = 4.0 * HOUR
    predict_without_restart: float = 4.3 * HOUR
    predict_with_restart: float = 5.0 * HOUR
    control_start: float = 5.0 * HOUR
    control_period: float = CONTROL["period"]
    rul_ref: float = CONTROL["rul_ref"]
    end: float = 14.0 * HOUR
    monitor_window: int = MONITOR["window"]
    monitor_persistence: int = MONITOR["persistence"]
    d_max: float = D_MAX
    m_period: float = RANDOM_M["period"]
    speedup: float = 1.0

    @property
    def measurement_noise(self) -> np.ndarray:
        """R of eq. 54; a faster story has k times fewer samples, each k times more precise."""
        return R / self.speedup

    def scaled(self, k: float) -> "Scenario":
        """The same story ``k`` times faster: m times k, energies (D), times and noise variances divided by k."""
        return replace(self, d_max=self.d_max / k, m_initial=self.m_initial * k, m_after=self.m_after * k,
                       change=self.change / k,
                       predict_without_restart=self.predict_without_restart / k,
                       predict_with_restart=self.predict_with_restart / k, control_start=self.control_start / k,
                       control_period=self.control_period / k, rul_ref=self.rul_ref / k, end=self.end / k,
                       monitor_window=max(30, int(self.monitor_window / k)),
                       monitor_persistence=max(3, int(self.monitor_persistence / k)),
                       m_period=self.m_period / k, speedup=k)

    def m_mean(self, t):
        """The mean of m at time(s) ``t``: m_initial before the change, m_after from it on."""
        return np.where(np.asarray(t) < self.change - 0.5 * DT, self.m_initial, self.m_after)


# -- model ------------------------------------------------------------------------------------------------


@lru_cache(maxsize=1)
def deterioration_equations():
    """Eq. 13 in the speeds, with alpha, m and D appended from the contact element's power (eqs. 14-19)."""
    equations = friction_drive().state_equations().coenergy_states({"J1": "omega1", "J2": "omega2"})
    return energy_deterioration(equations, "alpha", rate_value=1e-6)


@lru_cache(maxsize=1)
def models():
    """(EKF model: Euler as in eq. 28, truth: RK4), both with 10 substeps per 1 s sample."""
    equations = deterioration_equations()
    return (discretize(equations, dt=DT, method="euler", substeps=SUBSTEPS),
            discretize(equations, dt=DT, method="rk4", substeps=SUBSTEPS))


@lru_cache(maxsize=1)
def predictor_rates():
    """Deterioration rates under a speed plan omega2* (eqs. 45-46), derived from the bond graph.

    Holding omega2 = omega2* (d omega2/dt = 0) in the driven side's equation gives the omega1 the
    contact needs; substituted into the contact power, ``P = alpha p(omega2*, alpha)`` with
    ``p = (B2 omega2* / (alpha r2))^2`` (eq. 45).  Returns a numpy function of (alpha, omega2*).
    """
    equations = deterioration_equations()
    omega1, omega2, alpha = (sp.Symbol(n) for n in ("omega1", "omega2", "alpha"))
    held = sp.solve(sp.Eq(equations.rhs[1], 0), omega1)[0]
    power = sp.simplify(equations.power.subs(omega1, held).subs(equations.parameters))
    return sp.lambdify((alpha, omega2), power, "numpy"), power


def margin(x, d_max: float = D_MAX):
    """Distance to failure of the deterioration states (alpha, m, D): > 0 while working (Definition 2)."""
    return np.minimum(x[0] - ALPHA_MIN, (d_max - x[2]) / d_max * 10.0)


def predict_rul(mean, covariance, t, omega2_star, seed, keep=0, d_max=D_MAX):
    """Eq. 46 from the EKF's (alpha, m, D) estimate; draws stay in the Chebyshev box and alpha, m, D >= 0."""
    power, _ = predictor_rates()
    idx = [2, 3, 4]
    mu, p = np.asarray(mean)[idx], np.asarray(covariance)[np.ix_(idx, idx)]
    lo, hi = chebyshev_intervals(mu, p, C)

    def rates(x, _t):
        dissipated = power(x[0], omega2_star)
        return np.vstack([-x[1] * dissipated, np.zeros_like(dissipated), dissipated])

    return monte_carlo_rul(rates, mu, p, lambda x: margin(x, d_max), origin=t, horizon=MONTE_CARLO["horizon"],
                           dt=MONTE_CARLO["dt"],
                           n_samples=MONTE_CARLO["n_samples"], lower=np.maximum(lo, 0.0), upper=hi, seed=seed,
                           keep=keep)


# -- closed loop ------------------------------------------------------------------------------------------


class Drive:
    """The plant, its PI speed loop, the EKF (restartable) and an optional twin EKF without restart.

    ``random_m``: a generator for scenario 4, whose true m is redrawn every ``scenario.m_period`` from
    ``RANDOM_M``'s law around ``scenario.m_mean(t)``; without it m jumps once, at ``scenario.change``.
    """

    def __init__(self, scenario: Scenario, seed, twin: bool = True, random_m: np.random.Generator | None = None):
        ekf_model, truth_model = models()
        self.scenario, self.truth_model = scenario, truth_model
        self.rng = np.random.default_rng(seed)
        self.m_rng = random_m
        self.m_draws: list[tuple[float, float, bool]] = []  # (t, m, clipped) of scenario 4's truth
        self.x = X0_TRUE.copy()
        self.x[3] = scenario.m_initial
        estimate = X0_ESTIMATE.copy()
        estimate[3] *= scenario.speedup
        bounds = X0_BOUNDS.copy()
        bounds[3] *= scenario.speedup
        bounds[4] /= scenario.speedup
        self.ekf = ExtendedKalmanFilter(ekf_model, estimate, covariance_from_bounds(bounds, C), Q,
                                        scenario.measurement_noise)
        self.twin = self.ekf.copy() if twin else None
        self.monitor = InnovationMonitor(scenario.monitor_window, MONITOR["threshold"], scenario.monitor_persistence)
        self.t, self.integral, self.torque, self.theta = 0.0, 0.0, 0.0, 0.0
        if random_m is not None:
            self._draw_m()
        self.restarts: list[float] = []
        self.ekf_seconds, self.ekf_steps = 0.0, 0
        self.log: dict[str, list] = {k: [] for k in ("t", "truth", "mean", "half", "twin_mean", "twin_half",
                                                     "residual", "S", "theta")}

    def failed(self) -> bool:
        return bool(margin(self.x[2:, None], self.scenario.d_max)[0] <= 0) or not np.all(np.isfinite(self.x))

    def step(self) -> None:
        s = self.scenario
        self.x = self.truth_model.transition(self.x, [self.torque])
        self.t += DT
        if self.m_rng is not None:
            if self._redraw_due():
                self._draw_m()
        elif abs(self.t - s.change) < 0.5 * DT:
            self.x[3] = s.m_after
        y = self.x[:2] + self.rng.normal(0.0, np.sqrt(np.diag(self.scenario.measurement_noise)))
        started = time.perf_counter()
        innovation = self.ekf.step(y, [self.torque])
        self.ekf_seconds += time.perf_counter() - started
        self.ekf_steps += 1
        if self.twin is not None:
            self.twin.step(y, [self.torque])
        if self.monitor.update(innovation.residual, innovation.covariance):
            self.restart()
        error = y[1] - (OMEGA2_REF + self.theta)
        self.integral += error * DT
        self.torque = -PI_GAINS[0] * error - PI_GAINS[1] * self.integral  # eq. 59
        self._record(innovation)

    def _redraw_due(self) -> bool:
        """Scenario 4: a new m at every multiple of the period, and at the change of its mean."""
        s = self.scenario
        return abs(self.t - s.m_period * round(self.t / s.m_period)) < 0.5 * DT or abs(self.t - s.change) < 0.5 * DT

    def _draw_m(self) -> None:
        """Scenario 4: the true m from N(mu, (std_fraction mu)^2), clipped to stay positive."""
        mu = float(self.scenario.m_mean(self.t))
        value = self.m_rng.normal(mu, RANDOM_M["std_fraction"] * mu)
        floor = RANDOM_M["floor_fraction"] * mu
        self.x[3] = max(value, floor)
        self.m_draws.append((self.t, float(self.x[3]), bool(value < floor)))

    def restart(self) -> None:
        """New P_0 for alpha and m from the restart bounds (eq. 44); omega and D keep theirs."""
        p = self.ekf.covariance
        for name, bound in RESTART_BOUNDS.items():
            i = STATES.index(name)
            p[i, :] = p[:, i] = 0.0
            p[i, i] = (bound * (self.scenario.speedup if name == "m" else 1.0) / C) ** 2
        self.ekf.reinitialize(covariance=p)
        self.monitor.reset()
        self.restarts.append(self.t)

    def _record(self, innovation) -> None:
        log = self.log
        log["t"].append(self.t)
        log["truth"].append(self.x.copy())
        log["mean"].append(self.ekf.mean)
        log["half"].append(C * np.sqrt(np.diag(self.ekf.covariance)))
        if self.twin is not None:
            log["twin_mean"].append(self.twin.mean)
            log["twin_half"].append(C * np.sqrt(np.diag(self.twin.covariance)))
        log["residual"].append(innovation.residual)
        log["S"].append(innovation.covariance)
        log["theta"].append(self.theta)

    def run_until(self, t_stop: float) -> None:
        while self.t < t_stop - 0.5 * DT and not self.failed():
            self.step()

    def branch(self) -> "Drive":
        """An independent copy (its own noise from here on) for the controlled scenario."""
        other = copy.copy(self)  # models and scalars are shared or immutable; the mutable parts are copied
        other.ekf, other.twin, other.monitor = self.ekf.copy(), None, copy.deepcopy(self.monitor)
        other.x, other.restarts, other.m_draws = self.x.copy(), list(self.restarts), list(self.m_draws)
        other.rng = np.random.default_rng(self.rng.integers(2 ** 63))
        if self.m_rng is not None:  # its own m draws too, not the parent's stream
            other.m_rng = np.random.default_rng(self.m_rng.integers(2 ** 63))
        other.log = {k: [] for k in self.log}
        return other

    def arrays(self) -> dict:
        return {k: np.array(v) for k, v in self.log.items() if v}


def rul_control(drive: Drive, seed: int) -> list[dict]:
    """Scenario 3: the RUL controller re-decides theta every period until the end of life.

    Each decision is recorded with the controller's status: ``"converged"``, or a fallback
    (``"not converged"``: the largest feasible theta met; ``"no feasible setting found"``: theta =
    CONTROL["lower"], the slowest admissible speed), which is applied as the controller returned it
    and reported by :func:`controller_fallbacks`; ``"mission met"`` once 8 h has passed (theta = 0, no
    decision taken).
    """
    s = drive.scenario
    controller = RULController(rul_ref=s.rul_ref, eta=CONTROL["eta"], gain=CONTROL["gain"] * s.speedup,
                               lower=CONTROL["lower"], tolerance=CONTROL["tolerance"] / s.speedup,
                               max_iterations=CONTROL["max_iterations"])
    decisions, k = [], 0
    while not drive.failed() and drive.t < s.end:
        origin = drive.t
        required = s.control_start + s.rul_ref - origin  # the mission: EoL >= start + RUL_ref
        if required <= 0:  # mission accomplished: back to the nominal reference
            drive.theta = 0.0
            decisions.append({"t_h": origin / HOUR * s.speedup, "theta": 0.0, "feasible": True,
                              "status": "mission met", "probability": None, "evaluations": 0})
        else:
            controller.rul_ref = required
            mean, covariance = drive.ekf.mean, drive.ekf.covariance
            decision = controller.decide(lambda theta: predict_rul(mean, covariance, origin, OMEGA2_REF + theta,
                                                                   seed=seed + 7919 * k, d_max=s.d_max),
                                         theta0=drive.theta)
            drive.theta = decision.theta
            decisions.append({"t_h": origin / HOUR * s.speedup, "theta": decision.theta,
                              "feasible": decision.feasible, "status": decision.status,
                              "probability": decision.probability, "evaluations": len(decision.history)})
        drive.run_until(origin + s.control_period)
        k += 1
    return decisions


def controller_fallbacks(results: list[dict]) -> dict:
    """Every scenario 3 decision over the seeds where the RUL controller did not converge, and what it applied.

    Parameters
    ----------
    results : list of dict
        ``run_seed``'s results.

    Returns
    -------
    dict
        ``decisions`` (the controller's decisions, "mission met" left out), ``count`` (the fallbacks
        among them) and ``at``: per fallback the seed, the time (h), the status, the theta applied
        (rad/s) and its Pr(RUL <= RUL_ref).
    """
    taken = [(r["seed"], d) for r in results for d in r["scenario_3"]["decisions"] if d["status"] != "mission met"]
    at = [{"seed": seed, "t_h": d["t_h"], "status": d["status"], "theta": d["theta"],
           "probability": d["probability"]} for seed, d in taken if d["status"] != "converged"]
    return {"decisions": len(taken), "count": len(at), "at": at}


# -- one seed ---------------------------------------------------------------------------------------------


def random_m_truth(seed: int, s: Scenario) -> Drive:
    """Scenario 4's drive at t = 0: a random true m and the EKF with restart, no twin.

    Parameters
    ----------
    seed : int
        The measurement noise and the m draws get their own streams, both derived from it and apart
        from the stream of scenarios 1-3.
    s : Scenario

    Returns
    -------
    Drive
    """
    noise, draws = np.random.SeedSequence([seed, 4]).spawn(2)
    return Drive(s, noise, twin=False, random_m=np.random.default_rng(draws))


def random_m_drive(seed: int, s: Scenario, keep_paths: int = 0):
    """Scenario 4: the drive with a random true m, its EKF with restart, and the RUL predicted at 5.0 h.

    The prediction is scenario 2's: m drawn per trajectory from the estimate's normal law and held
    (dm/dt = 0), with the Monte Carlo seed of scenario 2 (common random numbers: the two predictions
    differ by their estimates only).

    Parameters
    ----------
    seed : int
    s : Scenario
    keep_paths : int
        Monte Carlo trajectories kept for the plots.

    Returns
    -------
    (Drive, RULDistribution)
        The drive run to its end of life (or ``s.end``), and the prediction made at 5.0 h.
    """
    drive = random_m_truth(seed, s)
    drive.run_until(s.predict_with_restart)
    state = (drive.ekf.mean, drive.ekf.covariance)
    drive.run_until(s.end)
    return drive, predict_rul(*state, s.predict_with_restart, OMEGA2_REF, seed, keep_paths, s.d_max)


def run_seed(seed: int, scenario: Scenario = Scenario(), keep: bool = False) -> dict:
    """Scenarios 1-4 of section 6 on one seed."""
    started = time.perf_counter()
    s = scenario
    hours = HOUR / s.speedup  # one (unscaled) hour in scenario seconds

    def h(t):
        return float(t / hours)

    drive = Drive(s, seed)
    drive.run_until(s.predict_without_restart)
    twin_state = (drive.twin.mean, drive.twin.covariance)
    drive.run_until(s.predict_with_restart)
    restarted_state = (drive.ekf.mean, drive.ekf.covariance)
    controlled = drive.branch()
    drive.run_until(s.end)
    keep_paths = 20 if keep else 0
    prediction_1 = predict_rul(*twin_state, s.predict_without_restart, OMEGA2_REF, seed, keep_paths, s.d_max)
    prediction_2 = predict_rul(*restarted_state, s.predict_with_restart, OMEGA2_REF, seed, keep_paths, s.d_max)
    decisions = rul_control(controlled, seed)
    first = decisions[0]
    prediction_3 = predict_rul(*restarted_state, s.control_start, OMEGA2_REF + first["theta"], seed, keep_paths,
                               s.d_max)
    random_drive, prediction_4 = random_m_drive(seed, s, keep_paths)

    log, clog = drive.arrays(), controlled.arrays()
    before = log["t"] < s.change
    consistency = innovation_consistency(log["residual"][before], log["S"][before], lags=10)
    inside = np.all(np.abs(log["truth"] - log["mean"]) <= log["half"], axis=1)
    twin_inside = np.all(np.abs(log["truth"] - log["twin_mean"]) <= log["twin_half"], axis=1)
    after_restart = log["t"] >= (drive.restarts[0] if drive.restarts else np.inf)
    result = {
        "seed": seed,
        "true_eol_h": h(drive.t) if drive.failed() else None,
        "controlled_true_eol_h": h(controlled.t) if controlled.failed() else None,
        "restart_h": [h(t) for t in drive.restarts],
        "consistency_before_change": {
            "variance_ratio": consistency.variance_ratio.tolist(), "bias_z": consistency.bias_z.tolist(),
            "nis_mean": consistency.nis_mean, "nis_interval": list(consistency.nis_interval),
            "white": consistency.white, "consistent": consistency.consistent},
        "box_coverage": {
            "before_change": float(inside[before].mean()),
            "after_restart": float(inside[after_restart].mean()) if after_restart.any() else None,
            "without_restart_after_change": float(twin_inside[~before].mean()),
        },
        "m_estimate_at_eol": {"with_restart": float(log["mean"][-1, 3]),
                              "without_restart": float(log["twin_mean"][-1, 3]),
                              "true": float(log["truth"][-1, 3])},
        "scenario_1": _summary(prediction_1, h, s),
        "scenario_2": _summary(prediction_2, h, s),
        "scenario_3": {**_summary(prediction_3, h, s), "theta": first["theta"],
                       "omega2_star": OMEGA2_REF + first["theta"],
                       "decisions": decisions},
        "scenario_4": random_m_figures(random_drive, prediction_4, h, s),
        "ekf_us_per_step": drive.ekf_seconds / max(drive.ekf_steps, 1) * 1e6,
        "seconds": time.perf_counter() - started,
    }
    if keep:
        result["logs"] = {"uncontrolled": log, "controlled": clog, "random_m": random_drive.arrays()}
        result["predictions"] = (prediction_1, prediction_2, prediction_3)
        result["prediction_4"] = prediction_4
    return result


def _summary(prediction, h, s: Scenario) -> dict:
    eol = prediction.eol
    finite = eol[np.isfinite(eol)]
    return {"origin_h": h(prediction.origin), "eol_mean_h": h(np.mean(finite)) if finite.size else None,
            "eol_std_h": h(np.std(finite)) if finite.size else None,
            "eol_q05_h": h(np.quantile(eol, 0.05)), "survive_horizon": float(np.mean(~np.isfinite(eol))),
            "p_eol_before_8h": float(np.mean(eol <= 8.0 * HOUR / s.speedup))}


def random_m_figures(drive: Drive, prediction, h, s: Scenario) -> dict:
    """Scenario 4 on one seed: the random truth, the EKF's box and m error, the prediction against the truth.

    The box is read per state (alpha, m, D; Chebyshev with c = 10, at least 99 % per state by eq. 37) and,
    for m, against both the current draw and the law's mean.  The m error is relative to the law's mean
    (and to the current draw), averaged over the last hour of each regime: the hour before the change of
    the mean, and the last hour of the run if the EKF was restarted after the change.

    Parameters
    ----------
    drive : Drive
        Scenario 4's drive, run to its end.
    prediction : RULDistribution
        The prediction made at 5.0 h.
    h : callable
        Scenario seconds to story hours.
    s : Scenario

    Returns
    -------
    dict
        ``_summary``'s figures of the prediction, with the true EoL, the error of the predicted mean EoL,
        whether the true EoL lies in the predicted 5-95 % range, the restarts, the spread of the m draws,
        the box coverage and the m error.
    """
    log = drive.arrays()
    t, truth, mean, half = log["t"], log["truth"], log["mean"], log["half"]
    law = s.m_mean(t)
    hour = HOUR / s.speedup
    later = [r for r in drive.restarts if r >= s.change - 0.5 * DT]
    regimes = {"before_change": t < s.change - 0.5 * DT,
               "after_restart": t >= later[0] if later else np.zeros(t.size, bool)}
    windows = {"before_change": (t >= s.change - hour) & regimes["before_change"],
               "before_end": (t >= t[-1] - hour) & regimes["after_restart"]}
    draws = np.array([m for _, m, _ in drive.m_draws])
    draw_means = s.m_mean(np.array([d for d, _, _ in drive.m_draws]))
    true_eol = h(drive.t) if drive.failed() else None
    summary = _summary(prediction, h, s)
    q05, q95 = (h(q) for q in np.quantile(prediction.eol, [0.05, 0.95]))
    return {
        **summary,
        "true_eol_h": true_eol,
        "eol_error_h": None if true_eol is None or summary["eol_mean_h"] is None
        else summary["eol_mean_h"] - true_eol,
        "true_eol_in_90": None if true_eol is None else bool(q05 <= true_eol <= q95),
        "m_at_prediction": _m_at(prediction.origin, t, truth, mean, half, s),
        "restart_h": [h(r) for r in drive.restarts],
        "restarts_before_change": sum(r < s.change - 0.5 * DT for r in drive.restarts),
        "m_truth": {"draws": int(draws.size), "clipped": sum(c for _, _, c in drive.m_draws),
                    "relative_std": float(np.std(draws / draw_means - 1.0)),
                    "relative_range": [float(np.min(draws / draw_means - 1.0)),
                                       float(np.max(draws / draw_means - 1.0))]},
        "box_coverage": {name: _box(mask, truth, mean, half, law) for name, mask in regimes.items()},
        "m_relative_error": {name: None if not mask.any() else
                             {"vs_mean": float(np.mean(np.abs(mean[mask, 3] - law[mask]) / law[mask])),
                              "vs_draw": float(np.mean(np.abs(mean[mask, 3] - truth[mask, 3]) / truth[mask, 3]))}
                             for name, mask in windows.items()},
    }


def _m_at(origin: float, t, truth, mean, half, s: Scenario) -> dict:
    """m at the prediction time: the EKF's estimate and its bound, both also relative to the law's mean.

    With them, the true m's time average from then to the end, relative to the law's mean: roughly the
    constant m a prediction would have needed, which the draws still to come decide.
    """
    k = int(np.argmin(np.abs(t - origin)))
    mu = float(s.m_mean(origin))
    return {"estimate": float(mean[k, 3]), "half_width": float(half[k, 3]),
            "estimate_relative_to_mean": float(mean[k, 3] / mu - 1.0),
            "true_average_after_relative_to_mean": float(np.mean(truth[k:, 3]) / mu - 1.0)}


def _box(mask, truth, mean, half, law) -> dict | None:
    """Fraction of the samples in ``mask`` whose Chebyshev box holds alpha, m (its draw, its mean), D, all."""
    if not mask.any():
        return None
    inside = np.abs(truth[mask] - mean[mask]) <= half[mask]
    figures = {name: float(inside[:, STATES.index(name)].mean()) for name in ("alpha", "m", "D")}
    figures["m_mean"] = float(np.mean(np.abs(law[mask] - mean[mask, 3]) <= half[mask, 3]))
    figures["all"] = float(np.all(inside, axis=1).mean())
    return figures


# -- report -----------------------------------------------------------------------------------------------


def summarize(results: list[dict]) -> dict:
    def stat(values):
        values = np.array([v for v in values if v is not None], float)
        return {"mean": float(values.mean()), "std": float(values.std()), "min": float(values.min()),
                "max": float(values.max()), "n": int(values.size)} if values.size else None

    delays = [r["restart_h"][0] - 4.0 for r in results if r["restart_h"]]
    return {
        "seeds": len(results),
        "true_eol_h": stat(r["true_eol_h"] for r in results),
        "controlled_true_eol_h": stat(r["controlled_true_eol_h"] for r in results),
        "restart_delay_h": stat(delays),
        "restarts_before_change": int(sum(any(t < 4.0 for t in r["restart_h"]) for r in results)),
        "box_coverage_before_change": stat(r["box_coverage"]["before_change"] for r in results),
        "box_coverage_after_restart": stat(r["box_coverage"]["after_restart"] for r in results),
        "box_coverage_without_restart": stat(r["box_coverage"]["without_restart_after_change"] for r in results),
        "nis_mean_before_change": stat(r["consistency_before_change"]["nis_mean"] for r in results),
        "variance_ratio_before_change": np.mean([r["consistency_before_change"]["variance_ratio"] for r in results],
                                                axis=0).tolist(),
        "scenario_1_eol_mean_h": stat(r["scenario_1"]["eol_mean_h"] for r in results),
        "scenario_2_eol_mean_h": stat(r["scenario_2"]["eol_mean_h"] for r in results),
        "scenario_3_eol_mean_h": stat(r["scenario_3"]["eol_mean_h"] for r in results),
        "scenario_3_p_eol_before_8h": stat(r["scenario_3"]["p_eol_before_8h"] for r in results),
        "scenario_2_p_eol_before_8h": stat(r["scenario_2"]["p_eol_before_8h"] for r in results),
        "omega2_star": stat(r["scenario_3"]["omega2_star"] for r in results),
        "controller_fallbacks": controller_fallbacks(results),
        "m_without_restart_at_eol": stat(r["m_estimate_at_eol"]["without_restart"] for r in results),
        "m_with_restart_at_eol": stat(r["m_estimate_at_eol"]["with_restart"] for r in results),
        "scenario_4": summarize_random_m([r["scenario_4"] for r in results], [r["seed"] for r in results], stat),
        "ekf_us_per_step": stat(r["ekf_us_per_step"] for r in results),
        "seconds_per_seed": stat(r["seconds"] for r in results),
    }


def summarize_random_m(rows: list[dict], seeds: list[int], stat) -> dict:
    """Scenario 4 over the seeds: each figure's statistics (``stat``), restarts before the change by seed."""
    def over(*keys):
        return stat(_nested(row, keys) for row in rows)

    early = [seed for seed, row in zip(seeds, rows) if row["restarts_before_change"]]
    return {
        "true_eol_h": over("true_eol_h"), "eol_mean_h": over("eol_mean_h"), "eol_error_h": over("eol_error_h"),
        "abs_eol_error_h": stat(None if row["eol_error_h"] is None else abs(row["eol_error_h"]) for row in rows),
        "of": len(rows), "true_eol_in_90_in": sum(bool(row["true_eol_in_90"]) for row in rows),
        "restarts": stat(len(row["restart_h"]) for row in rows),
        "seeds_restarted_before_change": early,
        "first_restart_after_change_h": stat(next((t for t in row["restart_h"] if t >= 4.0), None) for row in rows),
        "m_relative_std": over("m_truth", "relative_std"), "m_clipped": sum(row["m_truth"]["clipped"] for row in rows),
        "box_coverage": {regime: {name: over("box_coverage", regime, name)
                                  for name in ("alpha", "m", "m_mean", "D", "all")}
                         for regime in ("before_change", "after_restart")},
        "m_relative_error": {window: {name: over("m_relative_error", window, name) for name in ("vs_mean", "vs_draw")}
                             for window in ("before_change", "before_end")},
        "m_at_prediction": {name: over("m_at_prediction", name)
                            for name in ("estimate_relative_to_mean", "true_average_after_relative_to_mean")},
    }


def _nested(row, keys):
    """``row[k1][k2]...``, None as soon as a level is None."""
    for key in keys:
        if row is None:
            return None
        row = row[key]
    return row


def report(summary: dict) -> str:
    def f(key, unit="h", digits=2):
        v = summary[key]
        return "n/a" if v is None else f"{v['mean']:.{digits}f} +- {v['std']:.{digits}f} {unit}".rstrip()

    lines = [
        f"  true end of life without control: {f('true_eol_h')}",
        f"  EKF restart after the m change at 4 h: delay {f('restart_delay_h')}; "
        f"restarts before the change: {summary['restarts_before_change']}",
        f"  Chebyshev box (c = 10) holds the true state: {f('box_coverage_before_change', '', 4)} of samples before "
        f"the change, {f('box_coverage_after_restart', '', 4)} after the restart, "
        f"{f('box_coverage_without_restart', '', 4)} without restart after the change",
        f"  innovations before the change: NIS mean {f('nis_mean_before_change', '', 3)} (2 expected), variance "
        f"ratios {', '.join(f'{v:.3f}' for v in summary['variance_ratio_before_change'])} (<= 1)",
        f"  scenario 1 (4.3 h, no restart): predicted EoL {f('scenario_1_eol_mean_h')}",
        f"  scenario 2 (5.0 h, restarted):  predicted EoL {f('scenario_2_eol_mean_h')}, "
        f"Pr(EoL <= 8 h) {f('scenario_2_p_eol_before_8h', '', 3)}",
        f"  scenario 3 (5.0 h, RUL control): omega2* {f('omega2_star', 'rad/s')}, predicted EoL "
        f"{f('scenario_3_eol_mean_h')}, Pr(EoL <= 8 h) {f('scenario_3_p_eol_before_8h', '', 3)}, "
        f"true EoL {f('controlled_true_eol_h')}",
        report_fallbacks(summary["controller_fallbacks"]),
        *report_random_m(summary["scenario_4"]),
        f"  EKF {f('ekf_us_per_step', 'us/step', 0)}, {f('seconds_per_seed', 's', 1)} per seed",
    ]
    return "\n".join(lines)


def report_fallbacks(fallbacks: dict) -> str:
    """One line: how many of scenario 3's decisions fell back, and when, why and what was applied then."""
    head = f"  RUL controller: {fallbacks['count']} of {fallbacks['decisions']} decisions fell back"
    if not fallbacks["count"]:
        return head + " (every decision converged)"
    return head + ": " + "; ".join(f"seed {f['seed']} at {f['t_h']:.2f} h {f['status']}, applied omega2* = "
                                   f"{OMEGA2_REF + f['theta']:.2f} rad/s (Pr(RUL <= RUL_ref) {f['probability']:.3f})"
                                   for f in fallbacks["at"])


def report_random_m(s4: dict) -> list[str]:
    """Scenario 4's lines: mean over the seeds and the worst seed (lowest coverage, largest error)."""
    def mw(v, worst="min", digits=3, unit=""):
        return "n/a" if v is None else f"{v['mean']:.{digits}f}{unit} (worst {v[worst]:.{digits}f}{unit})"

    def span(v):
        return "n/a" if v is None else f"{v['mean']:.2f} h ({v['min']:.2f}-{v['max']:.2f})"

    def span_signed(v):
        return "n/a" if v is None else f"{v['mean']:+.3f} ({v['min']:+.3f} to {v['max']:+.3f})"

    box = s4["box_coverage"]
    error = s4["m_relative_error"]
    at = s4["m_at_prediction"]
    early = s4["seeds_restarted_before_change"]
    return [
        f"  scenario 4 (random m, 5.0 h, restarted): true m drawn every {RANDOM_M['period'] / 60:g} min, relative std "
        f"{mw(s4['m_relative_std'], 'max')}, {s4['m_clipped']} clipped; EKF restarts per run "
        f"{mw(s4['restarts'], 'max', 1)}, first after the change at {mw(s4['first_restart_after_change_h'], 'max', 2)}"
        f" h; seeds restarted before the change: {', '.join(map(str, early)) or 'none'}",
        "    Chebyshev box holds (before the change / after the restart): "
        + "; ".join(f"{name} {mw(box['before_change'][name])} / {mw(box['after_restart'][name])}"
                    for name in ("alpha", "m_mean", "m", "D", "all")),
        f"    m error relative to its mean: {mw(error['before_change']['vs_mean'], 'max')} in the hour before the "
        f"change, {mw(error['before_end']['vs_mean'], 'max')} in the last hour (to the current draw: "
        f"{mw(error['before_change']['vs_draw'], 'max')}, {mw(error['before_end']['vs_draw'], 'max')})",
        f"    predicted EoL {span(s4['eol_mean_h'])}, true EoL {span(s4['true_eol_h'])}, "
        f"|error| {mw(s4['abs_eol_error_h'], 'max', 2, ' h')}; true EoL inside the predicted 5-95 % range in "
        f"{s4['true_eol_in_90_in']}/{s4['of']} seeds",
        f"    m at 5.0 h relative to its mean: estimate {span_signed(at['estimate_relative_to_mean'])}, true m "
        f"averaged from 5.0 h to the end {span_signed(at['true_average_after_relative_to_mean'])}",
    ]


def write(out: Path, summary: dict, results: list[dict], first: dict, scenario: Scenario) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    written = [out / "results.json"]
    clean = [{k: v for k, v in r.items() if k not in ("logs", "predictions", "prediction_4")} for r in results]
    written[0].write_text(json.dumps({"summary": summary, "seeds": clean,
                                      "settings": {"dt_s": DT, "substeps": SUBSTEPS, "c": C, "d_max_J": D_MAX,
                                                   "monte_carlo": MONTE_CARLO, "control": CONTROL,
                                                   "monitor": MONITOR, "restart_bounds": RESTART_BOUNDS,
                                                   "random_m": RANDOM_M, "speedup": scenario.speedup}}, indent=2))
    return written + write_figures(_plots, out, first, scenario)


def _plots(out: Path, first: dict, s: Scenario) -> list[Path]:
    plt = pyplot("Agg")

    hours = HOUR / s.speedup
    log, clog = first["logs"]["uncontrolled"], first["logs"]["controlled"]
    t = log["t"] / hours
    paths = []

    def estimate(ax, time, mean, half, truth, i, label, colour="C0"):
        ax.plot(time, truth[:, i], "k", lw=1, label="true")
        ax.plot(time, mean[:, i], colour, lw=1, label=f"{label} estimate")
        band(ax, time, mean[:, i] - half[:, i], mean[:, i] + half[:, i], color=colour, alpha=0.2,
             label="Chebyshev bounds (c = 10)")

    def save(fig, name):
        paths.append(save_figure(fig, out / name))

    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for ax, i, unit in zip(axes, (0, 1), ("omega1 (rad/s)", "omega2 (rad/s)")):
        estimate(ax, t, log["mean"], log["half"], log["truth"], i, "EKF")
        ax.set_ylabel(unit)
    axes[0].legend(fontsize=8)
    axes[1].set_xlabel("time (h)")
    save(fig, "fig05_speeds.png")

    for name, mean, half, title in (("fig06_alpha_m_restart.png", log["mean"], log["half"], "with restart"),
                                    ("fig08_alpha_m_no_restart.png", log["twin_mean"], log["twin_half"],
                                     "without restart")):
        fig, axes = plt.subplots(1, 2, figsize=(11, 4))
        estimate(axes[0], t, mean, half, log["truth"], 2, "EKF")
        estimate(axes[1], t, mean, half, log["truth"], 3, "EKF")
        axes[1].set_ylim(0, 4 * s.m_initial)
        for ax, label in zip(axes, ("alpha", "m")):
            ax.set_xlabel("time (h)")
            ax.set_ylabel(label)
            for r in first["restart_h"] if "with restart" == title else []:
                ax.axvline(r, color="r", ls="--", lw=1)
        axes[0].set_title(f"alpha, {title}")
        axes[1].set_title(f"m, {title}")
        axes[0].legend(fontsize=8)
        save(fig, name)

    fig, ax = plt.subplots(figsize=(8, 4))
    estimate(ax, t, log["mean"], log["half"], log["truth"], 4, "EKF")
    ax.axhline(s.d_max, color="r", ls=":", label="D_max")
    ax.set_xlabel("time (h)")
    ax.set_ylabel("D (J)")
    ax.legend(fontsize=8)
    save(fig, "fig07_deterioration.png")

    true_eol = first["true_eol_h"]
    for name, prediction, title in zip(("fig09_eol_no_restart.png", "fig11_eol_restart.png",
                                        "fig13_eol_controlled.png"), first["predictions"],
                                       ("scenario 1: 4.3 h, without restart", "scenario 2: 5.0 h, with restart",
                                        "scenario 3: 5.0 h, with RUL control")):
        fig, ax = plt.subplots(figsize=(7, 4))
        eol = prediction.eol[np.isfinite(prediction.eol)] / hours
        ax.hist(eol, bins=40, color="C0", alpha=0.7, label="predicted EoL")
        ax.axvline(np.mean(eol), color="C0", ls="--", label=f"mean {np.mean(eol):.2f} h")
        reference = first["controlled_true_eol_h"] if "control" in title else true_eol
        if reference is not None:
            ax.axvline(reference, color="k", label=f"true EoL {reference:.2f} h")
        ax.axvline(8.0, color="r", ls=":", label="8 h")
        ax.set_xlabel("end of life (h)")
        ax.set_title(title)
        ax.legend(fontsize=8)
        save(fig, name)

    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    tc = clog["t"] / hours
    for ax, i, label in zip(axes, (1, 2, 3), ("omega2 (rad/s)", "alpha", "m")):
        ax.plot(t, log["truth"][:, i], "k", lw=1, label="true, no control")
        ax.plot(tc, clog["truth"][:, i], "g", lw=1, label="true, RUL control")
        ax.plot(tc, clog["mean"][:, i], "C0", lw=1, label="estimate, RUL control")
        ax.set_xlabel("time (h)")
        ax.set_ylabel(label)
    axes[2].set_ylim(0, 4 * s.m_initial)
    axes[0].legend(fontsize=8)
    save(fig, "fig12_controlled.png")
    paths += _random_m_plots(plt, out, first, s)
    return paths


def _random_m_plots(plt, out: Path, first: dict, s: Scenario) -> list[Path]:
    """Scenario 4 (the paper's Figs. 14-15): m, alpha and D estimated, and 10 predicted trajectories from 5.0 h."""
    hours = HOUR / s.speedup
    log, prediction = first["logs"]["random_m"], first["prediction_4"]
    t = log["t"] / hours
    shown = min(10, prediction.trajectories.shape[2])
    paths = []
    for name, states in (("fig14_m_random.png", ("m",)), ("fig15_alpha_D_random.png", ("alpha", "D"))):
        fig, axes = plt.subplots(1, len(states), figsize=(6 * len(states), 4), squeeze=False)
        for ax, state in zip(axes[0], states):
            i = STATES.index(state)
            ax.plot(t, log["truth"][:, i], "k", lw=0.8, label="true", zorder=3)  # above the estimate it tracks
            if state == "m":
                ax.plot(t, s.m_mean(log["t"]), "k:", lw=1, label="mean of the true m")
            ax.plot(t, log["mean"][:, i], "C0", lw=1, label="EKF estimate (restart)")
            band(ax, t, log["mean"][:, i] - log["half"][:, i], log["mean"][:, i] + log["half"][:, i], color="C0",
                 alpha=0.2, label="Chebyshev bounds (c = 10)")
            _predicted_paths(ax, prediction, i - 2, shown, hours)
            if state == "D":
                ax.axhline(s.d_max, color="r", ls=":", label="D_max")
            if state == "m":
                ax.set_ylim(0, 4 * s.m_initial)
            ax.set_xlabel("time (h)")
            ax.set_ylabel(state)
        axes[0][0].legend(fontsize=8)
        axes[0][0].set_title(f"scenario 4: random m, prediction at {s.predict_with_restart / hours:.1f} h")
        paths.append(save_figure(fig, out / name))
    return paths


def _predicted_paths(ax, prediction, j: int, shown: int, hours: float) -> None:
    """The first ``shown`` Monte Carlo trajectories of deterioration state ``j``, each up to its own failure."""
    for k in range(shown):
        alive = prediction.times <= prediction.eol[k]
        ax.plot(prediction.times[alive] / hours, prediction.trajectories[alive, j, k], color="C1", lw=0.6,
                alpha=0.7, label="predicted (10 draws)" if k == 0 else None)


def _progress(quiet: bool, done: int, total: int) -> None:
    if not quiet:
        print(f"\r  seeds {done}/{total}", end="\n" if done == total else "", file=sys.stderr, flush=True)


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description="Friction drive, Rodriguez Obando et al. (2021): EKF deterioration "
                                                 "estimation, Chebyshev bounds, restart, Monte Carlo RUL, RUL control")
    parser.add_argument("--seeds", type=int, default=4, help="number of noise seeds (default 4)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2, help="processes over seeds (default 2)")
    parser.add_argument("--speedup", type=float, default=1.0,
                        help="run the story this many times faster (m times k, times / k), for quick checks")
    parser.add_argument("--out", type=Path, help="directory for results.json and the figures")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error("--seeds must be at least 1")
    if not args.speedup >= 1.0:
        parser.error("--speedup must be at least 1")
    scenario = Scenario().scaled(args.speedup) if args.speedup != 1.0 else Scenario()
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    print(f"Rodriguez Obando et al. (2021) on the friction drive: omega2_ref = {OMEGA2_REF} rad/s, "
          f"m {scenario.m_initial:g} -> {scenario.m_after:g} at 4 h, D_max = {scenario.d_max:g} J, {len(seeds)} seeds"
          + (f", {args.speedup:g}x faster" if args.speedup != 1.0 else ""))
    results = over_seeds(run_seed, [(seed, scenario, i == 0) for i, seed in enumerate(seeds)],
                         workers=max(1, args.workers), progress=lambda done, total: _progress(args.quiet, done, total))
    first = results[0]
    summary = summarize(results)
    print(report(summary))
    if args.out:
        for path in write(args.out, summary, results, first, scenario):
            print(f"  wrote {path}")
    return summary


if __name__ == "__main__":
    run_main(main)
