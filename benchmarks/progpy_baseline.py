"""ProgPy baseline: particle filter + Monte-Carlo RUL on the torsion-bar friction fault.

Jha et al. (2016), section 6.3: the motor-disk friction b_Md of the
torsion bar degrades exponentially, b_k = b_{k-1} exp(gamma_{k-1} dt), with an
unknown rate gamma (random walk).  The residual of the ARR is the observation,
y_k = (b_k - b_n) * (-omega_m / k_belt^2) + w.  Failure: b >= 0.45.

This file measures NASA's ProgPy (PyPI ``progpy``) on that problem so our own
benchmark can print ratios against it.  ProgPy is NOT a dependency of the
toolkit: it lives in its own virtualenv, ``benchmarks/.venv-progpy``.

Run inside that venv (prints one JSON object with --json):

    python -m venv benchmarks/.venv-progpy
    benchmarks/.venv-progpy/bin/pip install progpy==1.9.0
    benchmarks/.venv-progpy/bin/python benchmarks/progpy_baseline.py \
        --steps 900 --predictions 3 --particles 500 --json

From the main environment (progpy not installed there):

    from benchmarks.progpy_baseline import run_baseline   # or importlib by path
    ref = run_baseline(steps=900, predictions=3, particles=500)
    ref["filter_seconds_per_step"], ref["prediction_seconds_each"]

What is timed
-------------
* filter: ``estimator.estimate(t, u, z)`` of ``progpy.state_estimators.ParticleFilter``
  (N particles, vectorized model), mean over all ``--steps`` steps;
* prediction: ``progpy.predictors.MonteCarlo.predict(estimator.x, future_loading,
  dt=0.1, horizon=...)`` with n_samples = N, mean over ``--predictions`` calls
  made at times spread evenly over the run (t = 40, 60, 80 s for 900 steps).
  ProgPy's MonteCarlo simulates the samples one by one (it is not vectorized).

Modelling choices (the same ones our benchmark should use to be comparable)
--------------------------------------------------------------------------
* ProgPy applies process noise as ``x += dt * N(0, process_noise)``, so the
  per-step standard deviations sigma_v = 1e-5 (b) and 0.02 (gamma) are given to
  ProgPy as rates sigma / dt.
* Observations are generated from the truth b*(t) = b_n exp(0.05 (t - 10)) with
  the residual noise std 0.01 (``--obs-std``); the filter's likelihood uses the
  std 2 * 0.01 (4x the residual variance), as in Jha et al. (2016).
* omega_m = 112.5 rad/s is a constant model parameter: ProgPy's ``output(x)``
  takes no input, so it cannot be a ProgPy input of the observation.
* Prediction: by default the predictor's model keeps the process noise on b but
  holds gamma constant along each trajectory (the estimation random walk of
  gamma, std 0.02 per step, integrated over ~600 prediction steps, would
  otherwise give a log-spread of b of ~17 and meaningless RULs).  Use
  ``--predict-gamma-walk`` to keep the random walk in prediction; the per-step
  cost is the same either way.
* The RUL reported at each prediction point is the median over the samples
  that reach the threshold within the horizon; mean, 5th/95th percentiles and
  the fraction reaching it are in ``rul_details``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

# ---------------------------------------------------------------- constants
DT = 0.1  # s
T_START = 10.0  # s, fault onset and start of filtering
B_NOMINAL = 5.025e-3  # N.m.s/rad, theta_n
K_BELT = 3.75
OMEGA_M = 112.5  # rad/s
GAMMA_TRUE = 0.05  # 1/s
SIGMA_B = 1e-5  # per-step std of the process noise on b
SIGMA_GAMMA = 0.02  # per-step std of the random walk of gamma
RESIDUAL_STD = 0.01  # std of the residual noise used to generate observations
FILTER_MEAS_STD = 2 * RESIDUAL_STD  # filter likelihood std (variance x4)
B_FAIL = 0.45  # failure threshold on b
DELTA_BOX = (0.0, 0.2)  # uncertainty box of b_Md (multiplicative delta)

HERE = Path(__file__).resolve().parent
VENV_DIR = HERE / ".venv-progpy"
PROGPY_REQUIREMENT = "progpy==1.9.0"


def true_b(t):
    """Truth used to generate observations: b*(t) = b_n exp(0.05 (t - 10)), t >= 10 s."""
    import numpy as np

    return B_NOMINAL * np.exp(GAMMA_TRUE * (np.asarray(t) - T_START))


def true_rul(t: float) -> float:
    """Time for the truth to reach B_FAIL from time t (about 100 - t)."""
    import math

    return T_START + math.log(B_FAIL / B_NOMINAL) / GAMMA_TRUE - t


# ------------------------------------------------------- runs inside the venv
def make_model_class():
    """Build the ProgPy model class (progpy imported here, not at module import)."""
    import numpy as np
    from progpy import PrognosticsModel

    class TorsionBarFriction(PrognosticsModel):
        """Exponential growth of the motor-disk friction b_Md with unknown rate gamma."""

        inputs = []
        states = ["b", "gamma"]
        outputs = ["y"]
        events = ["failure"]
        is_vectorized = True

        default_parameters = {
            "b_nominal": B_NOMINAL,
            "k_belt": K_BELT,
            "omega_m": OMEGA_M,
            "b_fail": B_FAIL,
            # ProgPy scales process noise by dt: give per-step std / dt.
            "process_noise": {"b": SIGMA_B / DT, "gamma": SIGMA_GAMMA / DT},
            "measurement_noise": {"y": FILTER_MEAS_STD},
            "x0": {"b": B_NOMINAL, "gamma": 0.0},
        }

        def next_state(self, x, u, dt):
            gamma = x["gamma"]
            return self.StateContainer(
                np.array(
                    [
                        np.atleast_1d(x["b"] * np.exp(gamma * dt)),
                        np.atleast_1d(gamma),
                    ]
                )
            )

        def output(self, x):
            p = self.parameters
            gain = -p["omega_m"] / p["k_belt"] ** 2
            return self.OutputContainer(
                np.array([np.atleast_1d((x["b"] - p["b_nominal"]) * gain)])
            )

        def event_state(self, x):
            p = self.parameters
            frac = (x["b"] - p["b_nominal"]) / (p["b_fail"] - p["b_nominal"])
            return {"failure": np.clip(1.0 - frac, 0.0, 1.0)}

        def threshold_met(self, x):
            return {"failure": x["b"] >= self.parameters["b_fail"]}

    return TorsionBarFriction


def prediction_steps(steps: int, predictions: int) -> list[int]:
    """Step indices (1-based) of the predictions: evenly over [T/3, 7T/9] of the run.

    For 900 steps of 0.1 s from t = 10 s this is t = 40, 60, 80 s.
    """
    if predictions <= 0:
        return []
    if predictions == 1:
        fracs = [1.0 / 3.0]
    else:
        lo, hi = 1.0 / 3.0, 7.0 / 9.0
        fracs = [lo + (hi - lo) * i / (predictions - 1) for i in range(predictions)]
    return sorted({max(1, min(steps, round(f * steps))) for f in fracs})


def run(
    steps: int = 900,
    predictions: int = 3,
    particles: int = 500,
    seed: int = 3,
    horizon: float = 200.0,
    obs_std: float = RESIDUAL_STD,
    predict_gamma_walk: bool = False,
    log=None,
) -> dict:
    """Run the ProgPy filter and predictor; must be called where progpy is installed."""
    import numpy as np
    import progpy
    from progpy.predictors import MonteCarlo
    from progpy.state_estimators import ParticleFilter
    from progpy.uncertain_data import UnweightedSamples

    try:
        from importlib.metadata import version

        progpy_version = version("progpy")
    except Exception:  # pragma: no cover
        progpy_version = getattr(progpy, "__version__", "unknown")

    wall0 = time.perf_counter()
    Model = make_model_class()
    model = Model()
    if predict_gamma_walk:
        pred_model = model
    else:
        pred_model = Model(process_noise={"b": SIGMA_B / DT, "gamma": 0.0})

    # Observations from the truth (own generator, independent of ProgPy's draws).
    data_rng = np.random.default_rng(seed + 1000)
    times = T_START + DT * np.arange(1, steps + 1)
    gain = -OMEGA_M / K_BELT**2
    y_obs = (true_b(times) - B_NOMINAL) * gain + data_rng.normal(0.0, obs_std, steps)

    # ProgPy (and filterpy's resampler) draw from numpy's global generator.
    np.random.seed(seed)
    b0 = np.random.uniform(
        B_NOMINAL * (1 + DELTA_BOX[0]), B_NOMINAL * (1 + DELTA_BOX[1]), particles
    )
    x0 = UnweightedSamples(
        {"b": b0, "gamma": np.zeros(particles)}, _type=model.StateContainer
    )
    estimator = ParticleFilter(
        model,
        x0,
        num_particles=particles,
        t0=T_START,
        measurement_noise={"y": FILTER_MEAS_STD},
    )
    predictor = MonteCarlo(pred_model, n_samples=particles)
    u = model.InputContainer({})

    def future_loading(t, x=None):
        return u

    pred_at = set(prediction_steps(steps, predictions))
    filter_times = np.empty(steps)
    pred_seconds, pred_points, rul_med, rul_details = [], [], [], []
    pred_sim_steps = []
    track = []
    perf = time.perf_counter
    for k in range(steps):
        t = float(times[k])
        z = model.OutputContainer({"y": float(y_obs[k])})
        t0 = perf()
        estimator.estimate(t, u, z)
        filter_times[k] = perf() - t0
        if (k + 1) % max(1, steps // 9) == 0 or k + 1 == steps:
            bs = estimator.particles["b"]
            track.append(
                {
                    "t": round(t, 3),
                    "b_est": float(np.mean(bs)),
                    "b_true": float(true_b(t)),
                    "gamma_est": float(np.mean(estimator.particles["gamma"])),
                }
            )
        if (k + 1) in pred_at:
            t0 = perf()
            res = predictor.predict(
                estimator.x,
                future_loading,
                dt=DT,
                horizon=horizon,
                t0=t,
                events=["failure"],
            )
            pred_seconds.append(perf() - t0)
            toe = [s["failure"] for s in res.time_of_event]
            hit = np.array([v for v in toe if v is not None], dtype=float) - t
            # model steps simulated (a sample that never fails runs the whole horizon)
            n_sim = int(round((hit.sum() + (len(toe) - hit.size) * horizon) / DT))
            pred_sim_steps.append(n_sim)
            pred_points.append(round(t, 3))
            if hit.size:
                med = float(np.median(hit))
                det = {
                    "t": round(t, 3),
                    "rul_median": med,
                    "rul_mean": float(np.mean(hit)),
                    "rul_p05": float(np.percentile(hit, 5)),
                    "rul_p95": float(np.percentile(hit, 95)),
                    "fraction_reaching_threshold": hit.size / len(toe),
                    "true_rul": true_rul(t),
                }
            else:
                med = None
                det = {"t": round(t, 3), "rul_median": None,
                       "fraction_reaching_threshold": 0.0, "true_rul": true_rul(t)}
            rul_med.append(med)
            rul_details.append(det)
            if log:
                log(f"prediction at t={t:.1f}s: {pred_seconds[-1]:.2f} s, "
                    f"RUL median {med} (truth {true_rul(t):.2f})")

    if abs(estimator.t - float(times[-1])) > 1e-9:
        raise RuntimeError(f"filter time drifted: {estimator.t} vs {times[-1]}")

    return {
        "progpy_version": progpy_version,
        "particles": particles,
        "filter_steps": steps,
        "filter_seconds_per_step": float(np.mean(filter_times)),
        "filter_seconds_per_step_median": float(np.median(filter_times)),
        "predictions": len(pred_seconds),
        "prediction_seconds_each": float(np.mean(pred_seconds)) if pred_seconds else None,
        "prediction_seconds": pred_seconds,
        "prediction_times": pred_points,
        # sample-steps simulated per prediction, and the cost of one of them:
        # a prediction's time scales with how far its samples must run.
        "prediction_sample_steps": pred_sim_steps,
        "prediction_seconds_per_sample_step": (
            float(sum(pred_seconds) / sum(pred_sim_steps)) if pred_sim_steps else None),
        "final_estimate_b": float(np.mean(estimator.particles["b"])),
        "final_true_b": float(true_b(times[-1])),
        "final_estimate_gamma": float(np.mean(estimator.particles["gamma"])),
        "rul_at_prediction_points": rul_med,
        "true_rul_at_prediction_points": [true_rul(t) for t in pred_points],
        "rul_details": rul_details,
        "track": track,
        "settings": {
            "dt": DT,
            "t_start": T_START,
            "horizon": horizon,
            "seed": seed,
            "obs_std": obs_std,
            "filter_meas_std": FILTER_MEAS_STD,
            "sigma_b": SIGMA_B,
            "sigma_gamma": SIGMA_GAMMA,
            "predict_gamma_walk": predict_gamma_walk,
            "python": sys.version.split()[0],
            "numpy": np.__version__,
        },
        "wall_seconds": time.perf_counter() - wall0,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=900)
    ap.add_argument("--predictions", type=int, default=3)
    ap.add_argument("--particles", type=int, default=500)
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--horizon", type=float, default=200.0)
    ap.add_argument("--obs-std", type=float, default=RESIDUAL_STD)
    ap.add_argument("--predict-gamma-walk", action="store_true",
                    help="keep gamma's random walk during prediction")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    res = run(args.steps, args.predictions, args.particles, args.seed, args.horizon,
              args.obs_std, args.predict_gamma_walk, log=log)
    if args.json:
        print(json.dumps(res))
        return 0
    print(f"ProgPy {res['progpy_version']}, N = {res['particles']}, "
          f"{res['filter_steps']} steps of {DT} s from t = {T_START} s")
    print(f"filter:     {res['filter_seconds_per_step'] * 1e3:.3f} ms/step (mean), "
          f"{res['filter_seconds_per_step_median'] * 1e3:.3f} ms (median)")
    if res["prediction_seconds_each"] is not None:
        print(f"prediction: {res['prediction_seconds_each']:.3f} s each "
              f"({res['predictions']} predictions; "
              f"{res['prediction_seconds_per_sample_step'] * 1e6:.1f} us per sample-step, "
              f"sample-steps {res['prediction_sample_steps']})")
    print(f"{'t':>7} {'b_est':>11} {'b_true':>11} {'gamma_est':>10}")
    for r in res["track"]:
        print(f"{r['t']:7.1f} {r['b_est']:11.5f} {r['b_true']:11.5f} {r['gamma_est']:10.4f}")
    print(f"{'t':>7} {'RUL med':>9} {'mean':>8} {'p05':>8} {'p95':>8} {'reach':>6} {'truth':>8}")
    for d in res["rul_details"]:
        if d["rul_median"] is None:
            print(f"{d['t']:7.1f}   (no sample reached the threshold)  truth {d['true_rul']:.2f}")
            continue
        print(f"{d['t']:7.1f} {d['rul_median']:9.2f} {d['rul_mean']:8.2f} {d['rul_p05']:8.2f} "
              f"{d['rul_p95']:8.2f} {d['fraction_reaching_threshold']:6.2f} {d['true_rul']:8.2f}")
    print(f"wall time: {res['wall_seconds']:.1f} s")
    return 0


# -------------------------------------------- runs in the main environment
def _venv_python(venv: Path) -> Path:
    for rel in ("bin/python", "Scripts/python.exe"):
        p = venv / rel
        if p.exists():
            return p
    return venv / "bin" / "python"


def _has_progpy(python: Path) -> bool:
    r = subprocess.run([str(python), "-c", "import progpy"], capture_output=True)
    return r.returncode == 0


def ensure_venv(venv: Path = VENV_DIR) -> Path:
    """Create ``venv`` with ProgPy installed if needed; return its interpreter."""
    def log(msg):
        print(f"[progpy_baseline] {msg}", file=sys.stderr, flush=True)

    python = _venv_python(venv)
    if not python.exists():
        log(f"creating virtualenv {venv}")
        r = subprocess.run([sys.executable, "-m", "venv", str(venv)],
                           capture_output=True, text=True)
        if r.returncode != 0:
            raise RuntimeError(f"python -m venv {venv} failed: {r.stderr.strip()[-2000:]}")
        python = _venv_python(venv)
    if not _has_progpy(python):
        errors = []
        for req in (PROGPY_REQUIREMENT, "progpy"):
            log(f"pip install {req} into {venv} (pulls numpy, scipy, ...)")
            r = subprocess.run([str(python), "-m", "pip", "install", "-q", req],
                               capture_output=True, text=True)
            if r.returncode == 0 and _has_progpy(python):
                break
            errors.append(f"{req}: {r.stderr.strip()[-1500:]}")
        else:
            raise RuntimeError("could not install progpy: " + " | ".join(errors))
        log("progpy installed")
    return python


def run_baseline(steps: int = 900, predictions: int = 3, particles: int = 500,
                 python=None, extra_args=None, timeout: float | None = 3600) -> dict:
    """Run this script under ProgPy's interpreter and return its JSON result.

    ``python``: interpreter with progpy; default benchmarks/.venv-progpy (created
    with ``python -m venv`` and ``pip install progpy`` if it does not exist).
    Raises RuntimeError if the venv cannot be made or the run fails.
    """
    py = Path(python) if python is not None else ensure_venv(VENV_DIR)
    cmd = [str(py), str(Path(__file__).resolve()), "--steps", str(steps),
           "--predictions", str(predictions), "--particles", str(particles), "--json"]
    cmd += list(extra_args or [])
    print(f"[progpy_baseline] running {' '.join(cmd)}", file=sys.stderr, flush=True)
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)  # keep the toolkit's path out of the venv
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise RuntimeError(f"ProgPy baseline could not run: {exc}") from exc
    if r.returncode != 0:
        raise RuntimeError(
            f"ProgPy baseline failed (exit {r.returncode}): {r.stderr.strip()[-2000:]}")
    lines = [ln for ln in r.stdout.splitlines() if ln.strip().startswith("{")]
    if not lines:
        raise RuntimeError(f"ProgPy baseline printed no JSON: {r.stdout[-2000:]!r}")
    return json.loads(lines[-1])


if __name__ == "__main__":
    sys.exit(main())
