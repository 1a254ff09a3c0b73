"""diagnosis: interval-valued ARRs from bond graphs, interval thresholds, fault signatures, detection.

>>> from bondgraph.library import torsion_bar_monitorable
>>> from diagnosis import derive_arrs
>>> [arr.name for arr in derive_arrs(torsion_bar_monitorable())]
['ARR_1_1', 'ARR_1_2', 'ARR_MSO_1']
"""

from .derivation import derive_arrs, evaluable
from .arr import ARR, ARRWarning
from .residuals import ARRError
from .deltas import delta
from .detection import Evaluation, evaluate, noise_margin, robust_std
from .codegen import CodegenError, generate_code
from .calibration import POOLED_RECORDS, Calibration, DetectionSettings, calibrate, calibration_end, pooled_calibration
from .detectability import Detectability, detectability
from .monitoring import Detection, consistent_faults, detect
from .model_validation import (ModelFigures, ModelValidation, Whiteness, held_out_figures, residual_whiteness,
                               validate_calibration)
from .parameter_estimation import (Identifiability, ParameterEstimate, estimate_parameters, identifiability,
                                   uncertainty_boxes)
from .elimination import structural_arrs, unreached
from .fdt_export import to_fdt
from .intervals import Interval, IntervalArray, IntervalWarning, affine_range, compile_interval
from .csv_reading import read_csv
from .records import (Record, RecordError, RecordWarning, SensorFault, add_noise, add_sensor_faults, as_record,
                      check_signals)
from .uniform_grid import resample
from .sensor_placement import SensorPlacement, place_sensors
from .signatures import SignatureMatrix, signature_matrix
from .streaming import StreamChunk, StreamingEvaluation
from .structural import StructuralLimitError, StructuralModel, structural_model

__all__ = [
    "ARR", "ARRError", "ARRWarning", "Calibration", "CodegenError", "Detectability", "Detection", "DetectionSettings",
    "Evaluation", "Identifiability", "Interval", "IntervalArray", "IntervalWarning", "ModelFigures", "ModelValidation",
    "POOLED_RECORDS", "ParameterEstimate", "Record", "RecordError", "RecordWarning", "SensorFault", "SensorPlacement",
    "SignatureMatrix", "StreamChunk", "StreamingEvaluation", "StructuralLimitError", "StructuralModel", "Whiteness",
    "add_noise", "add_sensor_faults", "affine_range", "as_record", "calibrate", "calibration_end", "check_signals",
    "compile_interval", "consistent_faults", "delta", "derive_arrs", "detect", "detectability", "estimate_parameters",
    "evaluable", "evaluate", "generate_code", "held_out_figures", "identifiability", "noise_margin", "place_sensors",
    "pooled_calibration", "read_csv", "resample", "residual_whiteness", "robust_std", "signature_matrix",
    "structural_arrs", "structural_model", "to_fdt", "uncertainty_boxes", "unreached", "validate_calibration",
]
