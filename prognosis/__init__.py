"""prognosis: ARR-based fault model, batched particle filter, RUL prediction, metrics, health monitoring.

>>> from bondgraph.library import torsion_bar_monitorable
>>> from diagnosis import derive_arrs
>>> from prognosis import observation_model
>>> observation_model(derive_arrs(torsion_bar_monitorable())[0], "b_Md").coefficient
-omega_m(t)/k_belt**2
"""

from .degradation import Custom, Exponential, Linear, degradation_model
from .filter import ParticleFilter, StepDiagnostics, VarianceAdaptation
from .monitor import HealthMonitor, MonitorResult
from .observation import ObservationModel, observation_model
from .rul import RULPrediction, RULPredictor, predict_rul

__all__ = [
    "Custom", "Exponential", "HealthMonitor", "Linear", "MonitorResult", "ObservationModel", "ParticleFilter",
    "RULPrediction", "RULPredictor", "StepDiagnostics", "VarianceAdaptation", "degradation_model",
    "observation_model", "predict_rul",
]
