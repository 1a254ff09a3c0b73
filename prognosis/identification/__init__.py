"""Linear Gaussian state-space identification by EM for fault-trend detection and prediction (Gasperin et al. (2011)).

Model (Gasperin et al. (2011), eqs. 2-3)::

    x_{t+1} = A x_t + B u_t + w_t,        [w_t]      (    [Q    S])
    y_t     = C x_t + D u_t + v_t,        [v_t]  ~ N (0,  [S^T  R]),     x_1 ~ N(mu1, P1),

with ``n`` states, ``r`` known inputs (operating conditions: torque, temperature) and ``m`` outputs (the
vibration feature).  Time runs ``t = 1..T`` in the formulas and rows ``0..T-1`` in the arrays.

* :func:`kalman_smoother` (:mod:`.smoother`) is the E-step: Kalman filter and Rauch-Tung-Striebel smoother, with the
  cross-covariance ``S`` handled exactly, and the log-likelihood of eq. (10) from the innovations.
* :func:`em_step` (:mod:`.em`) is one EM iteration (eqs. 14-23, Gibson and Ninness 2005); :func:`fit_em` iterates it.
* :class:`OnlineEM` (:mod:`.online`) re-identifies the model on a sliding window (section 3.4).
* :func:`fault_trend` (:mod:`.trend`) and :func:`detect_trend` read the fault trend off the spectral radius of ``A``
  (section 5.1); :func:`predict_feature` predicts the feature under a known future load (section 5.2).
* :func:`sample_posterior` (:mod:`.predictive`) gives the posterior predictive over the window's
  parameters, so that a prediction carries the uncertainty of the identified model too.

Example
-------
>>> import numpy as np
>>> truth = LinearGaussianModel(A=[[0.9]], B=[[0.5]], C=[[1.0]], D=[[0.2]], Q=[[0.05]], R=[[0.1]])
>>> u = np.random.default_rng(0).standard_normal((500, 1))
>>> _, y = truth.simulate(u, rng=0)
>>> fit = fit_em(y, u, n_states=1, cross_covariance=False, max_iter=30)   # a few dozen steps suffice here
>>> bool(np.all(np.diff(fit.log_likelihood) >= -1e-9 * np.abs(fit.log_likelihood[1:])))
True
>>> bool(abs(fit.model.eigenvalues[0] - 0.9) < 0.05)
True
>>> bool(fault_trend(fit.model))   # stable: no fault progression
False
"""

from .em import EMResult, em_step, fit_em, initial_model
from .linear_gaussian import IdentificationWarning, LinearGaussianModel
from .online import OnlineEM, WindowIdentification
from .predictive import PosteriorPrediction, SamplerWarning, WindowPosterior, sample_posterior, window_log_posterior
from .smoother import SmootherResult, kalman_smoother, log_likelihood
from .trend import FeaturePrediction, detect_trend, fault_trend, predict_feature

__all__ = [
    "EMResult", "FeaturePrediction", "IdentificationWarning", "LinearGaussianModel", "OnlineEM", "PosteriorPrediction",
    "SamplerWarning", "SmootherResult", "WindowIdentification", "WindowPosterior", "detect_trend", "em_step",
    "fault_trend", "fit_em", "initial_model", "kalman_smoother", "log_likelihood", "predict_feature",
    "sample_posterior", "window_log_posterior",
]
