"""bgphm: the user-facing layer of bondgraph-phm: the ``bgphm`` command line and the plots.

The library lives in three packages whose data flow one way, ``bondgraph`` (model, causality,
equations, simulation) -> ``diagnosis`` (ARRs, intervals, thresholds, detection) -> ``prognosis``
(fault model, filters, RUL); this package sits on top of them and is the only one that may use
matplotlib (optional: ``pip install 'bondgraph-phm[plot]'``).
"""

__all__ = []
