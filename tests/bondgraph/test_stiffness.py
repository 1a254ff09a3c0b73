"""A C element declared by its stiffness (e = k q) is the law form e - k*q = 0 at every stage."""

import json
import re

import numpy as np
import pytest
import sympy as sp

from bondgraph import ModelError, simulate
from bondgraph.io import ModelFileError, model_from_json, to_json
from diagnosis import derive_arrs
from tests.zoo.models import quarter_car as qc


def spring(form: str):
    """The quarter car with its suspension spring as a compliance, a stiffness or the law e - k_s*q."""
    bg = qc.build()
    bg.graph.remove_node("C_s")
    box = (-0.05, 0.05)
    if form == "stiffness":
        bg.add("k_s", "C", stiffness=qc.K_S, uncertainty=box)
    elif form == "law":
        bg.add("k_s", "C", value=qc.K_S, law="e - k_s*q", uncertainty=box)
    else:
        bg.add("k_s", "C", value=1 / qc.K_S, uncertainty=box)
    bg.bond("1_d", "k_s")
    return bg


@pytest.mark.parametrize("integrals", ["avoid", "keep"])
def test_a_stiffness_gives_the_arrs_of_the_law_form(integrals):
    stiff = derive_arrs(spring("stiffness"), complete=False, integrals=integrals)
    law = derive_arrs(spring("law"), complete=False, integrals=integrals)
    assert [a.name for a in stiff] == [a.name for a in law]
    for a, b in zip(stiff, law):
        assert a.nominal == b.nominal and a.uncertain == b.uncertain
        assert a.values["k_s"] == qc.K_S and a.uncertainties == b.uncertainties
    # the residuals are linear in the stiffness: it multiplies the spring's deflection
    k = sp.Symbol("k_s")
    seeing = [a for a in stiff if k in a.nominal.free_symbols]
    assert seeing and all(not sp.diff(a.nominal, k).has(k) for a in seeing)


def test_a_stiffness_simulates_as_the_compliance_one_over_k():
    t = np.linspace(0.0, 2.0, 401)
    road = {"v_r": lambda t: 0.05 * np.sin(9.4 * t)}
    stiff = simulate(spring("stiffness"), (0.0, 2.0), road, t_eval=t).record()
    compliance = simulate(spring("compliance"), (0.0, 2.0), road, t_eval=t).record()
    for signal in ("v_u", "v_s"):
        scale = np.max(np.abs(compliance[signal]))
        assert scale > 1e-3 and np.max(np.abs(stiff[signal] - compliance[signal])) < 1e-4 * scale


def test_a_stiffness_survives_json():
    text = to_json(spring("stiffness"))
    node = next(n for n in json.loads(text)["nodes"] if n["id"] == "k_s")
    assert node["stiffness"] == qc.K_S and "value" not in node
    back = model_from_json(text).model
    assert back.parameters["k_s"] == qc.K_S
    assert [a.nominal for a in derive_arrs(back, complete=False)] == \
        [a.nominal for a in derive_arrs(spring("law"), complete=False)]
    bad = text.replace(f'"stiffness": {json.dumps(qc.K_S)}', '"stiffness": "stiff"')
    with pytest.raises(ModelFileError, match="'stiffness' must be a number"):
        model_from_json(bad)


@pytest.mark.parametrize("kind, attributes, message", [
    ("C", {"stiffness": 10.0, "value": 0.1}, "give 'stiffness' (e = k q) or 'value'"),
    ("C", {"stiffness": 10.0, "law": "e - k*q"}, "give 'stiffness' (e = k q) or 'law'"),
    ("C", {"stiffness": "10"}, "stiffness '10' is not a number"),
    ("C", {"stiffness": -10.0}, "outside its domain positive"),
    ("R", {"stiffness": 10.0}, "'stiffness' is only for C elements"),
    ("I", {"stiffness": 10.0, "value": 1.0}, "'stiffness' is only for C elements"),
])
def test_a_bad_stiffness_names_the_node(kind, attributes, message):
    bg = qc.build()
    with pytest.raises(ModelError, match=re.escape(message)) as caught:
        bg.add("k", kind, **attributes)
    assert f"{kind} 'k'" in str(caught.value)
