"""Resampling schemes: ranges, shapes, unbiasedness, low variance, log-weight normalization, ESS."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from prognosis.resampling import (
    SCHEMES, effective_sample_size, get_scheme, multinomial, normalize_log_weights, residual, stratified,
    systematic,
)

ALL = sorted(SCHEMES)
LOW_VARIANCE = ["systematic", "residual"]
# N w = [0.25, 0.65, 1.1, 1.35, 1.65]: no integer, so every particle has random offspring
W5 = np.array([0.05, 0.13, 0.22, 0.27, 0.33])


def offspring(indices, n):
    """Offspring counts per row, shape (rows, n)."""
    rows = indices.reshape(-1, indices.shape[-1])
    return np.array([np.bincount(r, minlength=n) for r in rows])


def test_registry_and_unknown_name():
    assert SCHEMES == {"systematic": systematic, "stratified": stratified, "residual": residual,
                       "multinomial": multinomial}
    assert all(get_scheme(name) is SCHEMES[name] for name in ALL)
    with pytest.raises(ValueError, match="multinomial, residual, stratified, systematic"):
        get_scheme("Systematic")


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("shape", [(7,), (3, 7), (2, 3, 7)])
def test_shape_range_sorted(name, shape):
    rng = np.random.default_rng(11)
    weights = rng.random(shape)
    indices = get_scheme(name)(weights, rng)
    assert indices.shape == shape
    assert np.issubdtype(indices.dtype, np.integer)
    assert indices.min() >= 0 and indices.max() < shape[-1]
    assert np.all(np.diff(indices, axis=-1) >= 0)


@pytest.mark.parametrize("name", ALL)
def test_unbiased_mean_offspring(name):
    # 4000 repetitions as one batch; rows alternate two weight vectors so that
    # mixing rows up in the vectorized code would show as a bias.
    reps, n = 4000, W5.size
    weights = np.where((np.arange(reps) % 2 == 0)[:, None], W5, W5[::-1])
    counts = offspring(get_scheme(name)(weights, np.random.default_rng(2024)), n)
    for parity, w in ((0, W5), (1, W5[::-1])):
        c = counts[parity::2]
        standard_error = c.std(axis=0, ddof=1) / np.sqrt(len(c))
        assert np.all(np.abs(c.mean(axis=0) - n * w) < 4 * standard_error + 1e-12), (name, c.mean(axis=0), n * w)


def test_multinomial_offspring_chi_square():
    # Pooled multinomial counts over 500 rows of 5 particles: Multinomial(2500, w);
    # chi-square with 4 degrees of freedom, 99.9 % quantile 18.47.
    counts = offspring(multinomial(np.tile(W5, (500, 1)), np.random.default_rng(5)), 5).sum(axis=0)
    expected = 2500 * W5
    assert np.sum((counts - expected) ** 2 / expected) < 18.47


@pytest.mark.parametrize("name", LOW_VARIANCE)
def test_low_variance_offspring_between_floor_and_ceil(name):
    rng = np.random.default_rng(3)
    weights = rng.dirichlet(np.full(50, 0.3), size=200)  # uneven weights, 200 assets
    counts = offspring(get_scheme(name)(weights, rng), 50)
    assert np.all(counts >= np.floor(50 * weights)) and np.all(counts <= np.ceil(50 * weights))
    assert np.all(counts.sum(axis=1) == 50)


def test_multinomial_is_not_low_variance():
    # guards the test above: the high-variance scheme does leave [floor, ceil]
    counts = offspring(multinomial(np.tile(W5, (200, 1)), np.random.default_rng(3)), 5)
    assert np.any((counts < np.floor(5 * W5)) | (counts > np.ceil(5 * W5)))


@settings(max_examples=60, deadline=None)
@given(weights=arrays(float, st.integers(1, 30), elements=st.floats(0, 1e3)).filter(lambda w: w.sum() > 0),
       seed=st.integers(0, 2**32 - 1))
def test_property_zero_weights_never_chosen_low_variance_bounds(weights, seed):
    n = weights.size
    p = weights / weights.sum()
    for name in ALL:
        indices = get_scheme(name)(weights, np.random.default_rng(seed))
        assert indices.shape == (n,) and np.all(np.diff(indices) >= 0)
        assert np.all(p[indices] > 0), name
        if name in LOW_VARIANCE:
            counts = np.bincount(indices, minlength=n)
            assert np.all(counts >= np.floor(n * p * (1 - 1e-12))) and np.all(counts <= np.ceil(n * p * (1 + 1e-12)))


@pytest.mark.parametrize("name", ALL)
def test_all_weight_on_one_particle(name):
    weights = np.zeros((3, 6))
    weights[[0, 1, 2], [0, 3, 5]] = [1.0, 2.5, 1e-300]  # unnormalized, one tiny
    indices = get_scheme(name)(weights, np.random.default_rng(0))
    assert indices.tolist() == [[0] * 6, [3] * 6, [5] * 6]


@pytest.mark.parametrize("name", ALL)
def test_batch_equals_row_by_row(name):
    # Each scheme draws its uniforms row-major, so a batch consumes the stream
    # exactly as successive single-asset calls do.
    weights = np.random.default_rng(1).random((4, 9))
    batch = get_scheme(name)(weights, np.random.default_rng(77))
    rng = np.random.default_rng(77)
    single = np.array([get_scheme(name)(w, rng) for w in weights])
    assert np.array_equal(batch, single)


@pytest.mark.parametrize("name", ALL)
def test_deterministic_for_a_seed(name):
    weights = np.random.default_rng(1).random((2, 100))
    first = get_scheme(name)(weights, np.random.default_rng(42))
    assert np.array_equal(first, get_scheme(name)(weights, np.random.default_rng(42)))
    assert not np.array_equal(first, get_scheme(name)(weights, np.random.default_rng(43)))


class Constant(np.random.Generator):
    """A generator whose uniforms all equal ``value``: pins the edge cases U = 0 and U -> 1."""

    def __init__(self, value):
        super().__init__(np.random.PCG64(0))
        self.value = value

    def random(self, size=None):
        return np.full(size, self.value)


def test_systematic_is_the_inverse_cdf_at_evenly_spaced_points():
    """The counting algorithm (shared with the fleet) picks particle i for every (j + U) / N in [C_{i-1}, C_i)."""
    rng = np.random.default_rng(8)
    for n in (1, 2, 7, 100, 513):
        weights = rng.random((6, n)) ** 3
        weights[1] = 1.0  # equal weights
        weights[2, n // 2:] = 0.0  # a weightless tail
        weights[2, 0] += 1e-3
        seed = int(rng.integers(1 << 30))
        u = np.random.default_rng(seed).random(6)  # systematic() draws one uniform per row, in order
        cdf = np.cumsum(weights / weights.sum(axis=1, keepdims=True), axis=1)
        expected = [np.minimum(np.searchsorted(c, (np.arange(n) + v) / n, side="right"), n - 1) for c, v in zip(cdf, u)]
        assert np.array_equal(systematic(weights, np.random.default_rng(seed)), np.array(expected))


def test_systematic_hand_case():
    # cumulative weights [0.1, 0.7, 1.0]; U = 0.5:
    # u = (0.5, 1.5, 2.5) / 3 = 0.167, 0.5, 0.833 -> particles 1, 1, 2
    assert systematic([0.1, 0.6, 0.3], Constant(0.5)).tolist() == [1, 1, 2]


@pytest.mark.parametrize("name", ALL)
@pytest.mark.parametrize("u", [0.0, float(np.nextafter(1.0, 0.0))])
def test_uniforms_at_the_edges_never_pick_zero_weight_particles(name, u):
    # u = 0 ties with the cumulative weight 0 of the leading zero-weight particles;
    # u -> 1 rounds (j + U) / N up to 1 and must not reach the trailing zero-weight particle or N.
    indices = get_scheme(name)(np.array([0.0, 0.0, 0.5, 0.5, 0.0, 0.0]), Constant(u))
    assert set(indices.tolist()) <= {2, 3}
    if name != "residual":  # residual's copies are deterministic: only its remainder uses u
        assert (2 if u == 0 else 3) in indices.tolist()


@pytest.mark.parametrize("bad, message", [
    ([0.5, np.nan], "NaN"), ([0.5, -0.1], "negative"), ([[1.0, 0.0], [0.0, 0.0]], r"row\(s\) \[1\] sum to 0"),
    ([1.0, np.inf], "infinite"), (np.zeros((2, 0)), "N >= 1"),
])
def test_invalid_weights_raise(bad, message):
    for name in ALL:
        with pytest.raises(ValueError, match=message):
            get_scheme(name)(np.array(bad), np.random.default_rng(0))


def test_normalize_very_negative_log_weights():
    log_w = -1e4 + np.log([[1.0, 2.0, 3.0, 4.0], [4.0, 4.0, 4.0, 4.0]])
    weights, log_z, degenerate = normalize_log_weights(log_w)
    assert np.allclose(weights, [[0.1, 0.2, 0.3, 0.4], [0.25] * 4], rtol=1e-9, atol=0)
    assert np.allclose(log_z, [-1e4 + np.log(10.0), -1e4 + np.log(16.0)], rtol=0, atol=1e-9)
    assert degenerate.tolist() == [False, False]
    # exp(-800) underflows relative to the maximum: weight exactly 0, no NaN
    weights, log_z, degenerate = normalize_log_weights(np.array([-1e4, -1e4 - 800.0]))
    assert weights.tolist() == [1.0, 0.0] and log_z == -1e4 and not degenerate


def test_degenerate_rows_flagged_uniform_and_finite():
    log_w = np.array([[-np.inf, -np.inf, -np.inf], [0.0, np.nan, 1.0], [-np.inf, 0.0, -np.inf], [0.0, np.inf, 0.0]])
    with np.errstate(all="raise"):
        weights, log_z, degenerate = normalize_log_weights(log_w)
    assert degenerate.tolist() == [True, True, False, True]
    assert not np.isnan(weights).any() and not np.isnan(log_z).any()
    assert np.allclose(weights[[0, 1, 3]], 1 / 3)
    assert weights[2].tolist() == [0.0, 1.0, 0.0] and log_z[2] == 0.0
    assert np.all(log_z[[0, 1, 3]] == -np.inf)
    assert np.allclose(weights.sum(axis=1), 1.0)


def test_normalize_log_weights_single_row_shapes():
    weights, log_z, degenerate = normalize_log_weights(np.full(5, -np.inf))
    assert weights.shape == (5,) and np.ndim(log_z) == 0 and np.ndim(degenerate) == 0
    assert bool(degenerate) and np.allclose(weights, 0.2)


def test_effective_sample_size():
    assert effective_sample_size(np.full(8, 1 / 8)) == pytest.approx(8.0)
    one_hot = np.zeros((2, 3, 8))
    one_hot[..., 4] = 1.0
    ess = effective_sample_size(one_hot)
    assert ess.shape == (2, 3) and np.all(ess == 1.0)
    # [0.5, 0.25, 0.25]: 1 / (0.25 + 0.0625 + 0.0625) = 2.666..., unnormalized gives the same
    assert effective_sample_size([2.0, 1.0, 1.0]) == pytest.approx(8 / 3)
    with pytest.raises(ValueError, match="negative"):
        effective_sample_size([1.0, -1.0])
