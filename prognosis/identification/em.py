"""Identification of a linear Gaussian model by expectation-maximization (Gibson and Ninness 2005).

One iteration (:func:`em_step`) smooths the window with the current model and maximizes the expected
complete-data log-likelihood in closed form (Gasperin et al. (2011), eqs. 14-23); :func:`fit_em`
iterates it from :func:`initial_model` until the log-likelihood stops increasing.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .. import _linalg as linalg
from .data import check_data
from .linear_gaussian import IdentificationWarning, LinearGaussianModel, check_model_data
from .smoother import SmootherResult, filter_arrays, smooth_arrays
from ..errors import PrognosisError

__all__ = [
    "EIGENVALUE_FLOOR", "EIGENVALUE_FLOOR_ABSOLUTE", "EMResult", "em_arrays_step", "em_step", "fit_em",
    "initial_model",
]


def em_step(model: LinearGaussianModel, y: ArrayLike, u: ArrayLike | None = None, *, cross_covariance: bool = True,
            estimate_initial: bool = True) -> tuple[LinearGaussianModel, float]:
    """One EM iteration (Gasperin et al. (2011), eqs. 14-23): returns ``(new_model, log p(Y | model))``.

    E-step: :func:`kalman_smoother` gives ``x_t = E[x_t | Y]``, ``P_t = Cov(x_t | Y)``,
    ``M_t = Cov(x_{t+1}, x_t | Y)``, hence ``E[x_t x_t^T] = P_t + x_t x_t^T`` and
    ``E[x_{t+1} x_t^T] = M_t + x_{t+1} x_t^T``.

    M-step.  Eqs. (19)-(23) maximize ``sum_t E log N([x_{t+1}; y_t]; Gamma [x_t; u_t], Pi)`` with
    ``Gamma = [[A, B], [C, D]] = Psi Sigma^-1`` and ``Pi = [[Q, S], [S^T, R]] = Phi - Psi Sigma^-1 Psi^T``.
    ``x_{t+1}`` exists for ``t = 1..T-1`` but ``y_t`` for ``t = 1..T``, so the complete-data likelihood
    (eq. 17) has ``T - 1`` joint terms and one more output term ``N(y_T; C x_T + D u_T, R)``.  We
    maximize it exactly by factorizing each joint term into ``p(y_t | x_t)`` and
    ``p(x_{t+1} | x_t, y_t)``, whose parameters ``(C, D, R)`` and ``(F, K, Q~)`` vary independently:

    1. output regression over the observed ``t = 1..T`` (``xi_t = [x_t; u_t]``)::

           [C, D] = Psi_y Sigma_y^-1,   R = Phi_y - Psi_y Sigma_y^-1 Psi_y^T,
           Phi_y = avg y_t y_t^T,  Psi_y = avg E[y_t xi_t^T],  Sigma_y = avg E[xi_t xi_t^T];

    2. state regression over ``t = 1..T-1`` on ``zeta_t = [x_t; u_t; y_t]``::

           [F_x, F_u, K] = Psi_x Sigma_x^-1,   Q~ = Phi_x - Psi_x Sigma_x^-1 Psi_x^T,
           Phi_x = avg E[x_{t+1} x_{t+1}^T],  Psi_x = avg E[x_{t+1} zeta_t^T],  Sigma_x = avg E[zeta_t zeta_t^T];

    3. back to the model: ``S = K R``, ``[A, B] = [F_x, F_u] + K [C, D]``, ``Q = Q~ + K R K^T``.

    Over the same pairs ``t = 1..T-1`` for both regressions this is exactly eqs. (19)-(20) (the Gaussian
    regression of ``[x_{t+1}; y_t]`` on ``xi_t`` factorizes this way); using the extra ``y_T`` is the
    exact maximizer of eq. (17) as written.  With ``cross_covariance=False``, ``S = 0`` is imposed: the
    state regression drops ``y_t`` and ``Q = Q~`` (still an exact M-step for that model).  With
    ``estimate_initial``, ``mu1 = x_{1|T}`` and ``P1 = P_{1|T}`` (exact); otherwise they are kept.

    ``Q~`` (``Q`` when ``S = 0``), ``R`` and ``P1`` are symmetrized and their eigenvalues floored at
    ``EIGENVALUE_FLOOR`` times the largest; an :class:`IdentificationWarning` says when a floor was hit.
    A singular ``Sigma`` (inputs that are not persistently exciting) falls back to the minimum-norm
    least-squares solution, which is still a maximizer.

    Missing outputs (NaN rows) are supported with ``cross_covariance=False`` only: the output regression
    then runs over the observed rows; with ``S`` free the M-step of an incomplete record has no closed
    form, and a ``PrognosisError`` says so.

    Example
    -------
    >>> truth = LinearGaussianModel(A=[[0.7]], B=None, C=[[1.0]], D=None, Q=[[1.0]], R=[[0.5]])
    >>> _, y = truth.simulate(steps=300, rng=2)
    >>> start = LinearGaussianModel(A=[[0.2]], B=None, C=[[1.0]], D=None, Q=[[0.3]], R=[[0.3]])
    >>> from prognosis.identification import log_likelihood
    >>> new, before = em_step(start, y)
    >>> bool(log_likelihood(new, y) > before)
    True
    """
    y, u = check_model_data(model, y, u)
    if y.shape[0] < 2:
        raise PrognosisError(f"y: EM needs at least 2 samples, got {y.shape[0]}")
    new, smoothed = em_arrays_step(model, y, u, cross_covariance, estimate_initial)
    return new, smoothed.log_likelihood


def em_arrays_step(model: LinearGaussianModel, y: np.ndarray, u: np.ndarray, cross_covariance: bool,
                   estimate_initial: bool
        ) -> tuple[LinearGaussianModel, SmootherResult]:
    """One EM iteration on checked arrays: smooth with ``model``, then the M-step; returns (new model, smoothing).

    The inner step of :func:`em_step`, :func:`fit_em` and :class:`~prognosis.identification.OnlineEM`,
    which check ``y`` and ``u`` once (:func:`~prognosis.identification.linear_gaussian.check_model_data`).
    """
    observed = ~np.isnan(y).any(axis=1)
    if cross_covariance and not observed.all():
        raise PrognosisError("y has missing rows (NaN): EM with a free cross-covariance S needs a complete record; "
                             "use cross_covariance=False")
    if not observed.any():
        raise PrognosisError("y: every row is missing (NaN)")
    res = smooth_arrays(model, y, u)
    new = _m_step(model, res, y, u, cross_covariance, estimate_initial)
    return new, res


def _m_step(model: LinearGaussianModel, res: SmootherResult, y: np.ndarray, u: np.ndarray,
            cross_covariance: bool, estimate_initial: bool) -> LinearGaussianModel:
    n, r = model.n_states, u.shape[1]
    xs, ps, obs = res.smoothed_means, res.smoothed_covariances, res.observed
    floored = []

    # 1. output regression, observed t = 1..T: y_t on xi_t = [x_t; u_t]
    xo, uo, yo = xs[obs], u[obs], y[obs]
    count = xo.shape[0]
    sigma_y = np.block([[ps[obs].sum(axis=0) + xo.T @ xo, xo.T @ uo], [uo.T @ xo, uo.T @ uo]]) / count
    psi_y = np.hstack([yo.T @ xo, yo.T @ uo]) / count
    phi_y = yo.T @ yo / count
    gamma_y = linalg.solve_psd(sigma_y, psi_y.T).T
    c, d = gamma_y[:, :n], gamma_y[:, n:]
    rr = _floor_psd(phi_y - psi_y @ gamma_y.T, "R", floored)

    # 2. state regression, t = 1..T-1: x_{t+1} on zeta_t = [x_t; u_t] (+ y_t with S free)
    x0, x1, u0 = xs[:-1], xs[1:], u[:-1]
    pairs = x0.shape[0]
    blocks = [[ps[:-1].sum(axis=0) + x0.T @ x0, x0.T @ u0], [u0.T @ x0, u0.T @ u0]]
    psi_x = [res.lag_one_covariances.sum(axis=0) + x1.T @ x0, x1.T @ u0]
    if cross_covariance:
        y0 = y[:-1]
        blocks = [blocks[0] + [x0.T @ y0], blocks[1] + [u0.T @ y0], [y0.T @ x0, y0.T @ u0, y0.T @ y0]]
        psi_x.append(x1.T @ y0)
    sigma_x = np.block(blocks) / pairs
    psi_x = np.hstack(psi_x) / pairs
    phi_x = (ps[1:].sum(axis=0) + x1.T @ x1) / pairs
    gamma_x = linalg.solve_psd(sigma_x, psi_x.T).T
    residual = phi_x - psi_x @ gamma_x.T
    if cross_covariance:
        gain = gamma_x[:, n + r:]  # K = S R^-1
        q_cond = _floor_psd(residual, "Q - S R^-1 S^T", floored)
        a = gamma_x[:, :n] + gain @ c
        b = gamma_x[:, n:n + r] + gain @ d
        s = gain @ rr
        q = linalg.symmetric(q_cond + gain @ rr @ gain.T)
    else:
        a, b, s = gamma_x[:, :n], gamma_x[:, n:], None
        q = _floor_psd(residual, "Q", floored)

    if estimate_initial:
        mu1, p1 = xs[0], _floor_psd(ps[0], "P1", floored)
    else:
        mu1, p1 = model.mu1, model.P1
    if floored:
        warnings.warn(f"EM M-step floored the eigenvalues of {', '.join(floored)} at {EIGENVALUE_FLOOR:g} times "
                      f"the largest: the identified model is close to degenerate", IdentificationWarning,
                      stacklevel=4)
    return LinearGaussianModel(A=a, B=b, C=c, D=d, Q=q, R=rr, S=s, mu1=mu1, P1=p1)


@dataclass(frozen=True, eq=False)
class EMResult:
    """Output of :func:`fit_em`.

    Attributes
    ----------
    model : LinearGaussianModel
        The model after the last EM step.
    log_likelihood : ndarray (iterations + 1,)
        ``log p(Y | theta_k)`` of the start (``k = 0``) and after each EM step; the last entry is the
        returned model's.  EM never decreases it (up to round-off).
    iterations : int
        Number of EM steps taken.
    converged : bool
        Whether the relative change of the log-likelihood fell below ``tol`` before ``max_iter``.

    Example
    -------
    >>> y = np.random.default_rng(0).standard_normal(50)
    >>> fit = fit_em(y, None, 1, max_iter=5, tol=0.0)
    >>> fit.iterations, fit.converged, fit.log_likelihood.shape
    (5, False, (6,))
    """

    model: LinearGaussianModel
    log_likelihood: np.ndarray
    iterations: int
    converged: bool


def fit_em(y: ArrayLike, u: ArrayLike | None, n_states: int, *, initial: LinearGaussianModel | None = None,
           max_iter: int = 200, tol: float = 1e-8, cross_covariance: bool = True, estimate_initial: bool = True,
           seed: int | None = None) -> EMResult:
    """Maximum-likelihood ``A, B, C, D, Q, R`` (and ``S``, ``mu1``, ``P1``) by EM (Gasperin et al. (2011), section 3.3).

    Iterates :func:`em_step` until ``(L_k - L_{k-1}) <= tol |L_{k-1}|`` (relative change of the
    log-likelihood ``L``) or ``max_iter`` steps.

    Start.  The paper sets every entry of every matrix to 1 and argues the likelihood is unimodal.  It is
    not (any change of state basis gives the same likelihood, and there are genuine local maxima), and
    the all-ones start is a trap: with identical rows and columns the states are exchangeable, EM keeps
    that symmetry at every step, and the model stays of order 1 for ever.  The default start is
    deterministic and breaks the symmetry (``initial_model``):

    * ``D`` = least-squares regression of ``y`` on ``u`` (zero without inputs), ``e = y - D u``;
    * ``A = diag(linspace(0.9, 0.5, n))`` (distinct stable modes), ``B = 0``, ``C`` = ones (m, n);
    * ``R = Cov(e)``, ``Q = 0.1 tr(R) / m I``, ``mu1 = 0``, ``P1 = tr(R) / m I``.

    With ``seed``, ``A``'s off-diagonal entries and ``C`` get small random perturbations (N(0, 0.1^2)
    relative) for restarts.

    Parameters
    ----------
    y : array (T,) or (T, m), rows with NaN missing (only with ``cross_covariance=False``)
    u : array (T, r), or None without inputs
    n_states : int
    initial : LinearGaussianModel, optional
        Start model (``n_states`` must match); overrides the default start.
    max_iter, tol : stopping rule (``max_iter`` EM steps at most).
    cross_covariance : bool
        Estimate ``S`` (True) or impose ``S = 0`` (the paper's eq. 24 lists ``A, B, C, D, Q, R`` only).
    estimate_initial : bool
        Estimate ``mu1`` and ``P1`` (True) or keep the start's.

    Example
    -------
    >>> truth = LinearGaussianModel(A=[[0.9, 0.2], [0.0, 0.5]], B=[[1.0], [0.5]], C=[[1.0, 0.0]], D=[[0.0]],
    ...                             Q=0.01 * np.eye(2), R=[[0.01]])
    >>> u = np.random.default_rng(0).standard_normal((500, 1))
    >>> _, y = truth.simulate(u, rng=0)
    >>> fit = fit_em(y, u, 2, cross_covariance=False, max_iter=30)
    >>> bool(np.allclose(np.sort(fit.model.eigenvalues.real), [0.5, 0.9], atol=0.1))
    True
    >>> fit.log_likelihood.shape == (fit.iterations + 1,)
    True
    """
    if isinstance(n_states, bool) or not isinstance(n_states, (int, np.integer)) or n_states < 1:
        raise PrognosisError(f"n_states must be a positive integer, got {n_states!r}")
    if max_iter < 0:
        raise PrognosisError(f"max_iter must be >= 0, got {max_iter}")
    if not tol >= 0.0:
        raise PrognosisError(f"tol must be >= 0, got {tol}")
    y_arr, u_arr = check_data(y, u)
    model = initial_model(y_arr, u_arr, n_states, seed=seed) if initial is None else initial
    if model.n_states != n_states:
        raise PrognosisError(f"initial has {model.n_states} states but n_states is {n_states}")
    y_arr, u_arr = check_model_data(model, y_arr, u_arr)
    if y_arr.shape[0] < 2:
        raise PrognosisError(f"y: EM needs at least 2 samples, got {y_arr.shape[0]}")
    history: list[float] = []
    converged = False
    iterations = 0
    for iterations in range(1, max_iter + 1):
        new, res = em_arrays_step(model, y_arr, u_arr, cross_covariance, estimate_initial)
        history.append(res.log_likelihood)
        model = new
        if len(history) > 1 and history[-1] - history[-2] <= tol * abs(history[-2]):
            converged = True
            break
    history.append(filter_arrays(model, y_arr, u_arr).log_likelihood)
    return EMResult(model, np.array(history), iterations, converged)


def initial_model(y: ArrayLike, u: ArrayLike | None, n_states: int, *, seed: int | None = None
                  ) -> LinearGaussianModel:
    """The default EM start of :func:`fit_em` (deterministic without ``seed``; see there).

    Example
    -------
    >>> m = initial_model(np.arange(10.0), None, 3)
    >>> np.diag(m.A).tolist(), m.C.tolist()
    ([0.9, 0.7, 0.5], [[1.0, 1.0, 1.0]])
    """
    y, u = check_data(y, u)
    m, r = y.shape[1], u.shape[1]
    rows = ~np.isnan(y).any(axis=1)
    if rows.sum() < 2:
        raise PrognosisError("y: need at least 2 observed rows to initialize EM")
    yo, uo = y[rows], u[rows]
    d = np.linalg.lstsq(uo, yo, rcond=None)[0].T if r else np.zeros((m, 0))
    e = yo - uo @ d.T
    cov = np.atleast_2d(np.cov(e, rowvar=False))
    scale = max(float(np.trace(cov)) / m, 1e-12 * max(float(np.mean(yo ** 2)), 1.0))
    rr = _floor_psd(cov + 1e-9 * scale * np.eye(m), "R", [])
    a = np.diag(np.linspace(0.9, 0.5, n_states)) if n_states > 1 else np.array([[0.9]])
    c = np.ones((m, n_states))
    if seed is not None:
        rng = np.random.default_rng(seed)
        a = a + 0.1 * rng.standard_normal(a.shape) * (1.0 - np.eye(n_states))
        c = c * (1.0 + 0.1 * rng.standard_normal(c.shape))
    return LinearGaussianModel(A=a, B=np.zeros((n_states, r)), C=c, D=d, Q=0.1 * scale * np.eye(n_states), R=rr,
                               mu1=np.zeros(n_states), P1=scale * np.eye(n_states))


def _floor_psd(a: np.ndarray, name: str, floored: list) -> np.ndarray:
    """Symmetrize and lift the eigenvalues of ``a`` to at least the floor; note ``name`` if it was needed."""
    a = linalg.symmetric(a)
    values, vectors = np.linalg.eigh(a)
    floor = max(EIGENVALUE_FLOOR * max(values[-1], 0.0), EIGENVALUE_FLOOR_ABSOLUTE)
    if values[0] >= floor:
        return a
    floored.append(name)
    return linalg.symmetric((vectors * np.maximum(values, floor)) @ vectors.T)


#: Eigenvalues of Q, R (with S: of Q - S R^-1 S^T) and P1 are floored at this fraction of the largest one
#: after an M-step, and never below EIGENVALUE_FLOOR_ABSOLUTE.
EIGENVALUE_FLOOR = 1e-10


EIGENVALUE_FLOOR_ABSOLUTE = 1e-150
