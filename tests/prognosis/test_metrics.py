"""Prognostic metrics on hand-computed cases (Jha et al. (2016), section 5; Saxena et al. 2010)."""

import warnings

import numpy as np
import pytest

from prognosis.metrics import (
    MetricWarning, alpha_lambda, convergence, cumulative_relative_accuracy, mean_relative_accuracy, mean_rmad,
    prognostic_horizon, relative_accuracy, relative_rmse, rmad,
)
from prognosis.ranking import format_ranking, rank_with_ties
from prognosis.weighted import weighted_median


# ---------------------------------------------------------------- RMSE (eq. 40)

def test_relative_rmse_hand_case():
    # (3 - 2)/2 = 0.5, (3 - 4)/4 = -0.25, (1 - 1)/1 = 0: sqrt((0.25 + 0.0625 + 0) / 3) = sqrt(0.104166...)
    assert relative_rmse([3.0, 3.0, 1.0], [2.0, 4.0, 1.0]) == pytest.approx(np.sqrt(0.3125 / 3), rel=1e-15)


def test_relative_rmse_vectorized_over_assets_and_axis():
    estimates = np.array([[3.0, 3.0, 1.0], [1.1, 0.9, 1.0]])
    truth = np.array([[2.0, 4.0, 1.0], [1.0, 1.0, 1.0]])
    # asset 2: errors 0.1, -0.1, 0 -> sqrt(0.02 / 3)
    expected = [np.sqrt(0.3125 / 3), np.sqrt(0.02 / 3)]
    assert np.allclose(relative_rmse(estimates, truth), expected, rtol=1e-12)
    assert np.allclose(relative_rmse(estimates.T, truth.T, axis=0), expected, rtol=1e-12)
    # scalar truth broadcasts: constant true parameter
    assert relative_rmse([1.1, 0.9, 1.0], 1.0) == pytest.approx(np.sqrt(0.02 / 3))


# ------------------------------------------------------------ RMAD (eqs. 35, 41)

def test_rmad_unweighted_hand_case():
    # median 3; |x - 3| = 2 1 0 1 7, median 1; RMAD = 1/3
    assert rmad([1.0, 2.0, 3.0, 4.0, 10.0]) == pytest.approx(1 / 3, rel=1e-15)
    # even count: median (2 + 3)/2 = 2.5; |x - 2.5| = 1.5 0.5 0.5 1.5, median 1; RMAD = 0.4
    assert rmad([1.0, 2.0, 3.0, 4.0]) == pytest.approx(0.4, rel=1e-15)


def test_rmad_weighted_hand_case():
    # x = 1 2 3 4 10, w = 1 1 1 1 4 (total 8, half 4); cumulative 1 2 3 4 8:
    # lower median 4 (C = 4 >= 4), upper median 10 (first C > 4): median 7.
    # |x - 7| = 6 5 4 3 3 with the same weights; sorted 3(w 1) 3(w 4) 4 5 6, cumulative 1 5 6 7 8:
    # lower = upper = 3.  RMAD = 3/7
    x, w = [1.0, 2.0, 3.0, 4.0, 10.0], [1, 1, 1, 1, 4]
    assert weighted_median(x, w) == 7.0
    assert rmad(x, w) == pytest.approx(3 / 7, rel=1e-15)


def test_weighted_median_matches_numpy_for_uniform_weights():
    rng = np.random.default_rng(0)
    for n in (2, 3, 6, 10, 49, 50, 1000):
        x = rng.normal(size=(3, n))
        w = np.full(n, 1 / n)  # cumulative sums of 1/n are not exactly 0.5 at n/2
        assert np.allclose(weighted_median(x, w), np.median(x, axis=-1), rtol=0, atol=0)
        assert np.allclose(rmad(x, w), rmad(x), rtol=1e-12, atol=0)


def test_weighted_median_zero_weight_and_nan():
    # zero-weight outlier ignored: median of 1 2 3 is 2; deviations 1 0 1 -> 1; RMAD 1/2
    assert rmad([1.0, 2.0, 3.0, 1000.0], [1, 1, 1, 0]) == pytest.approx(0.5)
    # [0.5, 0, 0.5] on 1 2 3: lower 1, upper 3 -> midpoint 2, never the zero-weight 2's neighbours alone
    assert weighted_median([3.0, 2.0, 1.0], [0.5, 0.0, 0.5]) == 2.0
    assert np.isnan(weighted_median([1.0, np.nan, 3.0], [1, 1, 1]))
    assert np.isnan(rmad([1.0, np.nan, 3.0]))
    with pytest.raises(ValueError, match="negative"):
        rmad([1.0, 2.0], [1.0, -1.0])
    with pytest.raises(ValueError, match="sum to 0"):
        rmad([1.0, 2.0], [0.0, 0.0])


def test_rmad_vectorized_over_assets_and_axis():
    particles = np.array([[1.0, 2.0, 3.0, 4.0, 10.0], [10.0, 20.0, 30.0, 40.0, 100.0], [5.0, 5.0, 5.0, 5.0, 5.0]])
    expected = [1 / 3, 1 / 3, 0.0]  # RMAD is scale-free; a point mass has no spread
    assert np.allclose(rmad(particles), expected)
    assert np.allclose(rmad(particles.T, axis=0), expected)
    weights = np.array([1, 1, 1, 1, 4])  # broadcast to every asset
    assert np.allclose(rmad(particles, weights), [3 / 7, 3 / 7, 0.0])
    assert np.allclose(rmad(particles.T, weights[:, None], axis=0), [3 / 7, 3 / 7, 0.0])


def test_mean_rmad_ignores_nan():
    assert mean_rmad([0.1, 0.3, np.nan]) == pytest.approx(0.2)
    assert np.allclose(mean_rmad([[0.1, 0.3], [0.2, np.nan]]), [0.2, 0.2])
    assert np.isnan(mean_rmad([np.nan, np.nan]))


# ------------------------------------------------------------- RA (eqs. 42-43)

def test_relative_accuracy_hand_case():
    # 1 - |10 - 8|/10 = 0.8; 1 - |5 - 6|/5 = 0.8; 1 - |4 - 10|/4 = -0.5
    ra = relative_accuracy([10.0, 5.0, 4.0], [8.0, 6.0, 10.0])
    assert np.allclose(ra, [0.8, 0.8, -0.5], rtol=1e-15)
    assert mean_relative_accuracy(ra) == pytest.approx((0.8 + 0.8 - 0.5) / 3)


def test_relative_accuracy_at_end_of_life_is_nan_with_warning():
    with pytest.warns(MetricWarning, match="1 prediction point"):
        ra = relative_accuracy([10.0, 0.0], [9.0, 1.0])
    assert ra[0] == pytest.approx(0.9) and np.isnan(ra[1])
    assert mean_relative_accuracy(ra) == pytest.approx(0.9)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        relative_accuracy([10.0, 5.0], [9.0, 5.0])  # no warning when RUL* > 0


def test_relative_accuracy_vectorized_over_assets():
    rul_true = np.array([[30.0, 20.0, 10.0], [15.0, 10.0, 5.0]])
    mean = np.array([[27.0, 21.0, 10.0], [15.0, 12.0, 4.0]])
    # asset 1: 0.9, 0.95, 1; asset 2: 1, 0.8, 0.8
    ra = relative_accuracy(rul_true, mean)
    assert np.allclose(ra, [[0.9, 0.95, 1.0], [1.0, 0.8, 0.8]])
    assert np.allclose(mean_relative_accuracy(ra), [2.85 / 3, 2.6 / 3])


# ------------------------------------------------------------ alpha-lambda (5.3)

def test_alpha_lambda_hand_case_with_censored_particles():
    # RUL* = 8, alpha = 0.5: cone [4, 12] (exact in binary). Particles:
    # 3 (out), 4 (in, edge), 8 (in), 12 (in, edge), 13 (out), inf (censored), nan (censored), 6 (in)
    samples = [3.0, 4.0, 8.0, 12.0, 13.0, np.inf, np.nan, 6.0]
    mass, passed = alpha_lambda(samples, None, 8.0, alpha=0.5, beta=0.5)
    assert mass == 0.5 and passed  # 4 of 8: the censored particles stay in the denominator
    mass, passed = alpha_lambda(samples, None, 8.0, alpha=0.5, beta=0.51)
    assert not passed
    # weights 1..8 (total 36): inside 2 + 3 + 4 + 8 = 17
    weights = np.arange(1.0, 9.0)
    mass, _ = alpha_lambda(samples, weights, 8.0, alpha=0.5, beta=0.5)
    assert mass == pytest.approx(17 / 36)


def test_alpha_lambda_vectorized_over_assets_and_points():
    rng = np.random.default_rng(0)
    rul_true = np.array([[40.0, 30.0, 20.0], [20.0, 15.0, 10.0]])  # (assets, points)
    samples = rul_true[..., None] * rng.uniform(0.7, 1.3, size=(2, 3, 1000))
    mass, passed = alpha_lambda(samples, None, rul_true, alpha=0.2, beta=0.5)
    assert mass.shape == passed.shape == (2, 3)
    # uniform on [0.7, 1.3] RUL*: mass inside [0.8, 1.2] RUL* is 2/3 at every point
    assert np.allclose(mass, 2 / 3, atol=0.05) and passed.all()
    loop = [[alpha_lambda(samples[a, p], None, rul_true[a, p], 0.2, 0.5)[0] for p in range(3)] for a in range(2)]
    assert np.array_equal(mass, loop)


def test_alpha_lambda_rejects_bad_parameters():
    with pytest.raises(ValueError, match="alpha"):
        alpha_lambda([1.0], None, 1.0, alpha=-0.1, beta=0.5)
    with pytest.raises(ValueError, match="beta"):
        alpha_lambda([1.0], None, 1.0, alpha=0.1, beta=1.5)
    with pytest.raises(ValueError, match="NaN"):
        alpha_lambda([1.0, 2.0], [1.0, np.nan], 1.0, alpha=0.1, beta=0.5)


# ----------------------------------------------------------- prognostic horizon

def test_prognostic_horizon_hand_case():
    times = [10.0, 20.0, 30.0, 40.0]
    # passes at 10, fails at 20, passes from 30 on: PH = 50 - 30 = 20
    assert prognostic_horizon(times, [True, False, True, True], eol=50.0) == 20.0
    assert prognostic_horizon(times, [True, True, True, True], eol=50.0) == 40.0


def test_prognostic_horizon_never_reached():
    assert np.isnan(prognostic_horizon([10.0, 20.0, 30.0], [True, True, False], eol=50.0))
    assert np.isnan(prognostic_horizon([10.0, 20.0, 30.0], [False, False, False], eol=50.0))


def test_prognostic_horizon_vectorized_over_assets():
    passed = np.array([[False, True, True, True], [True, True, False, True], [True, False, True, False]])
    ph = prognostic_horizon([10.0, 20.0, 30.0, 40.0], passed, eol=np.array([50.0, 60.0, 70.0]))
    # asset 1: from 20 -> 50 - 20; asset 2: from 40 -> 60 - 40; asset 3: last fails -> NaN
    assert ph[:2].tolist() == [30.0, 20.0] and np.isnan(ph[2])


def test_prognostic_horizon_from_alpha_lambda():
    times = np.array([0.0, 10.0, 20.0, 30.0])
    eol = 40.0
    rul_true = eol - times
    predicted = np.array([20.0, 28.0, 19.0, 10.5])  # relative errors 50 %, 6.7 %, 5 %, 5 %
    samples = predicted[:, None] + np.linspace(-0.5, 0.5, 11)
    _, passed = alpha_lambda(samples, None, rul_true, alpha=0.2, beta=0.5)
    assert passed.tolist() == [False, True, True, True]
    assert prognostic_horizon(times, passed, eol) == 30.0


# ------------------------------------------------------- cumulative relative accuracy

def test_cumulative_relative_accuracy_hand_case():
    # (1*0.5 + 2*0.9 + 3*1.0) / (1 + 2 + 3) = 5.3 / 6
    assert cumulative_relative_accuracy([0.5, 0.9, 1.0], [1, 2, 3]) == pytest.approx(5.3 / 6, rel=1e-15)
    # uniform weights: mean RA, eq. (43)
    assert cumulative_relative_accuracy([0.5, 0.9, 1.0]) == pytest.approx(0.8)


def test_cumulative_relative_accuracy_drops_nan_points_and_vectorizes():
    # NaN at the third point is dropped with its weight: (1*0.5 + 2*0.9) / 3
    assert cumulative_relative_accuracy([0.5, 0.9, np.nan], [1, 2, 3]) == pytest.approx(2.3 / 3)
    ra = np.array([[0.5, 0.9, 1.0], [1.0, 1.0, 0.7]])
    assert np.allclose(cumulative_relative_accuracy(ra, [1, 2, 3]), [5.3 / 6, 5.1 / 6])
    assert np.allclose(cumulative_relative_accuracy(ra.T, [1, 2, 3], axis=0), [5.3 / 6, 5.1 / 6])


# ----------------------------------------------------------------- convergence

def test_convergence_hand_case():
    # M = 2 on [0, 1), 1 on [1, 2) (the last value 5 does not enter). Rectangles:
    # area 2 centred (0.5, 1), area 1 centred (1.5, 0.5): centroid ((1 + 1.5)/3, (2 + 0.5)/3) = (5/6, 5/6).
    # Formulas: x_c = 0.5 (1*2 + 3*1) / 3, y_c = 0.5 (1*4 + 1*1) / 3.  C = sqrt(2) 5/6
    assert convergence([0.0, 1.0, 2.0], [2.0, 1.0, 5.0]) == pytest.approx(np.sqrt(2) * 5 / 6, rel=1e-15)
    # t_start = -1: C = sqrt((5/6 + 1)^2 + (5/6)^2)
    assert convergence([0.0, 1.0, 2.0], [2.0, 1.0, 5.0], t_start=-1.0) == pytest.approx(
        np.hypot(11 / 6, 5 / 6), rel=1e-15)
    # default t_start is the first time: shifting the times leaves C unchanged
    assert convergence([10.0, 11.0, 12.0], [2.0, 1.0, 5.0]) == pytest.approx(np.sqrt(2) * 5 / 6, rel=1e-12)


def test_convergence_faster_is_smaller_and_vectorized():
    times = np.linspace(0.0, 10.0, 11)
    fast, slow = np.exp(-times), np.exp(-0.2 * times)
    c = convergence(times, np.stack([fast, slow]))
    assert c.shape == (2,) and c[0] < c[1]
    assert c[0] == pytest.approx(convergence(times, fast)) and c[1] == pytest.approx(convergence(times, slow))


def test_convergence_degenerate_inputs():
    assert np.isnan(convergence([0.0, 1.0, 2.0], [0.0, 0.0, 3.0]))  # zero area: centroid undefined
    with pytest.raises(ValueError, match="at least 2"):
        convergence([0.0], [1.0])
    with pytest.raises(ValueError, match="increasing"):
        convergence([0.0, 2.0, 1.0], [1.0, 1.0, 1.0])


# ------------------------------------------------------------ ranking with ties

def _three_tank_like():
    """Per-seed MAEs shaped like examples/three_tank.py's: three strong-tracking filters 1e-9 and 2e-6 apart in
    every seed, a PF clearly between, three plain filters 2e-7 apart."""
    rng = np.random.default_rng(3)
    strong = 0.0284 + 0.003 * rng.standard_normal(20)
    plain = 0.1478 + 0.0008 * rng.standard_normal(20)
    return {"SCKF": plain, "STUKF": strong + 1.6e-9, "STSCKF": strong, "EKF": plain + 1.7e-7,
            "PF": 0.0747 + 0.0195 * rng.standard_normal(20), "UKF": plain - 1e-8, "STEKF": strong + 2.1e-6}


def test_rank_with_ties_prints_differences_of_1e_9_as_ties():
    scores = _three_tank_like()
    groups = rank_with_ties(scores)
    assert groups == [["STSCKF", "STUKF", "STEKF"], ["PF"], ["UKF", "SCKF", "EKF"]]
    assert format_ranking(groups) == "STSCKF = STUKF = STEKF < PF < UKF = SCKF = EKF"
    # the old ranking, by the mean alone, claimed an order from differences the runs show in every seed
    assert " < ".join(sorted(scores, key=lambda n: scores[n].mean())).startswith("STSCKF < STUKF < STEKF")
    # with no resolution left, those consistent differences are resolved by the paired t-interval
    assert rank_with_ties(scores, rtol=0.0)[0] == ["STSCKF"]


def test_rank_with_ties_needs_the_runs_to_resolve_a_difference():
    a = np.array([1.0, 2.0, 3.0, 4.0])
    noisy = a + np.array([0.3, -0.2, 0.25, -0.15])  # 5 % apart in the mean, but the sign changes between runs
    assert rank_with_ties({"A": a, "B": noisy}) == [["A", "B"]]
    assert rank_with_ties({"B": a + 0.05, "A": a}) == [["A"], ["B"]]  # 2 % apart in every run
    # a single run: only the resolution applies
    assert rank_with_ties({"A": 1.0, "B": 1.0005}) == [["A", "B"]]
    assert rank_with_ties({"A": 1.0, "B": 1.002}) == [["A"], ["B"]]
    assert rank_with_ties({"B": 1.0, "A": 1.0}) == [["B", "A"]]  # equal: tied, in the given order


def test_rank_with_ties_chains_ties_between_neighbours():
    # A-B and B-C are each within 0.1 %, A-C is not: "<" never separates neighbours that are not told apart
    groups = rank_with_ties({"C": 1.0016, "A": 1.0, "B": 1.0008})
    assert groups == [["A", "B", "C"]] and format_ranking(groups) == "A = B = C"


def test_rank_with_ties_rejects_what_it_cannot_rank():
    with pytest.raises(ValueError, match="'PF'.*finite"):
        rank_with_ties({"EKF": [0.1, 0.2], "PF": [0.1, np.nan]})
    with pytest.raises(ValueError, match="'B'.*3 runs.*2 for 'A'"):
        rank_with_ties({"A": [0.1, 0.2], "B": [0.1, 0.2, 0.3]})
    with pytest.raises(ValueError, match="no methods"):
        rank_with_ties({})
    with pytest.raises(ValueError, match="confidence"):
        rank_with_ties({"A": [1.0]}, confidence=1.0)
    with pytest.raises(ValueError, match="rtol"):
        rank_with_ties({"A": [1.0]}, rtol=-1e-3)


def test_scores_against_truth_count_what_a_loop_counts():
    """Coverage, accuracy and the share within alpha recomputed prediction by prediction, with withheld
    predictions (NaN) and predictions after the end of life left out."""
    from prognosis import scores_against_truth

    rng = np.random.default_rng(7)
    k = 40
    t = np.linspace(0.0, 12.0, k)
    eol = 10.0
    centre = (eol - t) * rng.uniform(0.7, 1.3, k)
    spread = rng.uniform(0.05, 1.5, k)
    q = np.column_stack([centre - 2 * spread, centre - spread, centre, centre + spread, centre + 2 * spread])
    q[3] = np.nan                      # withheld
    q[5, 4] = np.inf                   # the 95 % beyond the horizon
    mean = centre + 0.1
    s = scores_against_truth(t, q, mean, eol, alpha=0.2)
    kept = [j for j in range(k) if eol - t[j] > 0 and not np.isnan(q[j, 2])]
    true = [eol - t[j] for j in kept]
    assert s["predictions"] == len(kept) and s["true_rul"] == true
    assert s["coverage_90"] == sum(q[j, 0] <= eol - t[j] <= q[j, 4] for j in kept) / len(kept)
    assert s["coverage_50"] == sum(q[j, 1] <= eol - t[j] <= q[j, 3] for j in kept) / len(kept)
    assert s["within_alpha_share"] == sum(abs(q[j, 2] - (eol - t[j])) <= 0.2 * (eol - t[j]) for j in kept) / len(kept)
    ra = [1 - abs((eol - t[j]) - mean[j]) / (eol - t[j]) for j in kept]
    assert s["mean_relative_accuracy"] == pytest.approx(np.mean(ra))
    assert s["worst_relative_accuracy"] == pytest.approx(min(ra))
