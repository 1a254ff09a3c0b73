"""BondGraphTools ``.bg`` files (bondgraph.bgt_format): the state equations of files written in its format
equal equations derived by hand from the physics; bad files are refused with the file, model, component
and line named; write_bgt reads back to the same equations.  (BondGraphTools' own equations:
tests/interop/test_bondgraphtools.py.)"""

from __future__ import annotations

import pytest
import sympy as sp
from sympy.core.function import AppliedUndef

from bondgraph import bgt_format, io
from bondgraph.bgt_format import BGTFileError, model_from_bgt, read_bgt, write_bgt
from bondgraph.io import ModelFileError, load_model
from bondgraph.library import dc_motor, rlc_circuit

pytestmark = pytest.mark.extras   # .bg files are YAML: PyYAML, the bgt extra

# BondGraphTools' test/files/rlc_parallel.bg, the layout of its own files: a series RLC on a 1-junction
SERIES_RLC = """\
# Base Model Definition
root: RLC
version: 0.1
models:
    /:
      components:
        - R1  base/R   2
        - C1  base/C   C=0.5
        - L1  base/I   L=4
        - kvl base/1
        - Se  base/Se

      netlist:
        - R1 kvl.inverting
        - C1 kvl.inverting
        - L1 kvl.inverting
        - Se kvl.non_inverting
"""


def two_inductors(tf: tuple[str, str] = ("0", "1"), gy: tuple[str, str] = ("0", "1")) -> str:
    """A source on a 1-junction with R1, L1 drives, through TF T and GY G, a 1-junction with L2, R2.

    ``tf``/``gy`` give the ports facing the source, then the load: ("1", "0") turns the element round.
    """
    return f"""\
version: '0.1'
root: coupled
models:
  /:
    components:
    - Se base/Se
    - J1 base/1
    - R1 base/R r=2
    - L1 base/I L=3
    - T base/TF r=5
    - G base/GY R=7
    - J2 base/1
    - L2 base/I L=11
    - R2 base/R 13
    netlist:
    - Se J1.non_inverting
    - J1.inverting R1
    - J1.inverting L1
    - J1.inverting T.{tf[0]}
    - T.{tf[1]} G.{gy[0]}
    - G.{gy[1]} J2.non_inverting
    - J2.inverting L2
    - J2.inverting R2
"""


def plain(expression) -> sp.Expr:
    """``expression`` with each function of time (a state, an input ``Se(t)``) as a plain symbol."""
    return sp.sympify(expression).replace(lambda e: isinstance(e, AppliedUndef), lambda e: sp.Symbol(e.func.__name__))


def rhs_by_state(bg) -> dict:
    """Our state equations as {state name: right-hand side}, parameters as symbols, signals as symbols."""
    eqs = bg.state_equations()
    return {str(plain(x)): plain(rhs) for x, rhs in zip(eqs.states, eqs.rhs)}


def same(ours: dict, expected: dict) -> bool:
    return set(ours) == set(expected) and all(sp.simplify(ours[k] - expected[k]) == 0 for k in ours)


def test_a_series_rlc_has_the_equations_of_kirchhoff():
    bg = read_bgt("rlc.bg", text=SERIES_RLC)
    q, p, se = sp.symbols("q_C1 p_L1 Se")
    r, c, el = sp.symbols("R1 C1 L1")
    # one loop current p/L: dq/dt = i, dp/dt = Se - R i - q/C
    assert same(rhs_by_state(bg), {"q_C1": p / el, "p_L1": se - r * p / el - q / c})
    assert bg.parameters == {"R1": 2.0, "C1": 0.5, "L1": 4.0}


@pytest.mark.parametrize("tf, gy", [(("0", "1"), ("0", "1")), (("1", "0"), ("1", "0"))])
def test_transformer_and_gyrator_follow_bondgraphtools_ports(tf, gy):
    # by hand, with BondGraphTools' laws (every port takes power in; bonds share e, oppose f):
    # TF e1 = r e0, f0 = -r f1 and GY e1 = -R f0, e0 = R f1.  Loop currents i1 = p1/L1, i2 = p2/L2; the
    # pair is lossless, so the coupling k = R/r enters the two loops with opposite signs:
    # dp1/dt = Se - R1 i1 + k i2,  dp2/dt = -k i1 - R2 i2.  Turned round, a TF is r -> 1/r, a GY R -> -R.
    bg = read_bgt("coupled.bg", text=two_inductors(tf, gy))
    p1, p2, se, r1, l1, l2, r2, r, g = sp.symbols("p_L1 p_L2 Se R1 L1 L2 R2 T G")
    ratio = r if tf == ("0", "1") else 1 / r
    gyration = g if gy == ("0", "1") else -g
    k = gyration / ratio
    expected = {"p_L1": se - r1 * p1 / l1 + k * p2 / l2, "p_L2": -k * p1 / l1 - r2 * p2 / l2}
    assert same(rhs_by_state(bg), expected)


def test_write_bgt_reads_back_to_the_same_equations():
    for original in (rlc_circuit(), dc_motor()):
        back = read_bgt("back.bg", text=write_bgt(original))
        values = {sp.Symbol(k): v for k, v in original.parameters.items()}
        values_back = {sp.Symbol(k): v for k, v in back.parameters.items()}
        ours, theirs = rhs_by_state(original), rhs_by_state(back)
        assert set(ours) == set(theirs)
        for state in ours:
            assert sp.simplify(ours[state].subs(values) - theirs[state].subs(values_back)) == 0
        assert back.outputs == original.outputs and back.inputs == original.inputs


def test_load_model_reads_a_bg_file(tmp_path):
    path = tmp_path / "rlc.bg"
    path.write_text(SERIES_RLC)
    spec = load_model(path)
    assert spec.source == str(path) and spec.model.name == "RLC" and spec.model.inputs == ["Se"]
    assert path.read_text() == SERIES_RLC


def test_source_sensors_become_sources_or_sensors():
    data = {"version": "0.1", "root": "x", "models": {"/": {
        "components": ["u base/SS e=V_in", "J base/1", "R base/R 1", "L base/I 1", "i base/SS e=0",
                       "Z base/0", "C base/C 1", "v base/SS f=0"],
        "netlist": ["u J.non_inverting", "J.inverting R", "J.inverting L", "J.inverting i", "J.inverting Z",
                    "Z C", "v Z"]}}}
    bg = model_from_bgt(data, where="ss.bg")
    kinds = {n: d["kind"] for n, d in bg.graph.nodes(data=True)}
    assert (kinds["u"], kinds["i"], kinds["v"]) == ("Se", "Df", "De")
    assert bg.inputs == ["V_in"] and bg.outputs == ["i", "v"]
    assert {("J", "i"), ("Z", "v")} <= set(bg.graph.edges)


def test_a_ring_of_junctions_no_orientation_fits_gets_a_junction_on_a_bond():
    # three 1-junctions bonded non_inverting to non_inverting: each bond wants its two junctions turned
    # opposite ways, which an odd ring cannot do; a 0-junction of two bonds is exactly the third bond
    data = {"version": "0.1", "root": "x", "models": {"/": {
        "components": ["Se base/Se", "A base/1", "B base/1", "C base/1", "L base/I 1", "R base/R 1", "K base/C 1"],
        "netlist": ["A.non_inverting B.non_inverting", "B.non_inverting C.non_inverting",
                    "C.non_inverting A.non_inverting", "Se A.non_inverting", "B.inverting L", "C.inverting R",
                    "A.inverting K"]}}}
    graph = model_from_bgt(data, where="x.bg").graph
    middle = [n for n, d in graph.nodes(data=True) if d["kind"] == "0"]
    assert middle == ["C_A"] and {("C_A", "C"), ("C_A", "A")} <= set(graph.edges)
    assert graph.number_of_edges() == 8


def error(text: str, where: str = "bad.bg") -> str:
    with pytest.raises(BGTFileError) as caught:
        read_bgt(where, text=text)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(where)
    return message


@pytest.mark.parametrize("change, expected", [
    (("version: 0.1", "version: 0.3"), "unknown BondGraphTools file version '0.3'"),
    (("        - Se  base/Se", "        - Se  BioChem/Ce"), "component 'Se  BioChem/Ce' (line 11): 'BioChem/Ce' is"),
    (("        - R1 kvl.inverting", "        - R1 kcl.inverting"),
     "bond 'R1 kcl.inverting' (line 14): no component 'kcl'"),
    (("        - R1 kvl.inverting", "        - R1 kvl"), "a 1-junction's bond names its port"),
    (("        - R1 kvl.inverting", "        - R1.3 kvl.inverting"), "R 'R1' has one port (0), not '3'"),
    (("base/R   2", "base/R   R_1"), "parameter 'R_1' has no value"),
    (("base/R   2", "base/R   x=2"), "unknown parameter 'x' (parameters: r)"),
    (("base/R   2", "base/R   2 3"), "value '3' is one too many"),
    (("base/R   2", "base/R   __import__('os')"), "is neither a number nor a name"),
    (("root: RLC", "root: RLC\nextra: 1"), "unknown top-level field(s) ['extra']"),
])
def test_bad_files_are_refused_naming_the_item(change, expected):
    text = SERIES_RLC.replace(*change)
    assert text != SERIES_RLC
    assert expected in error(text)


def test_yaml_that_is_not_a_model_or_not_safe_is_refused(tmp_path, monkeypatch):
    assert "expected a YAML mapping" in error("- a\n- b\n")
    assert "not valid YAML" in error("root: !!python/object/apply:os.system ['true']\n")
    assert "line 2" in error("root: x\n  : : [\n")
    assert "contains itself" in error("version: 0.1\nroot: x\nmodels:\n  /:\n    components: [a /]\n")
    # twenty levels of ten empty sub-models each would be 10^20 expansions: stopped at the limit
    levels = "".join(f"  m{k}:\n    components: [{', '.join(f'x{j} m{k + 1}' for j in range(10))}]\n"
                     for k in range(20))
    nested = f"version: 0.1\nroot: x\nmodels:\n  /:\n    components: [top m0]\n{levels}  m20:\n    components: []\n"
    assert "more than 10000 model instances" in error(nested)
    monkeypatch.setattr(bgt_format, "MAX_FILE_BYTES", 100)
    path = tmp_path / "big.bg"
    path.write_text(SERIES_RLC)
    with pytest.raises(BGTFileError, match="larger than the limit of 100 bytes"):
        read_bgt(path)
    with pytest.raises(ModelFileError, match="big.bg: .* larger than the limit"):   # load_model keeps its error
        load_model(path)


def test_the_limits_are_those_of_json_model_files():
    assert (bgt_format.MAX_FILE_BYTES, bgt_format.MAX_NODES, bgt_format.MAX_LINKS) == (
        io.MAX_FILE_BYTES, io.MAX_NODES, io.MAX_LINKS)


def test_an_open_source_sensor_is_refused():
    data = {"version": "0.1", "root": "x", "models": {"/": {
        "components": ["p base/SS", "Z base/0", "C base/C 1"], "netlist": ["p Z", "Z C"]}}}
    with pytest.raises(BGTFileError, match=r"x.bg: model '/' component 'p base/SS': an open source-sensor"):
        model_from_bgt(data, where="x.bg")
