"""bondgraph: bond graph models, causality, sympy equations and simulation.

The public names load on first use (:pep:`562`), so that ``import bondgraph.errors`` (as the command
line's ``--help`` does) costs no sympy, scipy or networkx import.

>>> from bondgraph import BondGraph, simulate
>>> from bondgraph.library import dc_motor
>>> dc_motor().assign_causality("integral").storage
{'L_a': 'integral', 'J': 'integral'}
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # what the lazy names below resolve to, for type checkers and readers
    from .bgt_format import read_bgt, write_bgt
    from .causality import Causality, CausalIssue, assign_causality
    from .composition import compose
    from .control import PIController
    from .drawing import to_svg, to_tikz
    from .equations import (AlgebraicLoopError, ModelEquation, StateEquations, causal_equations, labelled_equations,
                            model_equations, state_equations)
    from .errors import (CausalityError, EquationError, FmuError, LawError, ModelError, PHMError, PHMWarning,
                         SettingError, SimulationError)
    from .fmu_export import fmu_sources, to_fmu
    from .fmu_plant import FmuPlant, simulate_fmu
    from .inputs import InputExpression, TabulatedInput
    from .io import load_model, to_json
    from .model import BondGraph
    from .scenarios import Degradation, parse_degradation
    from .simulation import SimulationResult, simulate
    from .structure import Bond, Element, signal_function

#: The module of each public name.
_HOMES = {
    "bgt_format": ("read_bgt", "write_bgt"),
    "causality": ("Causality", "CausalIssue", "assign_causality"),
    "composition": ("compose",),
    "control": ("PIController",),
    "drawing": ("to_svg", "to_tikz"),
    "equations": ("AlgebraicLoopError", "ModelEquation", "StateEquations", "causal_equations", "labelled_equations",
                  "model_equations", "state_equations"),
    "errors": ("CausalityError", "EquationError", "FmuError", "LawError", "ModelError", "PHMError", "PHMWarning",
               "SettingError", "SimulationError"),
    "fmu_export": ("fmu_sources", "to_fmu"),
    "fmu_plant": ("FmuPlant", "simulate_fmu"),
    "inputs": ("InputExpression", "TabulatedInput"),
    "io": ("load_model", "to_json"),
    "model": ("BondGraph",),
    "scenarios": ("Degradation", "parse_degradation"),
    "simulation": ("SimulationResult", "simulate"),
    "structure": ("Bond", "Element", "signal_function"),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [  # the keys of _MODULE_OF, written out for readers and tools that do not run the module
    "AlgebraicLoopError", "Bond", "BondGraph", "CausalIssue", "Causality", "CausalityError", "Degradation", "Element",
    "EquationError", "FmuError", "FmuPlant", "InputExpression", "LawError", "ModelEquation", "ModelError", "PHMError",
    "PHMWarning", "PIController", "SettingError", "SimulationError", "SimulationResult", "StateEquations",
    "TabulatedInput", "assign_causality", "causal_equations", "compose", "fmu_sources", "labelled_equations",
    "load_model", "model_equations", "parse_degradation", "read_bgt", "signal_function", "simulate", "simulate_fmu",
    "state_equations", "to_fmu", "to_json", "to_svg", "to_tikz", "write_bgt",
]


def __getattr__(name: str):
    """Load a public name's module on first use; a submodule's name imports the submodule."""
    if name in _MODULE_OF:
        value = getattr(importlib.import_module(f".{_MODULE_OF[name]}", __name__), name)
        globals()[name] = value  # later uses skip this function
        return value
    try:
        return importlib.import_module(f".{name}", __name__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":  # a missing dependency of an existing module: say so
            raise
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
