"""prognosis: from the nominal residual of an ARR to the remaining useful life (Jha et al. (2016)).

The core chain lives at the top of the package: a degradation law of the prognostic candidate
``theta`` (:mod:`.degradation`), the observation equation ``y = -r_n`` derived from the ARR
(:mod:`.observation`), the SIR particle filter with its resampling schemes and variance adaptation
(:mod:`.particle_filter`, :mod:`.resampling`), the resample-move filter over a law's static
parameters with the residual noise and wandering offset it weighs them by (:mod:`.resample_move`,
:mod:`.likelihood`, :mod:`.wander`),
the RUL by propagating the particles to the failure value (:mod:`.rul`), the prognostic metrics
(:mod:`.metrics`) and the health monitor that runs detection, estimation and RUL on a record
(:mod:`.monitor`).

Three method families sit beside it as subpackages:

* :mod:`prognosis.statespace`: Kalman filters (EKF, UKF, square-root CKF, strong tracking), a
  bootstrap particle filter, consistency tests, look-ahead and ROS-ELM forecasts on a discrete
  model of the bond graph (Du et al. (n.d.));
* :mod:`prognosis.identification`: linear Gaussian models identified by EM on a sliding window,
  fault trend and the posterior predictive (Gasperin et al. (2011));
* :mod:`prognosis.lifecontrol`: energy-driven deterioration, Chebyshev bounds, Monte Carlo RUL and
  RUL control (Rodriguez Obando et al. (2021)).

>>> from bondgraph.library import torsion_bar_monitorable
>>> from diagnosis import derive_arrs
>>> from prognosis import observation_model
>>> observation_model(derive_arrs(torsion_bar_monitorable(), complete=False, integrals="keep")[0], "b_Md").coefficient
-omega_m(t)/k_belt**2
"""

from .errors import PrognosisError
from .degradation import (CustomDegradation, ExponentialDegradation, LinearDegradation, PowerDegradation,
                          degradation_model)
from .metrics import (alpha_lambda, pooled_scores, prognostic_horizon, relative_accuracy, relative_rmse, rmad,
                      scores_against_truth)
from .health_monitor import HealthMonitor, MonitorResult
from .isolation import MAX_PARTICLES, IsolatingMonitor, IsolationResult, IsolationSettings
from .pipeline import PrognosisSettings, check_candidate, check_failures, filter_step, prognose, rul_horizon
from .observation import ObservationModel, observation_model
from .likelihood import ResidualNoise
from .particle_filter import ParticleFilter, StepDiagnostics, VarianceAdaptation
from .progpy_export import ProgPyDefinition, progpy_definition, to_progpy, to_progpy_samples
from .resample_move import ResampleMoveFilter
from .resampling import effective_sample_size
from .rul import RULDistribution, RULPredictor, predict_rul

__all__ = [
    "CustomDegradation", "ExponentialDegradation", "HealthMonitor", "IsolatingMonitor", "IsolationResult",
    "IsolationSettings",
    "LinearDegradation", "MAX_PARTICLES", "MonitorResult", "ObservationModel", "ParticleFilter", "PowerDegradation",
    "PrognosisError", "PrognosisSettings", "ProgPyDefinition", "RULDistribution", "RULPredictor", "ResampleMoveFilter",
    "ResidualNoise",
    "StepDiagnostics", "VarianceAdaptation", "alpha_lambda", "check_candidate", "check_failures",
    "degradation_model", "effective_sample_size", "filter_step", "observation_model", "pooled_scores", "predict_rul",
    "prognose", "progpy_definition",
    "prognostic_horizon", "relative_accuracy", "relative_rmse", "rmad", "rul_horizon", "scores_against_truth",
    "to_progpy", "to_progpy_samples",
]
