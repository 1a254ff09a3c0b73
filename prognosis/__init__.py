"""prognosis: ARR-based fault model, particle and Kalman filters, RUL prediction, metrics, health monitoring.

>>> from bondgraph.library import torsion_bar_monitorable
>>> from diagnosis import derive_arrs
>>> from prognosis import observation_model
>>> observation_model(derive_arrs(torsion_bar_monitorable())[0], "b_Md").coefficient
-omega_m(t)/k_belt**2
"""

from .bootstrap import BootstrapParticleFilter
from .chebyshev import chebyshev_bounds, chebyshev_intervals, chebyshev_level, chebyshev_scale, covariance_from_bounds
from .consistency import ConsistencyReport, InnovationMonitor, innovation_consistency, whiten
from .degradation import Custom, Exponential, Linear, degradation_model
from .deterioration import DeteriorationEquations, energy_deterioration
from .elm import ROSELM, SeriesForecaster
from .filter import ParticleFilter, StepDiagnostics, VarianceAdaptation
from .identification import (EMResult, FeaturePrediction, IdentificationWarning, LinearGaussianModel, OnlineEM,
                             SmootherResult, WindowIdentification, detect_trend, em_step, fault_trend, fit_em,
                             initial_model, kalman_smoother, log_likelihood, predict_feature)
from .kalman import CubatureKalmanFilter, ExtendedKalmanFilter, FilterWarning, Innovation, StrongTracking, UnscentedKalmanFilter
from .lookahead import LookAhead, look_ahead, predict_ahead
from .monitor import HealthMonitor, MonitorResult
from .montecarlo import RULDistribution, monte_carlo_rul, sample_gaussian
from .observation import ObservationModel, observation_model
from .predictive import PosteriorPrediction, SamplerWarning, WindowPosterior, sample_posterior, window_log_posterior
from .rul import RULPrediction, RULPredictor, predict_rul
from .rulcontrol import RULController, RULDecision
from .statespace import DiscreteModel, discretize

__all__ = [
    "ConsistencyReport", "DeteriorationEquations", "InnovationMonitor", "RULController", "RULDecision",
    "RULDistribution", "chebyshev_bounds", "chebyshev_intervals", "chebyshev_level", "chebyshev_scale",
    "covariance_from_bounds", "energy_deterioration", "innovation_consistency", "monte_carlo_rul", "sample_gaussian",
    "whiten", "EMResult", "FeaturePrediction", "IdentificationWarning", "LinearGaussianModel", "OnlineEM",
    "SmootherResult", "WindowIdentification", "detect_trend", "em_step", "fault_trend", "fit_em", "initial_model",
    "kalman_smoother", "log_likelihood", "predict_feature",
    "PosteriorPrediction", "SamplerWarning", "WindowPosterior", "sample_posterior", "window_log_posterior",
    "BootstrapParticleFilter", "CubatureKalmanFilter", "Custom", "DiscreteModel", "Exponential",
    "ExtendedKalmanFilter", "FilterWarning", "HealthMonitor", "Innovation", "Linear", "LookAhead", "MonitorResult",
    "ObservationModel", "ParticleFilter", "ROSELM", "RULPrediction", "RULPredictor", "SeriesForecaster",
    "StepDiagnostics", "StrongTracking", "UnscentedKalmanFilter", "VarianceAdaptation", "degradation_model",
    "discretize", "look_ahead", "observation_model", "predict_ahead", "predict_rul",
]
