"""Resample-move SMC over a degradation law's static parameters: no collapse on clean data.

A hypothesis says that theta follows a law from its value at the alarm: ``theta_0`` at the first
filter step, then ``theta_k = g(theta_{k-1}, gamma, dt)``.  Its unknowns are static, ``(theta_0,
gamma)``, and their posterior after k steps is

    p(theta_0, gamma | y_1..k)  ~  prior(theta_0, gamma) prod_j p(y_j | theta_j),

which this filter follows with iterated batch importance sampling (Chopin (2002)): each new residual
reweights the particles; when the effective sample size would fall below ``ess_target`` N, the
increment is split by tempering, ``p(y_k | theta_k)^phi`` with phi found so that the ESS stays at
the target (Del Moral, Doucet and Jasra (2006)), and after each split the cloud is resampled and
*moved*: a few Metropolis-Hastings steps whose target is the posterior itself, on the whole history,
with a Gaussian random walk scaled on the cloud's covariance (Roberts and Rosenthal (2001): 2.38^2 / d).
The move leaves the posterior invariant and gives back distinct particles, so a sharp likelihood
(a clean residual, the first update at the alarm) narrows the cloud without collapsing it to a few
copies, and the weights track the posterior at every step instead of lagging one prediction behind.

There is no process noise: the law is a hypothesis about theta's path, and a law the data
contradict shows in its evidence and its innovations instead of being absorbed by a random walk.
The first step updates before anything moves: its measurement is of the time the particles are
drawn for.

The prior is uniform over a box of working coordinates: theta_0, and each gamma itself or (``log``)
its logarithm with its sign, so that a rate known to within decades is log-uniform.

A residual whose noise model has a walk (:attr:`~prognosis.likelihood.ResidualNoise.walk`: the drift
of an ARR's integral of noisy signals) carries an offset that wanders; the likelihood of a step is
then that of its innovation given the past gaps (:mod:`prognosis.wander`), so that the drift is not
read as wear.

The contract is the :class:`~prognosis.particle_filter.ParticleFilter`'s: ``initialize``, ``step``
(returning :class:`~prognosis.particle_filter.StepDiagnostics`), ``estimate``, ``weights``,
``theta``, ``gamma`` and ``log_evidence``, batched over independent assets (rows).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .degradation import trajectory
from .errors import PrognosisError
from .likelihood import MIN_STEPS, ResidualNoise, information_excess
from .particle_filter import COLLAPSE_BELOW, StepDiagnostics, check_particles, check_positive, cloud_estimate
from .resampling import effective_sample_size, get_scheme, normalize_log_weights
from .seeds import check_seed

__all__ = ["ResampleMoveFilter"]

ESS_TARGET = 0.5  # share of N the ESS is kept at by tempering
MOVES = 4  # Metropolis-Hastings steps per move
MAX_STAGES = 60  # tempering stages per filter step before the rest of the increment is taken at once
CHUNK = 1024  # filter steps evaluated at once when the whole history is replayed (bounds the memory)
DISCREPANCY = ("each", "shared", None)  # whose information excess divides an asset's likelihood


@dataclass(frozen=True)
class Prior:
    """Uniform over the box ``[lo, hi]`` (A, D) of working coordinates; ``log[a, g]``: gamma_g as sign * exp(u).

    A coordinate with ``lo == hi`` is fixed: a gamma of a row whose law does not have it.
    """

    lo: np.ndarray
    hi: np.ndarray
    log: np.ndarray  # (A, G) bool
    sign: np.ndarray  # (A, G)
    width: int = 1  # the first coordinates are theta_0's: one, or one per parameter of a joint hypothesis
    #: (A,) theta's value before its change began, (A, C) each parameter's for a joint hypothesis, when the
    #: record before the first step is weighed; the last ``width`` coordinates are then the onsets: how many
    #: steps before the first each change began
    nominal: np.ndarray | None = None

    def draw(self, n: int, rng: np.random.Generator) -> np.ndarray:
        shape = (self.lo.shape[0], n, self.lo.shape[1])
        return self.lo[:, None, :] + (self.hi - self.lo)[:, None, :] * rng.random(shape)

    @property
    def free(self) -> np.ndarray:
        """(A, D): the coordinates the prior does not fix (``lo < hi``)."""
        return self.hi > self.lo

    def rows(self, index: np.ndarray) -> "Prior":
        """The prior of the rows (assets) ``index`` alone."""
        return Prior(self.lo[index], self.hi[index], self.log[index], self.sign[index], self.width,
                     None if self.nominal is None else self.nominal[index])

    def inside(self, z: np.ndarray) -> np.ndarray:
        return np.all((z >= self.lo[:, None, :]) & (z <= self.hi[:, None, :]), axis=-1)

    def theta(self, z: np.ndarray, components: int | None) -> np.ndarray:
        """theta_0 of particles ``z``: (A, N), or (A, N, C) for ``components`` C."""
        return z[..., 0] if components is None else z[..., :components]

    def before_onset(self, path: np.ndarray, z: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """theta's ``path`` (A, N, K), or (A, N, K, C) of a joint hypothesis, at ``steps`` (K,) from the first
        (negative: before it) with the onsets of particles ``z``: the nominal value before the onset;
        between it and the first step the law's path traced back, stopped at the nominal value (a wear
        does not come from beyond it).  Each parameter of a joint hypothesis has its own onset."""
        if self.nominal is None or not np.any(steps < 0):
            return path
        single = path.ndim == 3
        path = path[..., None] if single else path  # (A, N, K, C)
        nominal = self.nominal.reshape(self.nominal.shape[0], 1, 1, -1)
        # (A, N, 1, C): the side of the nominal value theta_0 lies on, and the onset
        side = np.sign(z[..., None, :self.width] - nominal)
        onset = z[..., None, -self.width:]
        traced = nominal + side * np.maximum(side * (path - nominal), 0.0)
        at = steps[None, None, :, None]
        shaped = np.where(at < 0, np.where(at >= -onset, traced, nominal), path)
        return shaped[..., 0] if single else shaped

    def gamma(self, z: np.ndarray) -> np.ndarray:
        u = z[..., self.width:self.width + self.log.shape[1]]
        log = self.log[:, None, :]
        return np.where(log, self.sign[:, None, :] * np.exp(np.where(log, u, 0.0)), u)


class ResampleMoveFilter:
    """Resample-move SMC for ``(theta_0, gamma)`` of a degradation law, batched over assets.

    Parameters
    ----------
    model : degradation model (:mod:`prognosis.degradation`)
        Only its deterministic ``step`` is used.
    observation : callable ``h(theta, points) -> y``
        As for :class:`~prognosis.particle_filter.ParticleFilter`: ``theta`` (A, N), returning (A, N)
        or (A, N, M).  With a method ``trajectory(theta, points)``, ``theta`` (A, N, K) and the
        points of K steps stacked, the history is replayed at once (else step by step).
    noise : ResidualNoise, or float / array of residual stds
    dt : float
    n_particles : int
    moves : int
        Metropolis-Hastings steps per move.
    ess_target : float
        Tempering keeps the ESS at this share of N.
    resampling : str
    discrepancy : {"each", "shared", None}
        Divide each whitened residual's log-likelihood by the information excess of its gaps
        (:func:`~prognosis.likelihood.information_excess`): each asset by its own ("each"), every
        row by that of the row with the largest evidence ("shared": rows that are hypotheses about
        one asset, whose evidence stays comparable), or not at all (None: the noise model is trusted).
        Per residual: an ARR whose gaps persist (a second derivative's lag) loses its weight, not
        the others.
    seed : int or numpy.random.SeedSequence

    Examples
    --------
    A level growing by 0.1 per step, measured with noise 0.05: after 30 steps the rate is known
    to within a few percent, with distinct particles all along.

    >>> from prognosis.degradation import LinearDegradation
    >>> rng = np.random.default_rng(1)
    >>> f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=0.05, dt=1.0,
    ...                        n_particles=400, seed=0)
    >>> f.initialize((0.0, 2.0), gamma_bounds=(0.0, 1.0), assets=1)
    >>> for k in range(30):
    ...     step = f.step(1.0 + 0.1 * k + rng.normal(0, 0.05))
    >>> estimate = f.estimate()
    >>> round(float(estimate["gamma_mean"][0, 0]), 2), bool(step.collapsed[0])
    (0.1, False)
    >>> bool(np.unique(f.gamma[0, :, 0]).size > 100)    # distinct particles, not copies of a few
    True
    """

    def __init__(self, model, observation, *, noise, dt: float, n_particles: int = 500, moves: int = MOVES,
                 ess_target: float = ESS_TARGET, resampling: str = "systematic", discrepancy: str | None = "each",
                 seed: int | np.random.SeedSequence = 0):
        self.model, self.observation = model, observation
        self.noise = noise if isinstance(noise, ResidualNoise) else ResidualNoise.independent(noise)
        self.dt, self.n = check_positive(dt, "dt"), check_particles(n_particles)
        if isinstance(moves, bool) or int(moves) != moves or moves < 1:
            raise PrognosisError(f"moves must be a whole number >= 1, got {moves!r}")
        if not 0.0 < ess_target < 1.0:
            raise PrognosisError(f"ess_target must lie in (0, 1), got {ess_target!r}")
        self.moves, self.ess_target = int(moves), float(ess_target)
        if discrepancy not in DISCREPANCY:
            raise PrognosisError(f"discrepancy must be one of {', '.join(map(repr, DISCREPANCY))}, got {discrepancy!r}")
        self.discrepancy = discrepancy
        self.resample = get_scheme(resampling)
        self.rng = np.random.default_rng(check_seed(seed))
        self.z = self.theta = self.log_weights = self.log_evidence = None
        self.lead = 0
        self.components = None
        self.acceptance = None
        #: assets (A,) reweighted but no longer moved: a caller's choice (an hypothesis left far behind)
        self.frozen = None

    # -- set-up ------------------------------------------------------------------------------
    def initialize(self, theta_bounds, gamma_bounds, assets: int = 1, log_gamma=False,
                   components: int | None = None, before: Sequence = (), nominal=None) -> None:
        """Particles from the prior: theta_0 ~ U(theta_bounds), gamma ~ U(gamma_bounds) or log-uniform.

        Bounds are scalars, (A,) or, for gamma, (A, G).  ``log_gamma`` (bool, (G,) or (A, G)): draw
        that gamma (of that asset) log-uniformly, its bounds then of one sign and nonzero.
        ``components``: C parameters per row degrading at once (a joint hypothesis), theta (A, N, C),
        its bounds (A, C); the model then moves (A, N, C) (a
        :class:`~prognosis.degradation.JointDegradation`) and the observation takes it.

        ``before``: the measurements ``(y, points)`` of the steps just before the first, weighed too,
        with ``nominal`` (A,) (or (A, C)) the value theta had before its change began.  Each particle
        then also has an onset (one per parameter), uniform over those steps: before it theta was
        nominal, after it theta followed the law traced back from theta_0, stopped at the nominal
        value.  A change seen only from the first step tells a law's curvature badly (a power law's
        exponent, an exponential's rate); its start, below the alarm thresholds, tells it, and a jump
        at the onset (a step, then a drift; a sensor's bias) is a change that starts there.  A row
        whose ``y`` is NaN before the first step does not weigh them.
        """
        g = self.model.n_gamma
        shape = (assets,) if components is None else (assets, int(components))
        lo, hi = (np.broadcast_to(np.asarray(b, float), shape) for b in theta_bounds)
        g_lo, g_hi = (_per_asset(b, assets, g) for b in gamma_bounds)
        if np.any(lo > hi) or np.any(g_lo > g_hi) or not (np.all(np.isfinite([lo, hi])) and
                                                           np.all(np.isfinite([g_lo, g_hi]))):
            raise PrognosisError(f"prior bounds must be finite with lo <= hi: theta {theta_bounds}, "
                                 f"gamma {gamma_bounds}")
        log = np.broadcast_to(np.asarray(log_gamma, bool), (assets, g))
        sign = np.sign(np.where(g_hi != 0, g_hi, g_lo))
        if np.any(log & (g_lo * g_hi <= 0)):
            raise PrognosisError("a log-uniform gamma needs bounds of one sign, both nonzero")
        u_lo = np.where(log, np.log(np.abs(np.where(log, np.where(sign > 0, g_lo, g_hi), 1.0))), g_lo)
        u_hi = np.where(log, np.log(np.abs(np.where(log, np.where(sign > 0, g_hi, g_lo), 1.0))), g_hi)
        self.components = None if components is None else int(components)
        before = list(before)
        if before and nominal is None:
            raise PrognosisError("the steps before the first are weighed with theta's nominal value")
        self.lead = len(before)  # steps of the history before the first
        width = 1 if components is None else self.components
        onset = [np.empty((assets, 0))] * 2
        if before:
            nominal = np.broadcast_to(np.asarray(nominal, float), shape).copy()
            # an onset per parameter, uniform over the steps before the first; none for a parameter the prior
            # holds at its nominal value (a joint row's missing part): its path before the first is nominal
            held = ((lo == nominal) & (hi == nominal)).reshape(assets, width)
            onset = [np.zeros((assets, width)), np.where(held, 0.0, float(self.lead))]
        self.prior = Prior(np.column_stack([lo, u_lo, onset[0]]), np.column_stack([hi, u_hi, onset[1]]), log, sign,
                           width, nominal if before else None)
        self.z = self.prior.draw(self.n, self.rng)
        self.theta = self.prior.theta(self.z, self.components).copy()
        self.log_weights = np.full((assets, self.n), -np.log(self.n))
        self.log_evidence = np.zeros(assets)
        # sum of log p(y_j | theta_j) of each particle over the history, per whitened residual (A, N, M)
        self.past = np.zeros((assets, self.n, 1))
        self.level = None  # (A, N, M): each particle's offset predicted for the next step (whitened)
        self.history = before  # (y, points) of every step, those before the first included
        self.acceptance = np.full(assets, np.nan)
        self.frozen = np.zeros(assets, bool)
        self.scale = 2.38 / np.sqrt(np.maximum(self.prior.free.sum(axis=1), 1))
        self.excess = np.ones((assets, 1))  # what each residual's likelihood is divided by (information_excess)

    @property
    def assets(self) -> int:
        return self._initialized().shape[0]

    @property
    def gamma(self) -> np.ndarray:
        """gamma of every particle (A, N, G)."""
        return self.prior.gamma(self._initialized())

    @property
    def weights(self) -> np.ndarray:
        self._initialized()
        return normalize_log_weights(self.log_weights)[0]

    def _initialized(self):
        if self.z is None:
            raise RuntimeError("the filter has no particles yet: call initialize() first (at detection time)")
        return self.z

    # -- a step --------------------------------------------------------------------------------
    def step(self, y, points=()) -> StepDiagnostics:
        """Take the measurement ``y`` (A,) or (A, M) of the next step (the first: of the alarm)."""
        self._initialized()
        y = np.asarray(y, float)
        y = y if y.ndim == 2 else np.broadcast_to(y, (self.assets,))
        if len(self.history) > self.lead:
            self.theta = self.model.step(self.theta, self.prior.gamma(self.z), self.dt)
        self.history.append((y, points))
        predicted = self._observe(self.theta, points, self.z)
        innovation = self._innovation(y, predicted)
        increment, self.level = self._log_likelihood(y, predicted, self.theta, self.level)
        first = len(self.history) == self.lead + 1
        if first and self.lead:  # the steps before the first come in with it, each particle from its onset
            self.past, increment, _, self.level = self._replay_rows(self.z, None)
        elif first:
            self.past = np.zeros(increment.shape)
        updated = np.isfinite(y).any(axis=1) if y.ndim == 2 else np.isfinite(y)
        increment = np.where(updated[:, None, None], increment, 0.0)
        if first:  # the residuals' count is known now
            self.excess = np.ones((self.assets, increment.shape[-1]))
        # the target moves from exp(sum past / excess_before) to exp(sum (past + increment) / excess_after);
        # at the first step the weights are the prior's, whatever came before it
        before, after = 1.0 / self.excess, 1.0 / self._excess_now()
        before = np.zeros_like(before) if first else before
        done = np.zeros(self.assets)  # the share phi of the way already in the weights
        ess_min = np.full(self.assets, float(self.n))
        moved = np.zeros(self.assets, bool)
        distinct = np.full(self.assets, float(self.n))
        for stage in range(MAX_STAGES + 1):
            rows = done < 1.0
            if not rows.any():
                break
            # d log target / d phi; a particle without density (a past of -inf) keeps none at any temperature
            retempered = np.where(np.isfinite(self.past), (after - before)[:, None, :] * self.past, 0.0)
            slope = np.sum(retempered + after[:, None, :] * increment, axis=-1)
            # a frozen asset is not moved, so it takes its increment at once
            share = 1.0 - done if stage == MAX_STAGES else np.where(self.frozen, 1.0 - done,
                                                                     self._next_share(slope, done))
            share = np.where(rows, share, 0.0)
            # in log-weights: a particle whose weight underflows may carry a past the new temperature raises
            log_sum = _logsumexp(self.log_weights + share[:, None] * slope) - _logsumexp(self.log_weights)
            self.log_evidence = self.log_evidence + np.where(rows, log_sum, 0.0)
            self.log_weights = self.log_weights + share[:, None] * slope
            done = np.where(rows, np.minimum(done + share, 1.0), done)
            done = np.where(np.isclose(done, 1.0, rtol=0, atol=1e-12), 1.0, done)
            weights = normalize_log_weights(self.log_weights)[0]
            ess = effective_sample_size(weights)
            ess_min = np.minimum(ess_min, ess)
            low = rows & (ess < self.ess_target * self.n * (1 + 1e-9)) & ~self.frozen
            if low.any():
                share_done = done[:, None]
                increment = self._resample_move(weights, low, increment,
                                                (1 - share_done) * before + share_done * after, share_done * after)
                moved |= low
                distinct = np.where(low, self._distinct(), distinct)
        self.past = self.past + increment
        self.excess = 1.0 / after
        collapsed = moved & (distinct < COLLAPSE_BELOW * self.n)
        return StepDiagnostics(updated, ess_min, moved, np.zeros(self.assets, bool), collapsed, innovation)

    def _excess_now(self) -> np.ndarray:
        """The information excess (A, M) each residual's likelihood is divided by from this step on (1 without
        ``discrepancy``).

        Read from the standardized gaps of the history at the particle that explains it best, the
        largest likelihood of the past (:func:`information_excess`), not at the cloud's mean: a
        posterior along a curved ridge (a power law's rate, exponent and start trade off) has its
        mean off the ridge, where the gaps show the curvature, not the noise.  Read
        every step while the history is short, then about twenty times per tenfold of history (the
        replay it takes costs as much as the history is long).
        """
        steps = len(self.history) - self.lead
        if self.discrepancy is None or steps < MIN_STEPS or (steps - MIN_STEPS) % max(1, steps // 20):
            return self.excess
        past = self.past.sum(axis=-1)
        best = np.argmax(np.where(np.isfinite(past), past, -np.inf), axis=1)
        # read where the law is put to the test, from the first step on: the steps before it, nominal
        # for the most part, fit every law and would dilute a misfit the law shows once theta moves
        gaps = self._standardized_gaps(self.z[np.arange(self.assets), best][:, None, :])
        excess = information_excess(gaps[:, self.lead:])
        if self.discrepancy == "shared":  # rows are hypotheses of one asset: the best one's excess for all
            best = np.where(self.frozen, -np.inf, self.log_evidence)
            excess = np.broadcast_to(excess[int(np.argmax(best))], excess.shape).copy()
        return excess

    def _innovation(self, y: np.ndarray, predicted: np.ndarray) -> np.ndarray:
        """``(y - E[y]) / sd[y]`` (A, M) under the predictive: the cloud's spread of ``h`` plus the noise."""
        weights = normalize_log_weights(self.log_weights)[0]
        if y.ndim == 1:
            y, predicted = y[:, None], predicted[..., None]
        mean = np.einsum("an,anm->am", weights, predicted)
        spread = np.einsum("an,anm->am", weights, np.square(predicted - mean[:, None, :]))
        noise = np.einsum("an,anm->am", weights,
                          np.diagonal(self.noise.covariance_at(self._noise_theta(self.theta)), axis1=-2, axis2=-1))
        return (y - mean) / np.sqrt(spread + noise)

    def _next_share(self, increment: np.ndarray, done: np.ndarray) -> np.ndarray:
        """The share of the increment that brings the ESS to the target (the rest of it if that stays above)."""
        rest = 1.0 - done
        target = self.ess_target * self.n

        def ess(share):
            return _ess(self.log_weights + share[:, None] * increment)

        whole = ess(rest) >= target
        if whole.all():
            return rest
        lo, hi = np.zeros_like(rest), rest.copy()
        for _ in range(40):  # bisection, all assets at once
            mid = 0.5 * (lo + hi)
            above = ess(mid) >= target
            lo, hi = np.where(above, mid, lo), np.where(above, hi, mid)
        # at least a sliver, so that every stage moves on even when one particle dominates at once
        return np.where(whole, rest, np.maximum(lo, np.minimum(rest, 1e-6 * np.maximum(rest, 1e-300))))

    # -- resample and move ---------------------------------------------------------------------
    def _resample_move(self, weights: np.ndarray, rows: np.ndarray, increment: np.ndarray,
                       on_past: np.ndarray, on_increment: np.ndarray) -> np.ndarray:
        """Resample the ``rows`` assets, then move them by MH on the tempered posterior; returns the new increment.

        The target is ``prior exp(sum_m on_past_m past_m + on_increment_m increment_m)``, exponents (A, M).
        """
        spread = _weighted_covariance(self.z, weights)  # (A, D, D): the proposal's shape, before resampling
        index = self.resample(weights, self.rng)
        index = np.where(rows[:, None], index, np.arange(self.n))
        self.z = np.take_along_axis(self.z, index[..., None], axis=1)
        self.theta = _take(self.theta, index)
        self.past = _take(self.past, index)
        self.level = _take(self.level, index)
        increment = _take(increment, index)
        self.log_weights = np.where(rows[:, None], -np.log(self.n), self.log_weights)
        width = np.maximum(np.sqrt(np.diagonal(spread, axis1=-2, axis2=-1)),
                           1e-9 * np.maximum(np.abs(self.prior.hi - self.prior.lo), 1e-300))
        # a ridge on the diagonal: a collapsed cloud still proposes along every coordinate
        proposal = spread + np.einsum("ad,de->ade", np.square(1e-3 * width), np.eye(width.shape[1]))
        # a coordinate the prior fixes (a gamma the row's law does not have) is not proposed along
        free = self.prior.free
        both = free[:, :, None] & free[:, None, :]
        proposal = np.where(both, proposal, np.eye(width.shape[1]))
        chol = _cholesky(proposal) * free[:, :, None]
        accepted = np.zeros(self.assets)
        view = self._view(np.flatnonzero(rows))
        for _ in range(self.moves):
            step = np.einsum("ade,ane->and", chol, self.rng.standard_normal(self.z.shape))
            z_new = self.z + self.scale[:, None, None] * step
            inside = self.prior.inside(z_new) & rows[:, None]
            # a proposal outside the prior is rejected; replayed inside it, so that no law overflows
            past, last, theta, level = self._replay(np.clip(z_new, self.prior.lo[:, None, :],
                                                            self.prior.hi[:, None, :]), view, increment)
            a, b = on_past[:, None, :], on_increment[:, None, :]
            log_ratio = np.sum(a * past + b * last, axis=-1) - np.sum(a * self.past + b * increment, axis=-1)
            accept = inside & (np.log(self.rng.random(log_ratio.shape)) < np.nan_to_num(log_ratio, nan=-np.inf))
            self.z = np.where(accept[..., None], z_new, self.z)
            self.theta = np.where(_along(accept, theta), theta, self.theta)
            self.past = np.where(accept[..., None], past, self.past)
            self.level = np.where(accept[..., None], level, self.level)
            increment = np.where(accept[..., None], last, increment)
            accepted += accept.mean(axis=1)
        rate = accepted / self.moves
        self.acceptance = np.where(rows, rate, self.acceptance)
        # keep the acceptance near a quarter: smaller jumps when few are accepted, larger when most are
        self.scale = np.where(rows, self.scale * np.where(rate < 0.15, 0.6, np.where(rate > 0.45, 1.5, 1.0)),
                              self.scale)
        return increment

    def _view(self, index: np.ndarray):
        """(rows, model, observation, noise, prior) of the rows ``index`` alone, or None for every row.

        A move replays the history of the rows it moves; the others (frozen hypotheses, assets whose
        cloud is healthy) need no replay.  Only when the model, the observation and the noise can
        each be cut to rows (a bank of laws, hypotheses' observations, per-row noise: a method
        ``rows``); otherwise, or when every row moves, the whole arrays are replayed.
        """
        parts = (self.model, self.observation, self.noise)
        if index.size == self.assets or not all(hasattr(part, "rows") for part in parts):
            return None
        return (index, *(part.rows(index) for part in (*parts, self.prior)))

    def _replay(self, z: np.ndarray, view=None, increment: np.ndarray | None = None):
        """Log-likelihood of particles ``z`` over the history before this step, of this step, theta now and
        the offset predicted for the next step.

        With a ``view`` (:meth:`_view`) only its rows are replayed; the others keep the current
        particles' values (``self.past``, ``increment``, ``self.theta``).
        """
        if view is None:
            return self._replay_rows(z, None)
        index = view[0]
        past, last, theta, level = self.past.copy(), increment.copy(), self.theta.copy(), self.level.copy()
        past[index], last[index], theta[index], level[index] = self._replay_rows(z[index], view)
        return past, last, theta, level

    def _replay_rows(self, z: np.ndarray, view) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        past, level = 0.0, None
        for path, rate, start, stop in self._paths(z, view):
            terms, level, _ = self._history_terms(path, rate, start, stop, level, view)  # (A, N, K, M)
            if stop == len(self.history):
                return past + terms[..., :-1, :].sum(axis=-2), terms[..., -1, :], path[:, :, -1], level
            past = past + terms.sum(axis=-2)
        raise RuntimeError("no history to replay")

    def _standardized_gaps(self, z: np.ndarray) -> np.ndarray:
        """The innovations of the whitened gaps over their sd (A, K, M), over the history of one particle
        per asset, ``z`` (A, 1, D): N(0, 1) and white if the noise and wander models hold (NaN: unmeasured)."""
        pieces, level = [], None
        for path, rate, start, stop in self._paths(z):
            _, level, standardized = self._history_terms(path, rate, start, stop, level)
            pieces.append(standardized[:, 0])
        return np.concatenate(pieces, axis=1)

    def _paths(self, z: np.ndarray, view=None):
        """theta's path (A, N, K) under particles ``z`` and its rate (or None), CHUNK steps at a time,
        with the steps ``start, stop`` of the history they cover (of the rows of ``view``)."""
        steps = len(self.history)
        for start in range(0, steps, CHUNK):
            stop = min(start + CHUNK, steps)
            yield (*self._path(z, start, stop, view), start, stop)

    def _path(self, z: np.ndarray, start: int, stop: int, view=None,
              lag: int = 0) -> tuple[np.ndarray, np.ndarray | None]:
        """theta's path (A, N, K) under particles ``z`` over the steps ``start..stop`` (of the rows of ``view``),
        lagged by ``lag`` steps, and its rate (None where no ARR sees it, as only a differentiated one does)."""
        model, observation, prior = ((self.model, self.observation, self.prior) if view is None
                                     else (view[1], view[2], view[4]))
        rates = getattr(observation, "rates", False)
        # the whole stretch at once (in closed form where the law has one), its rate from the step after each;
        # steps counted from the first, those before it (the lead) negative
        steps = np.arange(start - lag, stop - lag + rates) - self.lead
        path = prior.before_onset(trajectory(model, prior.theta(z, self.components), prior.gamma(z), steps[0],
                                             steps[-1] + 1, self.dt), z, steps)
        rate = np.diff(path, axis=2) / self.dt if rates else None
        return path[:, :, :stop - start], rate

    def _history_terms(self, path: np.ndarray, rate: np.ndarray, start: int, stop: int,
                       level: np.ndarray | None, view=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """log p(y_j | y_<j, theta_j) per whitened residual (A, N, K, M) for the steps ``start..stop`` of the
        history, the offset predicted after them (A, N, M) from ``level`` before them (None: zero), and
        the standardized innovations (A, N, K, M), NaN where not measured."""
        gaps = self._history_gaps(path, rate, start, stop, view)
        return (self.noise if view is None else view[3]).history_density(gaps, self._noise_theta(path), level)

    def _history_gaps(self, path: np.ndarray, rate: np.ndarray, start: int, stop: int, view=None) -> np.ndarray:
        """``y_j - h(theta_j)`` (A, N, K, M) for the steps ``start..stop`` of the history."""
        ys = np.stack([self.history[j][0] for j in range(start, stop)], axis=1)  # (A, K) or (A, K, M)
        observation = self.observation if view is None else view[2]
        if view is not None:
            ys = ys[view[0]]
        trajectory = getattr(observation, "trajectory", None)
        if trajectory is not None:
            predicted = trajectory(path, [self.history[j][1] for j in range(start, stop)],
                                   **({} if rate is None else {"rate": rate}))
        else:
            predicted = np.stack([self._call(path[:, :, j], self.history[start + j][1],
                                             None if rate is None else rate[:, :, j], observation)
                                  for j in range(stop - start)], axis=2)
        if ys.ndim == 2:
            ys, predicted = ys[..., None], predicted[..., None] if predicted.ndim == 3 else predicted
        return ys[:, None] - predicted

    def forecast_miss(self, z: np.ndarray, log_weights: np.ndarray, made: int, start: int,
                      excess: np.ndarray | None = None, lag: int = 1) -> np.ndarray:
        """How far the residuals' mean over the steps ``start`` to now falls from what particles ``z`` (A, N, D)
        with ``log_weights`` (A, N), the cloud after step ``made``, forecast for it: (A, M), in sd.

        The forecast of the window's mean gap is the cloud's weighted mean.  Its variance: the cloud's
        spread of that mean; the noise's over the window, times the largest information excess (the
        gaps' persistence); the walk of an integral's offset since step ``made``; and what a lag of
        theta by ``lag`` filter steps changes (the record does not time a change finer than its step,
        or than its derivative window when longer: see the RUL).  A law that fits keeps the miss within
        a few sd however far ahead; one that cannot bend as the data do (a power law through a wear
        that saturates) misses by more and more.  Unlike the one-step innovations, the cloud is not
        refitted to the data it is judged on.

        Examples
        --------
        A level growing by 0.1 a step that stops growing at step 35: the linear law's cloud after 30
        steps forecasts steps 50-60 well on the straight line, and misses them by far on the bent one.

        >>> from prognosis.degradation import LinearDegradation
        >>> def miss(bend):
        ...     f = ResampleMoveFilter(LinearDegradation(), lambda theta, points: theta, noise=0.05, dt=1.0,
        ...                            n_particles=300, seed=0)
        ...     f.initialize((0.0, 2.0), gamma_bounds=(0.0, 1.0), assets=1)
        ...     rng = np.random.default_rng(2)
        ...     for k in range(60):
        ...         f.step(1.0 + 0.1 * min(k, bend) + rng.normal(0, 0.05))
        ...         if k == 29:
        ...             cloud = f.z.copy(), f.log_weights.copy()
        ...     return abs(float(f.forecast_miss(*cloud, made=29, start=50)[0, 0]))
        >>> miss(bend=60) < 4.0, miss(bend=35) > 4.0
        (True, True)
        """
        stop = len(self.history) - self.lead
        if not 0 <= made < start < stop:
            raise PrognosisError(f"a forecast made at step {made} is judged on the steps {start} to {stop} after it")
        made, start, stop = made + self.lead, start + self.lead, stop + self.lead
        mean_gap, path = self._mean_gaps(z, start, stop)
        lagged, _ = self._mean_gaps(z, start, stop, lag=lag)
        weights = normalize_log_weights(log_weights)[0]
        with np.errstate(invalid="ignore", over="ignore"):
            finite = np.isfinite(mean_gap) & np.isfinite(lagged)
            mean_gap, lagged = np.where(finite, mean_gap, 0.0), np.where(finite, lagged, 0.0)
            w = weights[..., None] * finite
            w = w / np.maximum(w.sum(axis=1, keepdims=True), 1e-300)
            forecast = np.sum(w * mean_gap, axis=1)  # (A, M)
            spread = np.sum(w * np.square(mean_gap - forecast[:, None, :]), axis=1)
            lag = np.sum(w * np.square(lagged - mean_gap), axis=1)
            variance = np.diagonal(self.noise.covariance_at(self._noise_theta(path)), axis1=-2, axis2=-1)
            noise = np.sum(w * np.nanmean(variance, axis=2), axis=1) / (stop - start)
            noise = noise * np.max(self.excess if excess is None else excess, axis=1, keepdims=True)
            walk = 0.0 if self.noise.walk is None else self.noise.walk * ((start + stop) / 2 - made)
            return forecast / np.sqrt(spread + noise + walk + lag)

    def _mean_gaps(self, z: np.ndarray, start: int, stop: int, lag: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Each particle's mean gap ``y - h(theta)`` (A, N, M) over the steps ``start..stop``, theta's path lagged
        by ``lag`` steps, and that path (A, N, K)."""
        path, rate = self._path(z, start, stop, lag=lag)
        gaps = self._history_gaps(path, rate, start, stop)  # (A, N, K, M)
        with np.errstate(invalid="ignore"):
            return np.nanmean(gaps, axis=2), path

    # -- pieces ----------------------------------------------------------------------------------
    def _observe(self, theta: np.ndarray, points, z: np.ndarray) -> np.ndarray:
        """What particles ``theta`` with working coordinates ``z`` predict; their rate too, when it matters."""
        rate = self._rate(theta, self.prior.gamma(z)) if getattr(self.observation, "rates", False) else None
        return self._call(theta, points, rate)

    def _call(self, theta, points, rate, observation=None):
        observation = self.observation if observation is None else observation
        if rate is None:
            return np.asarray(observation(theta, points), float)
        return np.asarray(observation(theta, points, rate=rate), float)

    def _rate(self, theta: np.ndarray, gamma: np.ndarray, model=None) -> np.ndarray:
        """theta's rate under ``model``'s law (default the filter's): ``(g(theta, gamma, dt) - theta) / dt``."""
        model = self.model if model is None else model
        return (model.step(theta, gamma, self.dt) - theta) / self.dt

    def _log_likelihood(self, y: np.ndarray, predicted: np.ndarray, theta: np.ndarray,
                        level: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """log p(y | past, theta) per whitened residual (A, N, M) of this step's measurement, and the offset
        predicted for the next."""
        if y.ndim == 1:
            y, predicted = y[:, None], predicted[..., None]
        # one step: a history of length one
        terms, level, _ = self.noise.history_density(np.expand_dims(y[:, None, :] - predicted, 2),
                                                     np.expand_dims(self._noise_theta(theta), 2), level)
        return terms[:, :, 0], level

    def _noise_theta(self, theta: np.ndarray) -> np.ndarray:
        """What the noise grows with: theta, or of joint hypotheses' parameters those the noise knows (the
        first, unless it grows with each: :attr:`~prognosis.likelihood.ResidualNoise.components`)."""
        if self.components is None or self.noise.components == self.components:
            return theta
        return theta[..., 0]

    def _distinct(self) -> np.ndarray:
        """Distinct particles per asset (A,), counted on a coordinate the prior leaves free (a move changes all)."""
        coordinate = np.argmax(self.prior.free, axis=1)
        ordered = np.sort(np.take_along_axis(self.z, coordinate[:, None, None], axis=2)[..., 0], axis=1)
        return 1.0 + np.count_nonzero(np.diff(ordered, axis=1) != 0, axis=1)

    def estimate(self) -> dict:
        """Weighted mean, median and RMAD of theta (now) and each gamma, per asset; of a joint hypothesis'
        parameters, ``theta_*`` of the first and ``components`` one estimate per parameter."""
        if self.components is None:
            return cloud_estimate(self.theta, self.gamma, self.weights)
        parts = [cloud_estimate(self.theta[..., c], self.gamma, self.weights) for c in range(self.components)]
        return {**parts[0], "components": parts}


def _take(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``values`` (A, N, ...) at the particles ``index`` (A, N) of each asset."""
    return np.take_along_axis(values, index.reshape(index.shape + (1,) * (values.ndim - 2)), axis=1)


def _along(mask: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``mask`` (A, N) broadcastable against ``values`` (A, N, ...)."""
    return mask.reshape(mask.shape + (1,) * (values.ndim - mask.ndim))


def _per_asset(bound, assets: int, g: int) -> np.ndarray:
    """A bound of gamma as (A, G): a scalar, one value per gamma (G,), per asset (A,) when G = 1, or (A, G)."""
    value = np.asarray(bound, float)
    if value.ndim == 1 and value.size == assets and value.size != g:
        value = value[:, None]
    return np.broadcast_to(value, (assets, g)).astype(float)


def _weighted_covariance(z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Covariance (A, D, D) of particles ``z`` (A, N, D) under ``weights`` (A, N)."""
    mean = np.einsum("an,and->ad", weights, z)
    centred = z - mean[:, None, :]
    return np.einsum("an,and,ane->ade", weights, centred, centred)


def _cholesky(matrices: np.ndarray) -> np.ndarray:
    """Cholesky factors of covariances (A, D, D); an asset whose covariance is not positive definite
    (rounding in a near-degenerate cloud) falls back to its diagonal."""
    diagonal = np.sqrt(np.maximum(np.diagonal(matrices, axis1=-2, axis2=-1), 0.0))
    factors = np.einsum("ad,de->ade", diagonal, np.eye(matrices.shape[-1]))
    for a in range(matrices.shape[0]):
        try:
            factors[a] = np.linalg.cholesky(matrices[a])
        except np.linalg.LinAlgError:
            pass
    return factors


def _ess(log_weights: np.ndarray) -> np.ndarray:
    """Effective sample size (A,) of unnormalized log-weights (A, N)."""
    w = np.exp(log_weights - np.max(log_weights, axis=1, keepdims=True))
    return np.square(w.sum(axis=1)) / np.sum(np.square(w), axis=1)


def _logsumexp(values: np.ndarray) -> np.ndarray:
    top = np.max(values, axis=-1, keepdims=True)
    top = np.where(np.isfinite(top), top, 0.0)
    return (top + np.log(np.sum(np.exp(values - top), axis=-1, keepdims=True)))[..., 0]
