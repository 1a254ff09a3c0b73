"""The estimators' scenarios the unit tests share, written with the public API (no test imports an example).

The case studies' truth laws and sensor records (the torsion bar's friction growing, its encoders,
the RLC's drifting resistor) live in :mod:`bondgraph.scenarios`, shared with the examples and the
benchmarks.  Here, the estimators' set-ups built on them:

* ``ThreeTanks``: the three tanks of Du et al. as a discrete model with az2 as an extra state (eqs. 59,
  62), the az2 drift of eq. 61, and the Kalman filters (plain or strong tracking) tuned for it;
* ``FrictionDriveRUL``: the Monte Carlo RUL of the friction drive of Rodriguez Obando et al. (2021)
  under a held speed omega2* (eqs. 45-46), failure when alpha reaches 0 or D reaches D_max.

The examples in ``examples/`` build the same scenarios for their case studies; ``tests/cases`` runs them.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import sympy as sp

from bondgraph.library import THREE_TANK, friction_drive, three_tank
from bondgraph.scenarios import three_tank_az2
from prognosis.lifecontrol import chebyshev_intervals, energy_deterioration, monte_carlo_rul
from prognosis.statespace import (BootstrapParticleFilter, CubatureKalmanFilter, ExtendedKalmanFilter, StrongTracking,
                                  UnscentedKalmanFilter, discretize)

# -- the three tanks of Du et al. ---------------------------------------------------------------------------


class ThreeTanks:
    """Du et al., section 6: 200 steps of 1 s, az2 drifting by eq. 61 from k = 10, noises of eqs. 59-60."""

    STEPS = 200
    ONSET = 10  # az2 drifts from k = 11
    RATE = 1e-4
    AREA = THREE_TANK["A_s"]
    INPUTS = {"Q1": THREE_TANK["Q1"], "Q2": THREE_TANK["Q2"]}
    LEVELS_0 = (1.0, 0.95, 0.9)  # m
    PROCESS_STD = 1e-4  # m, w_k on the levels (eq. 59)
    NOISE_STD = 2e-4  # m, v_k (eq. 60)
    PARAMETER_STD = 1e-3  # d_k of eq. 62, the random walk the filters assume for az2
    INITIAL_PARAMETER_STD = 0.03  # 5 % of az2_n
    FORGETTING, SOFTENING = 0.95, 1.0  # rho and beta of the strong tracking filter

    @staticmethod
    @lru_cache(maxsize=None)
    def model():
        """Discrete model, state (q_A_1, q_A_2, q_A_3, az2): tank volumes from the bond graph, levels measured."""
        bg = three_tank(uncertainty=0.05, area_uncertainty=0.02)
        return discretize(bg.state_equations(), dt=1.0, augment=["az2"], outputs=["h1", "h2", "h3"])

    @classmethod
    def az2_drift(cls, steps: int = STEPS) -> np.ndarray:
        """Eq. 61: az2_k = 0.6 for k <= 10, az2_{k-1} + 1e-4 (k - 10) after; entry k - 1 is time k."""
        return three_tank_az2(steps, cls.ONSET, cls.RATE)

    @classmethod
    def simulate_tanks(cls, seed: int, drift: bool = True, steps: int = STEPS) -> tuple[np.ndarray, np.ndarray]:
        """True states (steps, 4) and measured levels (steps, 3); az2 follows the drift or stays nominal."""
        m = cls.model()
        rng = np.random.default_rng(seed)
        az2 = cls.az2_drift(steps) if drift else np.full(steps, THREE_TANK["az2"])
        x = np.array([*(cls.AREA * h for h in cls.LEVELS_0), THREE_TANK["az2"]])
        states = np.empty((steps, 4))
        for k in range(steps):
            x = m.transition(x, cls.INPUTS)
            x[:3] += cls.AREA * cls.PROCESS_STD * rng.standard_normal(3)
            x[3] = az2[k]
            states[k] = x
        levels = m.measure(states.T).T
        return states, levels + cls.NOISE_STD * rng.standard_normal(levels.shape)

    @classmethod
    def estimator(cls, name: str, seed: int = 0):
        """A fresh filter (EKF, UKF, SCKF, their strong tracking ST* forms, or PF) at k = 0, az2 nominal."""
        m = cls.model()
        x0 = np.array([*(cls.AREA * h for h in cls.LEVELS_0), THREE_TANK["az2"]])
        p0 = np.diag([(cls.AREA * cls.NOISE_STD) ** 2] * 3 + [cls.INITIAL_PARAMETER_STD ** 2])
        q = np.diag([(cls.AREA * cls.PROCESS_STD) ** 2] * 3 + [cls.PARAMETER_STD ** 2])
        r = np.eye(3) * cls.NOISE_STD ** 2
        if name == "PF":
            return BootstrapParticleFilter(m, x0, p0, q, r, n_particles=1000, seed=seed)
        fading = StrongTracking(cls.FORGETTING, cls.SOFTENING) if name.startswith("ST") else None
        family = {"EKF": ExtendedKalmanFilter, "UKF": UnscentedKalmanFilter, "SCKF": CubatureKalmanFilter}
        return family[name[2:] if name.startswith("ST") else name](m, x0, p0, q, r, fading=fading)


# -- the friction drive of Rodriguez Obando et al. (2021) ---------------------------------------------------


class FrictionDriveRUL:
    """Eq. 46 from an (omega1, omega2, alpha, m, D) estimate: Monte Carlo over the Chebyshev box of (alpha, m, D)."""

    C = 10.0  # Chebyshev scale: 1 - 5/c^2 = 95 %
    D_MAX = 5e6  # J, maximal admissible deterioration
    ALPHA_MIN = 0.0
    MONTE_CARLO = {"n_samples": 1000, "dt": 30.0, "horizon": 12 * 3600.0}

    @staticmethod
    @lru_cache(maxsize=None)
    def contact_power():
        """Power dissipated by the contact as a numpy function of (alpha, omega2*), omega2 held (eq. 45).

        From the bond graph: the speeds' state equations with the energy deterioration appended; holding
        d omega2/dt = 0 gives the omega1 the contact needs, substituted into the contact power.
        """
        speeds = friction_drive().state_equations().coenergy_states({"J1": "omega1", "J2": "omega2"})
        equations = energy_deterioration(speeds, "alpha", rate_value=1e-6)
        omega1, omega2, alpha = (sp.Symbol(n) for n in ("omega1", "omega2", "alpha"))
        held = sp.solve(sp.Eq(equations.rhs[1], 0), omega1)[0]
        power = sp.simplify(equations.power.subs(omega1, held).subs(equations.parameters))
        return sp.lambdify((alpha, omega2), power, "numpy")

    @classmethod
    def margin(cls, x):
        """Distance to failure of (alpha, m, D): > 0 while working."""
        return np.minimum(x[0] - cls.ALPHA_MIN, (cls.D_MAX - x[2]) / cls.D_MAX * 10.0)

    @classmethod
    def predict_rul(cls, mean, covariance, t, omega2_star, seed):
        """RUL distribution from time ``t`` at the speed ``omega2_star``; draws in the box and alpha, m, D >= 0."""
        power = cls.contact_power()
        idx = [2, 3, 4]
        mu, p = np.asarray(mean)[idx], np.asarray(covariance)[np.ix_(idx, idx)]
        lo, hi = chebyshev_intervals(mu, p, cls.C)

        def rates(x, _t):
            dissipated = power(x[0], omega2_star)
            return np.vstack([-x[1] * dissipated, np.zeros_like(dissipated), dissipated])

        return monte_carlo_rul(rates, mu, p, cls.margin, origin=t, horizon=cls.MONTE_CARLO["horizon"],
                               dt=cls.MONTE_CARLO["dt"], n_samples=cls.MONTE_CARLO["n_samples"],
                               lower=np.maximum(lo, 0.0), upper=hi, seed=seed)
