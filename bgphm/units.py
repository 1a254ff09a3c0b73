"""The units the outputs state: the ``units`` block of ``summary.json`` (detect, prognose, fleet) and the page.

Examples
--------
>>> from bondgraph.library import dc_motor
>>> from diagnosis import derive_arrs
>>> motor = dc_motor()
>>> block = units_of(motor, derive_arrs(motor))
>>> block["t"], block["parameters"]["b"], block["residuals"]
('s', 'N*m*s/rad', {'ARR_1_e': 'V', 'ARR_1_m': 'N*m'})
"""

from __future__ import annotations

__all__ = ["units_of"]


def units_of(model, arrs) -> dict:
    """The units a command's JSON states: time, each signal and parameter of the model, each residual (empty
    texts where the model declares none)."""
    units = model.units
    return {"t": "s", "signals": {s: units.text(s) for s in [*model.inputs, *model.outputs]},
            "parameters": {p: units.text(p) for p in model.parameters},
            "residuals": {arr.name: str(arr.unit(units) or "") for arr in arrs}}
