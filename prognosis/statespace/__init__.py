"""State-space estimation on a discrete model made from the bond graph's state equations.

The degrading parameter becomes an extra state of a :class:`DiscreteModel` (:mod:`.model`, with
sympy Jacobians), which every estimator here tracks through one interface (``predict``,
``update``, ``step``, ``mean``, ``covariance``, ``copy``):

* :mod:`.ekf`, :mod:`.ukf`, :mod:`.ckf`: the extended, unscented and square-root cubature Kalman
  filters on the shared base of :mod:`.gaussian`, each with the strong-tracking fading factor of
  :mod:`.strong_tracking` (Du et al. (n.d.), section 3);
* :mod:`.bootstrap`: a bootstrap (SIR) particle filter with the same interface;
* :mod:`.consistency`: innovation consistency tests and an online supervisor of the innovations;
* :mod:`.lookahead`: n-step-ahead prediction by filtering forecast measurements;
* :mod:`.elm`: the regularized online sequential extreme learning machine (ROS-ELM) that forecasts them.

Examples
--------
>>> import numpy as np, sympy as sp
>>> from types import SimpleNamespace
>>> x, a = sp.symbols("x a")
>>> decay = SimpleNamespace(states=[x], rhs=[-a * x], inputs=[], outputs={"y": x}, parameters={"a": 0.1})
>>> model = discretize(decay, dt=1.0, augment=["a"])   # the decay rate a becomes a state
>>> model.states
('x', 'a')
>>> ekf = ExtendedKalmanFilter(model, [1.0, 0.2], np.diag([1e-4, 1e-2]), np.diag([1e-8, 1e-6]), [[1e-6]])
>>> for k in range(1, 61):
...     _ = ekf.step([0.9**k])
>>> round(float(ekf.mean[1]), 2)   # Euler step: x_{k+1} = (1 - a) x_k = 0.9 x_k
0.1
"""

from .bootstrap import BootstrapParticleFilter
from .consistency import ConsistencyReport, InnovationMonitor, innovation_consistency, whiten
from .elm import ROSELM, SeriesForecaster
from .ckf import CubatureKalmanFilter
from .ekf import ExtendedKalmanFilter
from .gaussian import FilterWarning, Innovation
from .strong_tracking import StrongTracking
from .ukf import UnscentedKalmanFilter
from .lookahead import LookAhead, look_ahead, predict_ahead
from .discrete_model import DiscreteModel, discretize

__all__ = [
    "BootstrapParticleFilter", "ConsistencyReport", "CubatureKalmanFilter", "DiscreteModel", "ExtendedKalmanFilter",
    "FilterWarning", "Innovation", "InnovationMonitor", "LookAhead", "ROSELM", "SeriesForecaster", "StrongTracking",
    "UnscentedKalmanFilter", "discretize", "innovation_consistency", "look_ahead", "predict_ahead", "whiten",
]
