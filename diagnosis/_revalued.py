"""A copy of a model with some parameters' values or uncertainty boxes replaced (elements and law constants)."""

from __future__ import annotations

from collections.abc import Mapping

from bondgraph import BondGraph

__all__ = ["revalued"]

#: The element kinds whose node carries a parameter (its ``param``, else the node's name).
PARAMETRIC = ("C", "I", "R", "TF", "GY", "MTF", "MGY")


def revalued(bg, values: Mapping | None = None, boxes: Mapping | None = None) -> BondGraph:
    """A copy of ``bg`` whose parameters in ``values`` take those values (a spring's stiffness where it is
    given as one) and whose parameters in ``boxes`` take those ``uncertainty=(lo, hi)`` boxes."""
    values, boxes = values or {}, boxes or {}
    graph = bg.graph.copy()
    for name, data in graph.nodes(data=True):
        param = data.get("param", name) if data.get("kind") in PARAMETRIC else None
        if param in values:
            data["stiffness" if "stiffness" in data else "value"] = values[param]
        if param in boxes:
            data["uncertainty"] = tuple(boxes[param])
        constants = dict(data.get("params") or {})
        if any(c in values for c in constants):
            data["params"] = {c: values.get(c, v) for c, v in constants.items()}
        if any(c in boxes for c in constants):
            data["uncertainties"] = {**(data.get("uncertainties") or {}),
                                     **{c: tuple(boxes[c]) for c in constants if c in boxes}}
    return BondGraph(graph, name=bg.name)
