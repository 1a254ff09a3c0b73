"""Model files: a bond graph from a Python file, a JSON file in networkx node-link form, or the library.

``load_model(source)`` accepts

* a JSON file (``*.json``) in networkx node-link form: ``nodes`` with an ``id`` and the node attributes
  of the model contract (``kind``, ``value``, ``uncertainty``, ``law``, ...), ``links`` (or ``edges``)
  with ``source`` and ``target`` (the power direction) and an optional ``label``, and ``graph`` with
  an optional ``name`` and the run settings ``inputs`` (signal -> a number, or the text of an expression
  of the time ``t`` such as ``"12*step(t - 0.5)"``: :class:`~bondgraph.inputs.InputExpression`),
  ``t_end`` and ``x0``, and an optional ``calibration`` object (what ``bgphm calibrate`` writes: where the
  values came from), kept as read in :attr:`ModelSpec.calibration`; ``graph.ports`` names the junctions
  where another model may bond (:meth:`BondGraph.port <bondgraph.model.BondGraph.port>`), and a file
  composed of sub-models names them in ``graph.parts`` (part -> JSON file, relative to it) and bonds their
  ports in ``graph.connections`` (``["motor.shaft", "belt.drive"]``; :mod:`bondgraph.composition`);
* a Python file (``*.py``) that defines ``model`` (a :class:`~bondgraph.model.BondGraph` or a function
  returning one), or exactly one bond graph or one such function, and optionally ``inputs`` (a
  string among them is an expression of ``t``, as in JSON), ``t_end`` and ``x0``; ``file.py:name``
  picks the object ``name``;
* a BondGraphTools file (``*.bg``, YAML; :func:`bondgraph.bgt_format.read_bgt`, the ``bgt`` extra);
* the name of a built-in example (:func:`bondgraph.library.example`): ``rlc``, ``dc-motor``,
  ``torsion-bar``, ``three-tank``.

A JSON file is data: laws, moduli and input expressions are strings parsed by
:func:`bondgraph.laws.parse_expression` (arithmetic, known names and a few functions, never ``eval``),
numbers must be finite JSON numbers, and every error names the file and the node, link, field or
input at fault.  Node ids, labels and names follow
:mod:`bondgraph.names`.  Before anything is built, a file larger than :data:`MAX_FILE_BYTES` or a model
with more than :data:`MAX_NODES` nodes or :data:`MAX_LINKS` links is refused.  A Python file is code and
runs as such: load only files you trust.

Example
-------
>>> import json
>>> text = json.dumps({"graph": {"name": "RL", "inputs": {"V": 1.0}, "t_end": 0.1},
...     "nodes": [{"id": "V", "kind": "Se"}, {"id": "J", "kind": "1"},
...               {"id": "R", "kind": "R", "value": 10.0, "uncertainty": [-0.05, 0.05]},
...               {"id": "L", "kind": "I", "value": 0.1}, {"id": "i", "kind": "Df"}],
...     "links": [{"source": "V", "target": "J"}, {"source": "J", "target": "R"},
...               {"source": "J", "target": "L"}, {"source": "J", "target": "i"}]})
>>> spec = model_from_json(text)
>>> spec.model.parameters, spec.inputs, spec.t_end
({'R': 10.0, 'L': 0.1}, {'V': 1.0}, 0.1)
>>> model_from_json(to_json(spec.model, inputs=spec.inputs)).model.parameters == spec.model.parameters
True
>>> text = text.replace('"V": 1.0', '"V": "step(t - 0.05)"')        # an input as an expression of t
>>> spec = model_from_json(text)
>>> spec.inputs, spec.inputs["V"](0.1), json.loads(to_json(spec.model, inputs=spec.inputs))["graph"]["inputs"]
({'V': InputExpression('step(t - 0.05)')}, 1.0, {'V': 'step(t - 0.05)'})
"""

from __future__ import annotations

import json
import math
import runpy
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import networkx as nx
import sympy as sp

from .errors import ModelError
from .inputs import InputExpression
from .composition import compose, path, renamed_settings
from .file_text import read_limited
from .model import BondGraph
from .names import check_node_id
from .structure import BOND_ATTRIBUTES, NODE_ATTRIBUTES, require_model

__all__ = ["ModelFileError", "ModelSpec", "load_model", "model_from_json", "to_json", "MAX_FILE_BYTES", "MAX_NODES",
           "MAX_LINKS", "MAX_PART_DEPTH"]

#: Node attributes a JSON node may carry (anything else is refused, so a typo is not silently ignored):
#: the model contract's node attributes and the ``id``.
NODE_FIELDS = NODE_ATTRIBUTES | {"id"}
LINK_FIELDS = BOND_ATTRIBUTES | {"source", "target"}
GRAPH_FIELDS = frozenset({"name", "inputs", "t_end", "x0", "description", "calibration", "ports", "parts",
                          "connections"})
#: How deep parts may nest (a part composed of parts composed of ...): a deeper file is refused.
MAX_PART_DEPTH = 8

#: The largest JSON model file (bytes; characters of a text given to :func:`model_from_json`).  A model
#: at :data:`MAX_NODES` written by :func:`to_json` takes about 1.3 MB; parsing the limit costs about a
#: second and 200 MB at worst (a file of empty lists).
MAX_FILE_BYTES = 8 * 2**20
#: The most nodes of a JSON model: four times the 2400 of the largest benchmark chain
#: (``mass_spring_chain(400)``); a model at the limit loads in about a second.
MAX_NODES = 10_000
#: The most links (bonds) of a JSON model.
MAX_LINKS = 20_000


class ModelFileError(ModelError):
    """A model file that cannot be read: the message names the file and the node, link or field."""


@dataclass
class ModelSpec:
    """A loaded model with the settings of its default run.

    Attributes
    ----------
    model : BondGraph
    inputs : dict
        Input signal -> constant value or callable ``u(t)`` (used by ``bgphm simulate``); an input a
        model file gives as text is an :class:`~bondgraph.inputs.InputExpression`.
    t_end : float or None
        Default simulation horizon.
    x0 : dict
        Initial state by storage element name.
    source : str
        Where the model came from (path or ``library:<name>``).
    calibration : dict
        The ``calibration`` object of a JSON model's ``graph`` (the provenance of calibrated values: the
        records, the method, the estimates), as read; empty without one.
    """

    model: BondGraph
    inputs: dict = field(default_factory=dict)
    t_end: float | None = None
    x0: dict = field(default_factory=dict)
    source: str = ""
    calibration: dict = field(default_factory=dict)


def load_model(source: str | Path) -> ModelSpec:
    """Load a model from a JSON, Python or BondGraphTools file, or a built-in example by name (module docstring).

    Raises :class:`ModelFileError` (a ``ModelError``) naming the file and what is wrong.

    >>> load_model("dc-motor").model.outputs
    ['i', 'omega']
    """
    text = str(source)
    path_part, attribute = (text.rsplit(":", 1) if ".py:" in text else (text, ""))
    path = Path(path_part)
    if not path.exists():
        from .library import example

        try:
            ex = example(text)
        except KeyError:
            raise ModelFileError(f"{text}: no such file (and not a built-in example: dc-motor, rlc, three-tank, "
                                 f"torsion-bar)") from None
        return ModelSpec(ex.model, dict(ex.inputs), ex.t_end, dict(ex.x0), f"library:{text}")
    if path.is_dir():
        raise ModelFileError(f"{path}: is a directory, not a model file")
    if path.suffix.lower() == ".json":
        return _from_json_file(path, ())
    if path.suffix.lower() == ".py":
        return _from_python(path, attribute or None)
    if path.suffix.lower() == ".bg":
        return _from_bgt(path)
    raise ModelFileError(f"{path}: unknown model file type {path.suffix!r} (expected .json, .py or .bg)")


def _from_json_file(path: Path, parents: tuple) -> ModelSpec:
    """A JSON model file; ``parents`` are the files composing it (a part's part...), to refuse a cycle."""
    content = read_limited(path, limit=MAX_FILE_BYTES, error=ModelFileError, what="JSON model",
                           constant="bondgraph.io.MAX_FILE_BYTES")
    return _model_from_json(content, str(path), path.parent, (*parents, path.resolve()))


def model_from_json(text: str, *, where: str = "JSON model", folder: str | Path | None = None) -> ModelSpec:
    """Parse a node-link JSON document into a :class:`ModelSpec` (no ``eval``; see the module docstring).

    A model composed of sub-models names its parts' files relative to ``folder`` (:func:`load_model` gives
    the file's own folder).

    A text longer than :data:`MAX_FILE_BYTES` characters, or with more than :data:`MAX_NODES` nodes or
    :data:`MAX_LINKS` links, is refused before the model is built.

    >>> model_from_json('{"nodes": [], "links": []}', where="empty.json")
    Traceback (most recent call last):
    ...
    bondgraph.io.ModelFileError: empty.json: 'nodes' is empty; a model needs at least one element
    """
    return _model_from_json(text, where, None if folder is None else Path(folder), ())


def _model_from_json(text: str, where: str, folder: Path | None, files: tuple) -> ModelSpec:
    if not isinstance(text, (str, bytes, bytearray)):
        raise TypeError(f"model_from_json: text must be a str, got {type(text).__name__}")
    if len(text) > MAX_FILE_BYTES:
        raise ModelFileError(f"{where}: {len(text)} characters, longer than the limit of {MAX_FILE_BYTES} for a "
                             "JSON model (bondgraph.io.MAX_FILE_BYTES)")
    try:
        data = json.loads(text, parse_constant=_no_constant(where), parse_float=_finite_float(where))
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"{where} line {exc.lineno} column {exc.colno}: not valid JSON ({exc.msg})") from None
    except RecursionError:
        raise ModelFileError(f"{where}: JSON nested too deeply") from None
    if not isinstance(data, dict):
        raise ModelFileError(f"{where}: expected a JSON object with 'nodes' and 'links', got {type(data).__name__}")
    unknown = set(data) - {"directed", "multigraph", "graph", "nodes", "links", "edges"}
    if unknown:
        raise ModelFileError(f"{where}: unknown top-level field(s) {sorted(unknown)}")
    if data.get("multigraph"):
        raise ModelFileError(f"{where}: 'multigraph' must be false (a bond graph has at most one bond per pair)")
    if data.get("directed") is False:
        raise ModelFileError(f"{where}: 'directed' must be true (a bond's direction is its power half-arrow)")
    settings = data.get("graph", {})
    if not isinstance(settings, dict):
        raise ModelFileError(f"{where}: 'graph' must be an object")
    bad = set(settings) - GRAPH_FIELDS
    if bad:
        raise ModelFileError(f"{where}: unknown field(s) {sorted(bad)} in 'graph' (allowed: {sorted(GRAPH_FIELDS)})")
    if "links" in data and "edges" in data:
        raise ModelFileError(f"{where}: give the bonds as 'links' or 'edges', not both")
    name = str(settings.get("name", Path(where).stem if where.endswith(".json") else "bond graph"))
    parts = _parts(settings, where, folder, files)
    composed = _composed(parts, settings, where)
    graph = nx.DiGraph(composed.graph) if composed is not None else nx.DiGraph()
    graph.graph = {"name": name}
    nodes = data.get("nodes", []) if parts and "nodes" not in data else _list(data, "nodes", where)
    links = data.get("links", []) if parts and not ({"links", "edges"} & set(data)) else \
        _list(data, "links" if "links" in data else "edges", where)
    for what, items, limit, constant in (("nodes", nodes, MAX_NODES, "MAX_NODES"),
                                         ("links", links, MAX_LINKS, "MAX_LINKS")):
        if len(items) > limit:  # before anything is built: validation costs time per node
            raise ModelFileError(f"{where}: {len(items)} {what}, more than the limit of {limit} "
                                 f"(bondgraph.io.{constant})")
    if not nodes and not parts:
        raise ModelFileError(f"{where}: 'nodes' is empty; a model needs at least one element")
    for index, node in enumerate(nodes):
        _add_node(graph, node, f"{where}: nodes[{index}]")
    for index, link in enumerate(links):
        _add_link(graph, link, f"{where}: links[{index}]")
    if "ports" in settings:
        graph.graph["ports"] = _ports(settings["ports"], graph, parts, where)
    try:
        model = BondGraph(graph)
    except ModelError as exc:  # keep the kind (LawError for a law) and add the file
        raise type(exc)(f"{where}: {exc}") from None
    inputs, x0 = {}, {}
    for part, spec in parts.items():  # the parts' run settings under their paths, then the file's own
        part_inputs, part_x0 = renamed_settings(part, spec.model, spec.inputs, spec.x0)
        inputs.update(part_inputs)
        x0.update(part_x0)
    inputs.update(_input_values(settings.get("inputs", {}), f"{where}: graph.inputs"))
    x0.update(_numbers(settings.get("x0", {}), f"{where}: graph.x0"))
    if settings.get("t_end") is None and any(spec.t_end for spec in parts.values()):
        settings = {**settings, "t_end": max(spec.t_end for spec in parts.values() if spec.t_end)}
    calibration = settings.get("calibration", {})
    if not isinstance(calibration, dict):
        raise ModelFileError(f"{where}: graph.calibration must be an object, got {type(calibration).__name__}")
    spec = _spec(model, inputs, settings.get("t_end"), x0, where, "graph.")
    spec.calibration = calibration
    return spec


def _parts(settings: Mapping, where: str, folder: Path | None, files: tuple) -> dict[str, ModelSpec]:
    """The sub-models ``graph.parts`` names: part name -> the JSON file's model, read relative to ``folder``."""
    parts = settings.get("parts")
    if parts is None:
        if "connections" in settings:
            raise ModelFileError(f"{where}: graph.connections without graph.parts")
        return {}
    if not isinstance(parts, dict) or not parts:
        raise ModelFileError(f"{where}: graph.parts must map part names to model files, got {parts!r}")
    if folder is None:
        raise ModelFileError(f"{where}: graph.parts names files; read the model with load_model (or give "
                             "model_from_json a folder)")
    if len(files) > MAX_PART_DEPTH:
        raise ModelFileError(f"{where}: parts nest deeper than {MAX_PART_DEPTH} files (bondgraph.io.MAX_PART_DEPTH)")
    specs = {}
    for part, file in parts.items():
        at = f"{where}: graph.parts[{part!r}]"
        if not isinstance(file, str) or not file.lower().endswith(".json"):
            raise ModelFileError(f"{at}: a part is a JSON model file (a part is data, never code), got {file!r}")
        path = folder / file
        if path.resolve() in files:
            chain = " -> ".join([*(str(f.name) for f in files), path.name])
            raise ModelFileError(f"{at}: {file} includes itself ({chain})")
        if not path.is_file():
            raise ModelFileError(f"{at}: no such file {str(path)!r}")
        specs[part] = _from_json_file(path, files)
    return specs


def _composed(parts: Mapping[str, ModelSpec], settings: Mapping, where: str) -> BondGraph | None:
    """The parts bonded as ``graph.connections`` says, or None without parts."""
    if not parts:
        return None
    connections = settings.get("connections", [])
    if not isinstance(connections, list):
        raise ModelFileError(f"{where}: graph.connections must be a list of [port, port] pairs")
    try:
        return compose({part: spec.model for part, spec in parts.items()}, connections)
    except ModelError as exc:
        raise ModelFileError(f"{where}: {str(exc).replace('compose: ', 'graph.', 1)}") from None


def _ports(ports, graph: nx.DiGraph, parts: Mapping[str, ModelSpec], where: str) -> dict:
    """``graph.ports``: port name -> a node of the file, or ``"part.port"``, a port of one of its parts."""
    if not isinstance(ports, dict):
        raise ModelFileError(f"{where}: graph.ports must map port names to junction nodes, got {ports!r}")
    resolved = {}
    for port, target in ports.items():
        if isinstance(target, str) and target not in graph and parts:
            part, _, name = target.partition(".")
            inner = parts[part].model.ports if part in parts else {}
            if name not in inner:
                raise ModelFileError(f"{where}: graph.ports[{port!r}]: {target!r} is neither a node nor a port "
                                     "'part.port' of a part")
            target = path(part, inner[name])
        resolved[port] = target
    return resolved


def to_json(bg: BondGraph, *, inputs: Mapping | None = None, t_end: float | None = None, x0: Mapping | None = None,
            calibration: Mapping | None = None, indent: int | None = 1) -> str:
    """The node-link JSON of a bond graph that :func:`model_from_json` reads back.

    Laws and moduli are written as strings.  An input is stored as a number, or as the text of an
    expression of ``t`` (an :class:`~bondgraph.inputs.InputExpression`, or a string, which is parsed
    first); any other function of time (a Python function, a table, a controller) cannot be stored.
    ``calibration`` (JSON data, finite numbers only) is stored as ``graph.calibration``.

    Examples
    --------
    >>> import json
    >>> from bondgraph.library import rlc_circuit
    >>> text = to_json(rlc_circuit(), inputs={"V": 1.0}, t_end=0.5)
    >>> json.loads(text)["graph"]["inputs"]
    {'V': 1.0}
    >>> back = model_from_json(text)
    >>> back.model.parameters == rlc_circuit().parameters, back.inputs, back.t_end
    (True, {'V': 1.0}, 0.5)
    >>> json.loads(to_json(rlc_circuit(), inputs={"V": "5 + sin(7*t)"}))["graph"]["inputs"]
    {'V': '5 + sin(7*t)'}
    >>> model_from_json(to_json(rlc_circuit(), calibration={"method": "least squares"})).calibration
    {'method': 'least squares'}
    """
    require_model(bg, "to_json")
    graph_settings: dict = {"name": bg.name}
    if inputs:
        graph_settings["inputs"] = {str(k): _stored_input(k, v) for k, v in inputs.items()}
    if x0:
        bad = [k for k, v in x0.items() if callable(v)]
        if bad:
            raise ModelError(f"to_json: x0 {bad} are functions; only numbers can be stored in JSON")
        graph_settings["x0"] = {str(k): float(v) for k, v in x0.items()}
    if t_end is not None:
        graph_settings["t_end"] = float(t_end)
    if calibration is not None:
        graph_settings["calibration"] = _json_data(calibration, "to_json: calibration")
    if bg.ports:
        graph_settings["ports"] = bg.ports
    nodes = []
    for name, data in bg.graph.nodes(data=True):
        node = {"id": name}
        for key, value in data.items():
            if key not in NODE_FIELDS:
                continue
            if isinstance(value, sp.Basic):
                value = str(value)
            elif isinstance(value, tuple):
                value = list(value)
            node[key] = value
        nodes.append(node)
    links = []
    for tail, head, data in bg.graph.edges(data=True):
        link = {"source": tail, "target": head}
        if data.get("label") is not None:
            link["label"] = data["label"]
        links.append(link)
    return json.dumps({"directed": True, "multigraph": False, "graph": graph_settings, "nodes": nodes,
                       "links": links}, indent=indent, allow_nan=False)


# ------------------------------------------------------------------------------------------- helpers

def _list(data: dict, key: str, where: str) -> list:
    value = data.get(key)
    if not isinstance(value, list):
        raise ModelFileError(f"{where}: '{key}' must be a list" + ("" if key in data else " (missing)"))
    return value


def _node_id(value, where: str, key: str = "id"):
    if isinstance(value, bool) or not isinstance(value, (str, int)):
        raise ModelFileError(f"{where}: '{key}' must be a string or an integer, got {value!r}")
    if isinstance(value, str) and not value.strip():
        raise ModelFileError(f"{where}: '{key}' is empty")
    try:
        return check_node_id(value, where=where, what=f"'{key}'")
    except ModelError as exc:
        raise ModelFileError(str(exc)) from None


def _add_node(graph: nx.DiGraph, node, where: str) -> None:
    if not isinstance(node, dict):
        raise ModelFileError(f"{where}: expected an object, got {type(node).__name__}")
    if "id" not in node:
        raise ModelFileError(f"{where}: missing 'id'")
    name = _node_id(node["id"], where)
    where = f"{where} ({name!r})"
    bad = set(node) - NODE_FIELDS
    if bad:
        raise ModelFileError(f"{where}: unknown field(s) {sorted(bad)} (allowed: {sorted(NODE_FIELDS - {'id'})})")
    if name in graph:
        raise ModelFileError(f"{where}: duplicate node id {name!r}")
    attributes = {k: v for k, v in node.items() if k != "id"}
    for key in ("law", "modulus"):  # strings only: parsed safely by the model, never evaluated
        if key in attributes and not isinstance(attributes[key], str):
            raise ModelFileError(f"{where}: '{key}' must be a string expression, got {type(attributes[key]).__name__}")
    for key in ("param", "signal", "domain"):
        if key in attributes and not isinstance(attributes[key], str):
            raise ModelFileError(f"{where}: '{key}' must be a string, got {attributes[key]!r}")
    if "domains" in attributes and not isinstance(attributes["domains"], dict):
        raise ModelFileError(f"{where}: 'domains' must map law constants to a domain name")
    for key in ("value", "stiffness"):
        if key in attributes and (isinstance(attributes[key], bool) or not isinstance(attributes[key], (int, float))):
            raise ModelFileError(f"{where}: '{key}' must be a number, got {attributes[key]!r}")
    if "uncertainty" in attributes:
        attributes["uncertainty"] = _pair(attributes["uncertainty"], f"{where}: 'uncertainty'")
    if "params" in attributes:
        attributes["params"] = _numbers(attributes["params"], f"{where}: 'params'")
    if "uncertainties" in attributes:
        raw = attributes["uncertainties"]
        if not isinstance(raw, dict):
            raise ModelFileError(f"{where}: 'uncertainties' must map law constants to [lo, hi]")
        attributes["uncertainties"] = {k: _pair(v, f"{where}: 'uncertainties' of {k!r}") for k, v in raw.items()}
    graph.add_node(name, **attributes)


def _add_link(graph: nx.DiGraph, link, where: str) -> None:
    if not isinstance(link, dict):
        raise ModelFileError(f"{where}: expected an object with 'source' and 'target', got {type(link).__name__}")
    bad = set(link) - LINK_FIELDS
    if bad:
        raise ModelFileError(f"{where}: unknown field(s) {sorted(bad)} (allowed: {sorted(LINK_FIELDS)})")
    for key in ("source", "target"):
        if key not in link:
            raise ModelFileError(f"{where}: missing '{key}'")
    tail, head = _node_id(link["source"], where, "source"), _node_id(link["target"], where, "target")
    where = f"{where} ({tail!r} -> {head!r})"
    for node in (tail, head):
        if node not in graph:
            raise ModelFileError(f"{where}: node {node!r} is not in 'nodes'")
    if graph.has_edge(tail, head):
        raise ModelFileError(f"{where}: duplicate bond")
    attributes = {}
    if link.get("label") is not None:
        attributes["label"] = _node_id(link["label"], where, "label")
    graph.add_edge(tail, head, **attributes)


def _number(value, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelFileError(f"{where}: expected a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ModelFileError(f"{where}: {value!r} is not finite")
    return number


def _positive(value, where: str) -> float:
    number = _number(value, where)
    if number <= 0:
        raise ModelFileError(f"{where}: must be positive, got {value!r}")
    return number


def _numbers(value, where: str) -> dict:
    if not isinstance(value, dict):
        raise ModelFileError(f"{where}: expected an object of name -> number, got {type(value).__name__}")
    return {str(k): _number(v, f"{where}[{k!r}]") for k, v in value.items()}


def _input_values(value, where: str) -> dict:
    """``graph.inputs``: signal -> a number or an expression of ``t`` (an error names the file and the input)."""
    if not isinstance(value, dict):
        raise ModelFileError(f"{where}: expected an object of input signal -> number or expression of t, got "
                             f"{type(value).__name__}")
    out = {}
    for name, given in value.items():
        at = f"{where}[{name!r}]"
        if isinstance(given, str):
            out[str(name)] = InputExpression(given, where=at)  # a LawError naming the file and the input
        elif isinstance(given, bool) or not isinstance(given, (int, float)):
            raise ModelFileError(f"{at}: expected a number or the text of an expression of t, got {given!r}")
        else:
            out[str(name)] = _number(given, at)
    return out


def _stored_input(name, value):
    """An input as :func:`to_json` writes it: a number or an expression's text."""
    if isinstance(value, str):
        value = InputExpression(value, where=f"to_json: inputs[{name!r}]")
    if isinstance(value, InputExpression):
        return value.text
    if callable(value) or hasattr(value, "derivative"):
        raise ModelError(f"to_json: inputs[{name!r}] is a {type(value).__name__}; only a number or an expression "
                         "of t (bondgraph.inputs.InputExpression) can be stored in JSON")
    return float(value)


def _json_data(value: Mapping, where: str) -> dict:
    """``value`` as plain JSON data (a copy), refused with a ModelError if it holds anything else or a NaN."""
    if not isinstance(value, Mapping):
        raise ModelError(f"{where} must be a mapping, got {type(value).__name__}")
    try:
        return json.loads(json.dumps(dict(value), allow_nan=False))
    except (TypeError, ValueError) as exc:
        raise ModelError(f"{where}: not JSON data with finite numbers ({exc})") from None


def _pair(value, where: str) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise ModelFileError(f"{where}: expected [lo, hi], got {value!r}")
    return (_number(value[0], where), _number(value[1], where))


def _no_constant(where: str) -> Callable:
    def refuse(name: str):
        raise ModelFileError(f"{where}: {name} is not a finite number (JSON has no NaN or Infinity)")
    return refuse


def _finite_float(where: str) -> Callable:
    def parse(text: str) -> float:
        number = float(text)
        if not math.isfinite(number):
            raise ModelFileError(f"{where}: number {text[:40]} overflows")
        return number
    return parse


def _from_bgt(path: Path) -> ModelSpec:
    """A BondGraphTools file: its model, no run settings (it holds none)."""
    from .bgt_format import BGTFileError, read_bgt   # here: it needs PyYAML, which only .bg files do

    try:
        return ModelSpec(read_bgt(path), source=str(path))
    except BGTFileError as exc:
        raise ModelFileError(str(exc)) from None


def _from_python(path: Path, attribute: str | None) -> ModelSpec:
    try:
        namespace = runpy.run_path(str(path), run_name="__bgphm_model__")
    except SyntaxError as exc:
        raise ModelFileError(f"{path} line {exc.lineno}: {exc.msg}") from None
    except ModelError as exc:
        raise ModelFileError(f"{path}: {exc}") from None
    except ImportError as exc:
        raise ModelFileError(f"{path}: {exc}") from None
    candidate = _pick(namespace, path, attribute)
    if not isinstance(candidate, BondGraph):
        try:
            candidate = candidate()
        except ModelError as exc:
            raise ModelFileError(f"{path}: {exc}") from None
        if not isinstance(candidate, BondGraph):
            raise ModelFileError(f"{path}: {attribute or 'model'}() returned {type(candidate).__name__}, "
                                 f"not a BondGraph")
    inputs = namespace.get("inputs", {})
    if not isinstance(inputs, Mapping):
        raise ModelFileError(f"{path}: 'inputs' must be a dict of input signal -> value or function")
    # a text is an expression of t, as in a JSON file
    inputs = {k: InputExpression(v, where=f"{path}: inputs[{k!r}]") if isinstance(v, str) else v
              for k, v in inputs.items()}
    return _spec(candidate, inputs, namespace.get("t_end"), namespace.get("x0", {}), str(path), "")


def _spec(model: BondGraph, inputs: Mapping, t_end, x0: Mapping, source: str, prefix: str) -> ModelSpec:
    """The run settings checked against the model (``prefix`` locates them in the file: ``graph.`` in JSON)."""
    unknown = sorted(set(inputs) - set(model.inputs))
    if unknown:
        raise ModelFileError(f"{source}: {prefix}inputs names {unknown}, which are not input signals of the model "
                             f"({model.inputs})")
    if t_end is not None:
        t_end = _positive(t_end, f"{source}: {prefix}t_end")
    return ModelSpec(model, dict(inputs), t_end, dict(x0), source)


def _pick(namespace: dict, path: Path, attribute: str | None):
    if attribute:
        if attribute not in namespace:
            raise ModelFileError(f"{path}: defines no {attribute!r}")
        found = namespace[attribute]
        if not (isinstance(found, BondGraph) or callable(found)):
            raise ModelFileError(f"{path}: {attribute!r} is a {type(found).__name__}, not a bond graph or a function")
        return found
    if "model" in namespace:
        found = namespace["model"]
        if isinstance(found, BondGraph) or callable(found):
            return found
        raise ModelFileError(f"{path}: 'model' is a {type(found).__name__}, not a BondGraph or a function")
    graphs = [k for k, v in namespace.items() if isinstance(v, BondGraph) and not k.startswith("_")]
    if len(graphs) == 1:
        return namespace[graphs[0]]
    functions = [k for k, v in namespace.items() if callable(v) and getattr(v, "__module__", None) == "__bgphm_model__"
                 and not k.startswith("_") and not isinstance(v, type)]
    if not graphs and len(functions) == 1:
        return namespace[functions[0]]
    found = graphs or functions
    raise ModelFileError(f"{path}: define 'model' (a BondGraph or a function returning one)"
                         + (f"; found several candidates {sorted(found)}: pick one with {path}:NAME" if found else ""))
