"""The main job (examples/torsion_bar.py) runs and reproduces the facts docs/design.md states for the torsion bar of
Jha et al. (2016)."""

import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.slow  # runs of an example script


@pytest.fixture(scope="module")
def b_md(example):
    """The simulated b_Md scenario (deterministic), shared by the tests below."""
    return example.simulate_case(example.CASES["b-md"])


def test_torsion_bar_example_reproduces_the_degradation_scenario(example, b_md):
    facts = b_md.facts
    assert facts["dependent_storage"] == ["J_Md"]
    assert facts["omega_Md_end_nominal_rad_s"] == pytest.approx(30.0, rel=1e-4)
    # docs/design.md: saturation in the mid-40 s, omega_Md = 3 rad/s and b_Md = 0.45 at t = 100 s
    assert 42.0 < facts["saturation_time_s"] < 48.0
    assert facts["omega_Md_end_degraded_rad_s"] == pytest.approx(3.0, abs=0.1)
    case = example.CASES["b-md"]
    assert case.truth(100.0) == pytest.approx(0.452, abs=0.002)
    assert case.truth(case.eol) == pytest.approx(0.45) and 99.0 < case.eol < 100.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_torsion_bar_detection_without_false_alarms(example, b_md, seed):
    """No false alarm on a 100 s nominal run; the b_Md degradation from t = 10 s is detected."""
    figures = example.detect("b-md", b_md, seed=seed, noise="quiet")
    assert figures["arrs"] == ["ARR_1_1", "ARR_1_2"]
    assert figures["false_alarms_nominal"] == 0
    # b_Md must leave its [0, +20 %] box plus the noise margin: about 4.4 s after onset at 112.5 rad/s
    assert 3.0 < figures["detection_delay_s"] < 6.0
    # with the paper's 0.01 N.m on the torque the margin is about ten times wider: b_Md must grow further
    loud = example.detect("b-md", b_md, seed=seed)
    assert loud["false_alarms_nominal"] == 0 and 10.0 < loud["detection_delay_s"] < 20.0
    assert figures["interval_never_wider_than_bglft"]
    assert figures["interval_width_median"] < figures["bglft_width_median"]


def test_b_md_prognosis_figures_on_a_short_run(example):
    """The whole chain with fewer particles and a 65 s horizon: the figures land within loose bounds."""
    run = example.run("b-md", seed=3, t_end=65.0, n_particles=100, workers=1, noise="quiet")
    figures = run.figures
    # detect(), which the detection tests use, gives the alarm the whole chain acted on
    alone = example.detect("b-md", run.scenario, seed=3, noise="quiet")
    assert figures["detection_time_s"] == alone["detection_time_s"]
    assert figures["filter_steps"] == pytest.approx((65.0 - figures["detection_time_s"]) / 0.1, abs=1.5)
    # gamma starts from a prior over four decades of life, not from a band around the true rate: its error
    # over the whole run is larger than with the first round's band, while theta and the RUL stay close
    assert figures["rmse_theta"] < 0.05 and figures["rmse_gamma"] < 0.35
    assert figures["ra"] > 0.9 and figures["alpha_lambda_pass_rate"] > 0.7
    assert 0 < figures["rmad_rul"] < 0.3 and figures["prognostic_horizon_s"] > 40.0


def test_seed_preset_keeps_the_seeds_tuning(example):
    case = example.CASES["b-md"]
    settings = example.tuning(case, "paper", residual_std=1e-3)
    assert settings["noise_std"] == 0.01 and settings["inflation"] == 4.0 and settings["gamma_std"] == 0.02
    assert settings["adaptation"].gain == 0.001 and settings["adaptation"].reference == 0.10
    assert settings["adaptation"].band == (0.03, 0.07) and settings["start"] == "uncertainty_box"
    assert settings["prediction_walk"] == 1.0  # Table IV keeps the random walk in the prediction
    with pytest.raises(ValueError, match="unknown preset 'tuned'"):
        example.tuning(case, "tuned", residual_std=1e-3)


@pytest.mark.parametrize("case, law", [("mass-linear", "linear"), ("mass-exponential", "exponential")])
def test_mass_cases_simulate_the_load_and_estimate_it(example, case, law):
    """Section 7 as simulations: the load M follows its law to M_fail and the chain estimates it."""
    spec = example.CASES[case]
    assert spec.law == law and spec.truth(spec.eol) == pytest.approx(spec.theta_fail)
    r = example.run(case, seed=0, n_particles=50, workers=1, noise="quiet")
    f = r.figures
    assert f["false_alarms_nominal"] == 0 and f["detection_time_s"] < spec.after
    assert f["rmse_theta"] < 0.1
    # N = 50 leaves the RUL to the draw: mass-exponential over seeds 0-19 has RA 0.73 on average, 0.47 at worst, and
    # above 0.85 in 5 of 20 seeds (6 of 20 before the seeds' streams were made independent, seed 0 among them)
    assert f["ra"] > 0.4
    assert r.arr.uncertainties["mu"] == (-0.1, 0.1)  # Table VI's mu enters the thresholds


@pytest.mark.extras   # the plots: matplotlib, the plot extra
def test_main_writes_results_csv_and_plots_over_runs(example, tmp_path, capsys):
    figures = example.main(["--case", "mass-exponential", "--runs", "2", "--particles", "30", "--workers", "1",
                            "--out", str(tmp_path)])
    results = json.loads((tmp_path / "results.json").read_text())
    assert results == json.loads(json.dumps(figures))
    for key in example.KEYS:
        assert key in results and f"{key}_std" in results
    assert results["seeds"] == [0, 1] and len(results["runs"]) == 2
    mean = sum(r["rmse_theta"] for r in results["runs"]) / 2
    assert results["rmse_theta"] == pytest.approx(mean)
    header = (tmp_path / "prognosis.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["t", "theta_true", "theta_mean"] and "rul_median" in header
    assert (tmp_path / "timeseries.csv").read_text().startswith("t,theta_true,U_nominal")
    for name in ("fig08_speed_voltage", "fig09_residual_thresholds", "fig10_theta", "fig11_gamma", "fig12_rul"):
        assert (tmp_path / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    printed = capsys.readouterr().out
    assert "RMSE theta (%)" in printed and "Jha et al. (2016)" in printed


def test_sweep_ladder_ends_at_the_named_preset_and_runs_a_group(example):
    from tests.cases.conftest import load_example

    sweep = load_example("torsion_bar_sweep")
    case = example.CASES["mass-linear"]
    named = example.tuning(case, "named", residual_std=6e-4)
    last = sweep.ladder(case, residual_std=6e-4)[-1][2]
    for key in ("noise_std", "inflation", "gamma_std", "start", "prediction_walk"):
        assert last[key] == named[key], key
    assert (last["gamma0"] == named["gamma0"]).all() and last["adaptation"] == named["adaptation"]
    rows = sweep.sweep("mass-linear", seeds=1, n_particles=20, workers=1, quiet=True, parameters=["band"])
    assert [r["value"] for r in rows] == ["[0.0224, 0.0336]", "[0.0168, 0.0392]", "[0.0056, 0.0504]"]
    assert all(0.0 <= r["alpha_lambda_pass_rate"] <= 1.0 and r["rmse_theta"] > 0 for r in rows)
    with pytest.raises(ValueError, match="unknown sweep parameter"):
        sweep.sweep("mass-linear", seeds=1, n_particles=20, workers=1, quiet=True, parameters=["gain"])


@pytest.mark.parametrize("name", ["b-md", "mass-linear", "mass-exponential", "linear-0.05"])
def test_no_preset_setting_comes_from_the_simulated_truth(example, name):
    """Every preset gives the same settings whatever the true rate and onset (the truth the simulation uses).

    Where each value comes from: ``paper``, the numbers Jha et al. (2016) print; ``named``, the failure
    value and nominal value (rate prior), the calibrated residual noise, and the constants of
    prognosis.hypotheses / prognosis.isolation (life prior 10 to 1e5 steps, kernel discount 0.98,
    inflation 4); ``auto``, the same plus the other failure values a user declares (``OTHER_FAILURES``).
    """
    import dataclasses

    case = example.CASES[name]
    other = dataclasses.replace(case, gamma=case.gamma * 1.7, onset=case.onset + 3.0)
    for preset in ("paper", "named"):
        a, b = example.tuning(case, preset, 1e-3, 100), example.tuning(other, preset, 1e-3, 100)
        assert a.keys() == b.keys()
        for key in a:
            if isinstance(a[key], np.ndarray):
                assert np.array_equal(a[key], b[key]), key
            else:
                assert a[key] == b[key], key
    assert case.other_failures == other.other_failures
