"""diagnosis: interval-valued ARRs from bond graphs, interval thresholds, fault signatures, detection.

>>> from bondgraph.library import torsion_bar_monitorable
>>> from diagnosis import derive_arrs
>>> [arr.name for arr in derive_arrs(torsion_bar_monitorable())]
['ARR_1_1', 'ARR_1_2']
"""

from .arrs import ARR, ARRWarning, delta, derive_arrs
from .signatures import SignatureMatrix, signature_matrix

__all__ = ["ARR", "ARRWarning", "SignatureMatrix", "delta", "derive_arrs", "signature_matrix"]
