"""bondgraph: bond graph models, causality, sympy equations and simulation.

>>> from bondgraph import BondGraph, simulate
>>> from bondgraph.library import dc_motor
>>> dc_motor().assign_causality("integral").storage
{'L_a': 'integral', 'J': 'integral'}
"""

from .causality import Causality, CausalIssue, assign_causality
from .control import PIController
from .equations import (AlgebraicLoopError, ModelEquation, StateEquations, causal_equations, labelled_equations,
                        model_equations, state_equations)
from .errors import (CausalityError, EquationError, LawError, ModelError, PHMError, PHMWarning, SettingError,
                     SimulationError)
from .model import BondGraph
from .structure import Bond, Element, signal_function
from .simulation import SimulationResult, simulate
from .drawing import to_svg, to_tikz
from .inputs import InputExpression, TabulatedInput
from .io import load_model, to_json
from .scenarios import Degradation, parse_degradation

__all__ = [
    "AlgebraicLoopError", "Bond", "BondGraph", "CausalIssue", "Causality", "CausalityError", "Degradation", "Element",
    "EquationError", "InputExpression", "LawError", "ModelEquation", "ModelError", "PHMError", "PHMWarning",
    "PIController", "SettingError", "SimulationError", "SimulationResult", "StateEquations", "TabulatedInput",
    "assign_causality", "causal_equations", "labelled_equations", "load_model", "model_equations",
    "parse_degradation", "signal_function", "simulate", "state_equations", "to_json", "to_svg", "to_tikz",
]
