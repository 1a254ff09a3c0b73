"""prognosis: ARR-based fault model, particle and Kalman filters, RUL prediction, metrics, health monitoring.

>>> from bondgraph.library import torsion_bar_monitorable
>>> from diagnosis import derive_arrs
>>> from prognosis import observation_model
>>> observation_model(derive_arrs(torsion_bar_monitorable())[0], "b_Md").coefficient
-omega_m(t)/k_belt**2
"""

from .bootstrap import BootstrapParticleFilter
from .degradation import Custom, Exponential, Linear, degradation_model
from .elm import ROSELM, SeriesForecaster
from .filter import ParticleFilter, StepDiagnostics, VarianceAdaptation
from .kalman import CubatureKalmanFilter, ExtendedKalmanFilter, FilterWarning, Innovation, StrongTracking, UnscentedKalmanFilter
from .lookahead import LookAhead, look_ahead, predict_ahead
from .monitor import HealthMonitor, MonitorResult
from .observation import ObservationModel, observation_model
from .rul import RULPrediction, RULPredictor, predict_rul
from .statespace import DiscreteModel, discretize

__all__ = [
    "BootstrapParticleFilter", "CubatureKalmanFilter", "Custom", "DiscreteModel", "Exponential",
    "ExtendedKalmanFilter", "FilterWarning", "HealthMonitor", "Innovation", "Linear", "LookAhead", "MonitorResult",
    "ObservationModel", "ParticleFilter", "ROSELM", "RULPrediction", "RULPredictor", "SeriesForecaster",
    "StepDiagnostics", "StrongTracking", "UnscentedKalmanFilter", "VarianceAdaptation", "degradation_model",
    "discretize", "look_ahead", "observation_model", "predict_ahead", "predict_rul",
]
