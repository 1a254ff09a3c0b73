"""Element kinds of a bond graph and their port structure.

The kinds follow the model contract of docs/design.md::

    sources      Se Sf MSe MSf      one power port, impose effort (e) or flow (f)
    storage      C I                one power port, integral or derivative causality
    dissipation  R                  one power port
    two-ports    TF GY MTF MGY      port 1 = entering bond, port 2 = leaving bond
    junctions    0 1                common effort (0) or common flow (1)
    detectors    De Df              signal bond from a junction, no power
"""

from __future__ import annotations

__all__ = [
    "DETECTORS", "DETECTOR_JUNCTION", "EFFORT_SOURCES", "FLOW_SOURCES", "GYRATORS", "JUNCTIONS", "KINDS",
    "LAW_VARIABLES", "MODULATED_TWO_PORTS", "ONE_PORTS", "PARAMETRIC", "SOURCES", "STORAGE", "TRANSFORMERS",
    "TWO_PORTS", "normalize_kind",
]

SOURCES = frozenset({"Se", "Sf", "MSe", "MSf"})
EFFORT_SOURCES = frozenset({"Se", "MSe"})
FLOW_SOURCES = frozenset({"Sf", "MSf"})
STORAGE = frozenset({"C", "I"})
ONE_PORTS = SOURCES | STORAGE | {"R"}
TRANSFORMERS = frozenset({"TF", "MTF"})
GYRATORS = frozenset({"GY", "MGY"})
TWO_PORTS = TRANSFORMERS | GYRATORS
MODULATED_TWO_PORTS = frozenset({"MTF", "MGY"})
JUNCTIONS = frozenset({"0", "1"})
DETECTORS = frozenset({"De", "Df"})
PARAMETRIC = STORAGE | {"R"} | TWO_PORTS
KINDS = ONE_PORTS | TWO_PORTS | JUNCTIONS | DETECTORS

#: The junction a detector must sit on: an effort detector on a common-effort
#: junction, a flow detector on a common-flow junction.
DETECTOR_JUNCTION = {"De": "0", "Df": "1"}

#: Port variables a nonlinear ``law`` may relate, and those it must mention.
#: C relates its effort to its charge q (integral of flow); I its flow to its
#: momentum p (integral of effort); R its effort to its flow.
LAW_VARIABLES = {"C": ("e", "q"), "I": ("f", "p"), "R": ("e", "f")}


def normalize_kind(kind: object) -> str | None:
    """Return the canonical kind string, accepting ``0``/``1`` as integers.

    >>> normalize_kind(0), normalize_kind("MSe"), normalize_kind("X")
    ('0', 'MSe', None)
    """
    if isinstance(kind, bool):
        return None
    if isinstance(kind, int) and kind in (0, 1):
        return str(kind)
    if isinstance(kind, str) and kind in KINDS:
        return kind
    return None
