"""BondGraphTools ``.bg`` files: read them as our bond graphs, and write our linear models as them.

BondGraphTools (Cudmore et al. (2019)) saves a model as YAML: ``version`` (``0.1``), ``root`` (the
model's name) and ``models``, keyed by a path (``/`` is the top; ``/sub`` or any other key a
sub-model).  Each model lists ``components`` as lines ``name template [value] [param=value ...]``
(``R1 base/R r=100``, ``C1 base/C 10``; a template that is a key of ``models`` nests that model), a
``netlist`` of bonds ``tail head`` between component ports (``kvl.inverting``, ``T.0``; a bare name
for a one-port or a 0-junction) and ``ports`` (``pout A``: the source-sensor ``pout`` is the
sub-model's port ``A``, bonded in the parent as ``sub.A``).

The mapping to our model contract (docs/design.md, section 2; docs/model.md, "BondGraphTools files"):

* ``base/R``, ``base/C``, ``base/I`` (parameters ``r``, ``C``, ``L``) are our R, C, I with the value as
  ``value``; ``base/Se``, ``base/Sf`` our sources (a number is their constant ``value``, a name their
  signal); ``base/0`` and ``base/1`` our junctions; ``base/TF`` (``r``) and ``base/GY`` (``R``) our
  two-ports.  A parameter the file omits takes BondGraphTools' library default (R, C: 1000, I: 2000,
  TF, GY: 1), as BondGraphTools' own loader does; a parameter given as a name has no value, which our
  models need, so it is refused.
* Every BondGraphTools port takes power in (a bond only says ``e`` is shared and the flows are
  opposite), and a 1-junction's ``inverting`` ports count with a minus sign.  Our bonds carry the power
  direction instead, so each bond is oriented: a 1-junction's ``non_inverting`` bonds enter it and its
  ``inverting`` bonds leave it (or all the other way round: that only changes the sign of the common
  flow), a two-port's port 0 bond enters it and its port 1 bond leaves it (or the other way round).
  With port 0 entering, BondGraphTools' ``e_1 = r e_0, f_0 = -r f_1`` is our TF of modulus ``1/r`` and
  its ``e_1 = -R f_0, e_0 = R f_1`` our GY of modulus ``-R``; entered at port 1 they are ``r`` and ``R``.
  Where these choices contradict each other (a loop of junctions and two-ports with an odd number of
  inversions, or two ``non_inverting`` ports bonded together) the bond gets a 0-junction of two bonds,
  ``<tail>_<head>``, which is exactly a BondGraphTools bond.  One-ports and 0-junctions take any
  direction (our one-port laws use the flow into the element).
* ``base/SS`` (a source-sensor) exposed as a sub-model's port and bonded in the parent disappears: the
  two bonds become one.  Elsewhere it needs one value: ``f=0`` makes it an effort sensor (our ``De``,
  on the 0-junction it is bonded to), ``e=0`` a flow sensor (``Df``, on a 1-junction), another ``e`` an
  effort source and another ``f`` a flow source; with neither it is an open port and is refused.
* Nested models are flattened: node ids, parameter and signal names are the instance paths joined by
  ``.`` (the instance ``sub`` of the model ``/sub`` gives ``sub.R1``, its parameter ``sub.R1``; nested twice
  ``a.b.R1``; states ``q_a.b.C1``), as :mod:`bondgraph.composition` names what it takes from a part.  A model
  may be used by several instances; a bond names a sub-model's port as ``sub.A``, or ``sub`` alone when it
  has one, and may join two sub-models' ports (``a.A b.A``).
* Why not :func:`bondgraph.composition.compose`: its ports are junctions, where a bond *to* the port shares
  the junction's effort or flow; a BondGraphTools port is a source-sensor bonded to any component port
  (an R, a two-port's ``.1``, a 1-junction's ``inverting``), and the two bonds through it are *one* bond.
  Read through ``compose``, each port would need a 0-junction on each side (``<sub>.<port>``), nodes no
  BondGraphTools model has; the orientation of a bond (above) depends on junctions and two-ports in
  several models at once, so it is decided once over the whole flattened model; and ``compose`` prefixes
  every part, where the top model's own components keep their names.  So a file is flattened here, into
  the same names ``compose`` gives.
* Anything else (the biochemical ``Ce``, ``Re``, port-Hamiltonian or custom components) is refused with
  a :class:`BGTFileError` naming the file, the model path, the component and its line.

:func:`write_bgt` writes a composed model (dotted node ids) nested, one BondGraphTools model per path
prefix, a port at every level a bond between parts leaves, so that ``read_bgt`` gives back its names.

The file is parsed with ``yaml.safe_load`` only (PyYAML, the ``bgt`` extra): no Python object is ever
built from it.  Before anything is built, a file larger than :data:`MAX_FILE_BYTES` is
refused, and so is a flattened model of more than :data:`MAX_NODES` components or
:data:`MAX_LINKS` bonds (a sub-model used many times multiplies).

Example
-------
>>> from bondgraph.library import rlc_circuit
>>> text = write_bgt(rlc_circuit())
>>> print(text)  # doctest: +NORMALIZE_WHITESPACE
version: '0.1'
root: series RLC circuit
models:
  /:
    components:
    - V base/Se
    - J1 base/1
    - R base/R r=10.0
    - L base/I L=0.1
    - J0 base/0
    - C base/C C=0.001
    - i base/SS e=0
    - v_C base/SS f=0
    netlist:
    - V J1.non_inverting
    - J1.inverting R
    - J1.inverting L
    - J1.inverting J0
    - J0 C
    - J1.inverting i
    - J0 v_C
<BLANKLINE>
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import networkx as nx
import sympy as sp

from . import elements as el
from .errors import ModelError
from .file_text import read_limited
from .model import BondGraph
from .names import PATH_SEPARATOR, is_name
from .optional import import_optional
from .structure import require_model

__all__ = ["BGT_VERSION", "BGT_KINDS", "BGTFileError", "MAX_FILE_BYTES", "MAX_NODES", "MAX_LINKS", "read_bgt",
           "model_from_bgt", "write_bgt"]

#: The file format version BondGraphTools writes and reads.
BGT_VERSION = "0.1"

#: BondGraphTools' base components we read: template -> (our kind, its parameters in positional order).
BGT_KINDS = {
    "R": ("R", ("r",)), "C": ("C", ("C",)), "I": ("I", ("L",)), "Se": ("Se", ("e",)), "Sf": ("Sf", ("f",)),
    "TF": ("TF", ("r",)), "GY": ("GY", ("R",)), "0": ("0", ()), "1": ("1", ()), "SS": ("SS", ("e", "f")),
}
#: BondGraphTools' library defaults (components/base.json), used when a file omits the value.
_DEFAULTS = {"R": 1000.0, "C": 1000.0, "I": 2000.0, "TF": 1.0, "GY": 1.0}
#: The largest ``.bg`` file (bytes), and the most components and bonds once sub-models are expanded: the
#: limits of JSON model files (:mod:`bondgraph.io`, which imports this module, so they are repeated here).
MAX_FILE_BYTES = 8 * 2**20
MAX_NODES = 10_000
MAX_LINKS = 20_000
_TOP_FIELDS = frozenset({"version", "root", "models"})
_MODEL_FIELDS = frozenset({"components", "netlist", "ports"})
_MAX_DEPTH = 32
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")




class BGTFileError(ModelError):
    """A ``.bg`` file that cannot be read: the message names the file, the model and the item at fault."""


# ------------------------------------------------------------------------------------------- reading

def read_bgt(source: str | Path, *, text: str | None = None) -> BondGraph:
    """Read a BondGraphTools ``.bg`` file (or its ``text``) as our bond graph.

    Parameters
    ----------
    source : str or Path
        The file; with ``text`` given, only the name used in messages.
    text : str, optional
        The file's content, when it is not on disk.

    Returns
    -------
    BondGraph
        The flattened model (module docstring).  A ``.bg`` file holds no run settings (inputs, horizon,
        initial state); :func:`bondgraph.io.load_model` reads it as a ``ModelSpec`` without them.

    Raises
    ------
    BGTFileError
        Naming the file, the model path and the component, bond or field at fault (and its line).
    ImportError
        Without PyYAML: ``pip install 'bondgraph-phm[bgt]'``.

    Examples
    --------
    The YAML is read by PyYAML; :func:`model_from_bgt` takes the data it gives:

    >>> data = {"version": 0.1, "root": "RC", "models": {"/": {
    ...     "components": ["Sf base/Sf", "kcl base/0", "R1 base/R r=100", "C1 base/C 0.01"],
    ...     "netlist": ["Sf kcl", "R1 kcl", "C1 kcl"]}}}
    >>> print(model_from_bgt(data, where="rc.bg").state_equations())
    dq_C1/dt = Sf(t) - q_C1/(C1*R1)
    """
    where = str(source)
    if text is None:
        text = read_limited(Path(source), limit=MAX_FILE_BYTES, error=BGTFileError, what="model file",
                            constant="bondgraph.bgt_format.MAX_FILE_BYTES")
    if not isinstance(text, str):
        raise TypeError(f"read_bgt: text must be a str, got {type(text).__name__}")
    if len(text) > MAX_FILE_BYTES:
        raise BGTFileError(f"{where}: {len(text)} characters, longer than the limit of {MAX_FILE_BYTES} for a "
                             "model file (bondgraph.bgt_format.MAX_FILE_BYTES)")
    yaml = import_optional("yaml", "PyYAML is needed to read BondGraphTools files: pip install 'bondgraph-phm[bgt]'")
    try:
        data = yaml.safe_load(text)   # plain data only: no tags that build Python objects
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" line {mark.line + 1} column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "invalid"
        raise BGTFileError(f"{where}{at}: not valid YAML ({problem})") from None
    except RecursionError:
        raise BGTFileError(f"{where}: YAML nested too deeply") from None
    return model_from_bgt(data, where=where, text=text)


def model_from_bgt(data: object, *, where: str = "BondGraphTools model", text: str = "") -> BondGraph:
    """Build our model from the parsed content of a ``.bg`` file (see :func:`read_bgt`).

    ``text``, the file's content, only lets messages give the line of a component or bond.

    >>> model_from_bgt({"version": 0.2, "root": "x", "models": {}}, where="x.bg")
    Traceback (most recent call last):
    ...
    bondgraph.bgt_format.BGTFileError: x.bg: unknown BondGraphTools file version '0.2' (this reader knows 0.1)
    """
    if not isinstance(data, dict):
        raise BGTFileError(f"{where}: expected a YAML mapping with 'version', 'root' and 'models', got "
                             f"{type(data).__name__}")
    unknown = set(map(str, data)) - _TOP_FIELDS
    if unknown:
        raise BGTFileError(f"{where}: unknown top-level field(s) {sorted(unknown)} (expected version, root, models)")
    if "version" not in data:
        raise BGTFileError(f"{where}: missing 'version' (BondGraphTools writes {BGT_VERSION})")
    version = str(data["version"])
    if version != BGT_VERSION:
        raise BGTFileError(f"{where}: unknown BondGraphTools file version {version!r} (this reader knows "
                             f"{BGT_VERSION})")
    models = data.get("models")
    if not isinstance(models, dict) or not models:
        raise BGTFileError(f"{where}: 'models' must be a non-empty mapping of model path -> model"
                             + ("" if "models" in data else " (missing)"))
    root = data.get("root", "/")
    if not isinstance(root, (str, int, float)) or isinstance(root, bool):
        raise BGTFileError(f"{where}: 'root' must be the model's name, got {type(root).__name__}")
    top = "/" if "/" in models else str(root)   # BondGraphTools starts at '/'; its old example at 'root'
    if top not in models:
        raise BGTFileError(f"{where}: 'models' has no '/' (the top model) and no {str(root)!r} (the root)")
    flat = _Flattener({str(k): v for k, v in models.items()}, where, _Lines(text))
    flat.expand(top, "", ())
    graph = _Orienter(flat).graph(str(root))
    try:
        return BondGraph(graph)
    except ModelError as exc:
        raise BGTFileError(f"{where}: {exc}") from None


@dataclass
class _Atom:
    """One base component of the flattened model."""

    path: str
    kind: str                    # BGT_KINDS kind (SS kept until it is resolved)
    values: dict                 # BondGraphTools parameter -> float or a name
    where: str                   # "file: model '/load' component 'R1' (line 12)"
    ports_used: set = field(default_factory=set)


@dataclass(frozen=True)
class _End:
    """A bond's end: the component's path and its BondGraphTools port (None: a one-port's or a 0-junction's)."""

    path: str
    port: object = None


class _Lines:
    """Where an item is written in the file: the first line after the model's key that holds it.

    The lines are indexed once, so that a file of many components costs one pass, not one per item.
    """

    def __init__(self, text: str):
        self.keys: dict[str, int] = {}
        self.items: dict[str, list[int]] = {}
        for number, raw in enumerate(text.splitlines() if text else [], 1):
            line = raw.split("#")[0].strip()
            if line.endswith(":") and not line.startswith("-"):
                self.keys.setdefault(line[:-1].strip().strip("'\""), number)
            elif line.startswith("-"):
                self.items.setdefault(" ".join(line[1:].split()).strip("'\""), []).append(number)

    def of(self, key: str, item: str) -> str:
        start = self.keys.get(key, 0)
        lines = self.items.get(" ".join(item.split()), [])
        found = next((n for n in lines if n > start), None)
        return f" (line {found})" if found is not None else ""


class _Flattener:
    """Expands the model tree into atoms and bonds between atom ends, sub-model ports spliced."""

    def __init__(self, models: dict, where: str, lines: _Lines):
        self.models, self.file, self.lines = models, where, lines
        self.atoms: dict[str, _Atom] = {}
        self.bonds: list[tuple[_End, _End, str]] = []
        self.exposed: set[str] = set()         # SS paths exposed as a port of their model
        self.instances = 0                     # models expanded: bounded even when they hold no component

    def expand(self, key: str, prefix: str, stack: tuple) -> dict:
        """Add model ``key``'s content under ``prefix``; return its ports: label -> the SS path behind it."""
        at = f"{self.file}: model {key!r}" + (f" (as {prefix[:-1]!r})" if prefix else "")   # a model may be reused
        if key in stack:
            raise BGTFileError(f"{at}: contains itself (through {' -> '.join(stack + (key,))})")
        if len(stack) >= _MAX_DEPTH:
            raise BGTFileError(f"{at}: models nested more than {_MAX_DEPTH} deep")
        self.instances += 1
        if self.instances > MAX_NODES:
            raise BGTFileError(f"{at}: more than {MAX_NODES} model instances once sub-models are expanded "
                               "(bondgraph.bgt_format.MAX_NODES)")
        body = self.models[key]
        if not isinstance(body, dict):
            raise BGTFileError(f"{at}: expected a mapping with 'components' and 'netlist', got {type(body).__name__}")
        bad = set(map(str, body)) - _MODEL_FIELDS
        if bad:
            raise BGTFileError(f"{at}: unknown field(s) {sorted(bad)} (expected components, netlist, ports)")
        local: dict[str, object] = {}   # component name -> its path (atom) or its ports (sub-model)
        for line in _strings(body, "components", at, required=True):
            self._component(key, prefix, stack, line, local, at)
        for line in _strings(body, "netlist", at):
            self._bond(key, line, local, at)
        ports = {}
        for line in _strings(body, "ports", at):
            where = f"{at} port {line!r}{self.lines.of(key, line)}"
            tokens = line.split()
            if len(tokens) != 2:
                raise BGTFileError(f"{where}: expected 'component label'")
            name, label = tokens
            atom = self.atoms.get(local.get(name)) if isinstance(local.get(name), str) else None
            if atom is None or atom.kind != "SS":
                raise BGTFileError(f"{where}: {name!r} is not a source-sensor (base/SS) of this model")
            if label in ports:
                raise BGTFileError(f"{where}: port {label!r} is exposed twice")
            ports[label] = atom.path
            self.exposed.add(atom.path)
        return ports

    def _component(self, key: str, prefix: str, stack: tuple, line: str, local: dict, at: str) -> None:
        where = f"{at} component {line!r}{self.lines.of(key, line)}"
        tokens = line.split()
        if len(tokens) < 2:
            raise BGTFileError(f"{where}: expected 'name template [values]'")
        name, template, args = tokens[0], tokens[1], tokens[2:]
        if name in local:
            raise BGTFileError(f"{where}: a second component named {name!r}")
        if "." in name:
            raise BGTFileError(f"{where}: a component name cannot hold '.' (it separates a port)")
        path = f"{prefix}{name}"
        if template in self.models:
            if args:
                raise BGTFileError(f"{where}: a sub-model takes no values")
            local[name] = self.expand(template, f"{path}.", stack + (key,))
            return
        library, _, component = template.rpartition("/")
        if library != "base" or component not in BGT_KINDS:
            raise BGTFileError(f"{where}: {template!r} is neither a model of this file nor a base component we "
                                 f"can represent (base/{', base/'.join(BGT_KINDS)})")
        if len(self.atoms) >= MAX_NODES:
            raise BGTFileError(f"{where}: more than {MAX_NODES} components once sub-models are expanded "
                                 "(bondgraph.bgt_format.MAX_NODES)")
        kind, names = BGT_KINDS[component]
        self.atoms[path] = _Atom(path, kind, _values(args, names, where), where)
        local[name] = path

    def _bond(self, key: str, line: str, local: dict, at: str) -> None:
        where = f"{at} bond {line!r}{self.lines.of(key, line)}"
        tokens = line.split()
        if len(tokens) != 2:
            raise BGTFileError(f"{where}: expected 'tail head'")
        if len(self.bonds) >= MAX_LINKS:
            raise BGTFileError(f"{where}: more than {MAX_LINKS} bonds once sub-models are expanded "
                                 "(bondgraph.bgt_format.MAX_LINKS)")
        tail, head = (self._end(token, local, where) for token in tokens)
        self.bonds.append((tail, head, where))

    def _end(self, token: str, local: dict, where: str) -> _End:
        name, dot, port = token.partition(".")
        if name not in local:
            raise BGTFileError(f"{where}: no component {name!r} in this model")
        target = local[name]
        if isinstance(target, dict):   # a sub-model: its exposed port
            if not dot and len(target) == 1:
                port = next(iter(target))
            if port not in target:
                raise BGTFileError(f"{where}: sub-model {name!r} has no port {port!r} (its ports: "
                                     f"{sorted(target)})")
            return _End(target[port])
        atom = self.atoms[target]
        port = _port(atom, port if dot else None, where)
        if atom.kind not in ("0", "1"):   # a junction's ports multiply; a component's are bonded once
            if port in atom.ports_used:
                raise BGTFileError(f"{where}: port {token!r} is bonded twice")
            atom.ports_used.add(port)
        return _End(target, port)


def _strings(body: dict, key: str, at: str, *, required: bool = False) -> list[str]:
    items = body.get(key)
    if items is None:
        if required:
            raise BGTFileError(f"{at}: missing '{key}'")
        return []
    if not isinstance(items, list) or not all(isinstance(i, str) for i in items):
        raise BGTFileError(f"{at}: '{key}' must be a list of text lines")
    return items


def _values(args: list[str], names: tuple, where: str) -> dict:
    """``10`` / ``r=10`` / ``e=V_in`` -> {parameter: float or name}; never evaluated."""
    values: dict = {}
    positional = iter(names)
    for arg in args:
        key, eq, text = arg.partition("=")
        if not eq:
            key, text = next(positional, None), arg
            if key is None:
                raise BGTFileError(f"{where}: value {arg!r} is one too many "
                                     f"(parameters: {', '.join(names) or 'none'})")
        elif key not in names:
            raise BGTFileError(f"{where}: unknown parameter {key!r} (parameters: {', '.join(names) or 'none'})")
        if key in values:
            raise BGTFileError(f"{where}: parameter {key!r} given twice")
        if _NUMBER.fullmatch(text):
            number = float(text)
            if not math.isfinite(number):
                raise BGTFileError(f"{where}: parameter {key!r} = {text} is not finite")
            values[key] = number
        elif is_name(text):
            values[key] = text
        else:
            raise BGTFileError(f"{where}: parameter {key!r} = {text!r} is neither a number nor a name")
    return values


def _port(atom: _Atom, port: str | None, where: str):
    """The BondGraphTools port a bond end names, checked against the component's kind."""
    if atom.kind == "1":
        if port not in ("inverting", "non_inverting"):
            raise BGTFileError(f"{where}: a 1-junction's bond names its port: {atom.path.rpartition('.')[2]}"
                                 ".inverting or .non_inverting")
        return port
    if atom.kind in ("TF", "GY"):
        if port not in ("0", "1"):
            raise BGTFileError(f"{where}: a two-port's bond names its port, .0 (primary) or .1 (secondary)")
        return int(port)
    if port not in (None, "0") and atom.kind != "0":
        raise BGTFileError(f"{where}: {atom.kind} {atom.path!r} has one port (0), not {port!r}")
    return None


class _Orienter:
    """Our directed graph for the flattened atoms and bonds (module docstring: the orientation)."""

    def __init__(self, flat: _Flattener):
        self.file, self.atoms = flat.file, flat.atoms
        self.bonds = self._splice(flat)
        self.parent: dict[str, tuple[str, int]] = {}   # parity union-find over 1-junctions and two-ports

    def _splice(self, flat: _Flattener) -> list:
        """Bonds through an exposed, bonded source-sensor joined into one.

        A bond may hold two such ports (``a.A b.A``: two sub-models bonded port to port), so the bonds a
        port touches are followed as they merge: the merged bond keeps the first index.
        """
        at_ss: dict[str, list[int]] = {}
        for index, (a, b, _) in enumerate(flat.bonds):
            for end in (a, b):
                if self.atoms[end.path].kind == "SS" and end.path in flat.exposed:
                    at_ss.setdefault(end.path, []).append(index)
        bonds = list(flat.bonds)
        for path, indices in at_ss.items():
            if len(indices) == 1:
                continue   # an exposed port nobody bonds: a boundary, resolved with the other SS
            if len(indices) > 2:
                raise BGTFileError(f"{flat.file}: port {path!r} is bonded {len(indices)} times; a port takes one "
                                     "bond inside its model and one outside")
            i, j = indices
            first, second = bonds[i], bonds[j]
            inner = first[1] if first[0].path == path else first[0]
            outer = second[1] if second[0].path == path else second[0]
            if inner.path == outer.path:
                raise BGTFileError(f"{second[2]}: port {path!r} is bonded to itself through a ring of ports")
            bonds[i] = (inner, outer, first[2])
            bonds[j] = None
            if outer.path in at_ss:   # the outer end is another port: its bond j is now bond i
                at_ss[outer.path] = [i if k == j else k for k in at_ss[outer.path]]
            del self.atoms[path]
        return [b for b in bonds if b is not None]

    # --- parity union-find: g(x) = g(root) * parity(x)
    def _find(self, node: str) -> tuple[str, int]:
        parity = 1
        while self.parent.get(node, (node, 1))[0] != node:
            node, step = self.parent[node]
            parity *= step
        return node, parity

    def _unite(self, a: str, b: str, relation: int) -> bool:
        """Require g(a) * g(b) == relation; False if that contradicts what is known."""
        (ra, pa), (rb, pb) = self._find(a), self._find(b)
        if ra == rb:
            return pa * pb == relation
        self.parent[rb] = (ra, relation * pa * pb)
        return True

    def _sign(self, end: _End) -> int | None:
        """+1 if the end must be a bond's head when its unit keeps its natural orientation, -1 its tail."""
        kind = self.atoms[end.path].kind
        if kind == "1":
            return 1 if end.port == "non_inverting" else -1
        if kind in ("TF", "GY"):
            return 1 if end.port == 0 else -1
        return None

    def graph(self, name: str) -> nx.DiGraph:
        sensors = self._sensor_bonds()
        split = []
        for index, (a, b, _) in enumerate(self.bonds):
            if index in sensors:
                continue
            sa, sb = self._sign(a), self._sign(b)
            if sa is not None and sb is not None and not self._unite(a.path, b.path, -sa * sb):
                split.append(index)
        graph = nx.DiGraph(name=name)
        for atom in self.atoms.values():
            graph.add_node(atom.path, **self._attributes(atom, sensors))
        for index, (a, b, where) in enumerate(self.bonds):
            if index in sensors:
                junction, sensor = sensors[index]
                graph.add_edge(junction, sensor)
            elif index in split:
                middle = self._free_id(graph, f"{a.path}_{b.path}")
                graph.add_node(middle, kind="0")
                for end in (a, b):
                    self._add(graph, end, _End(middle), where)
            else:
                self._add(graph, a, b, where)
        return graph

    def _add(self, graph: nx.DiGraph, a: _End, b: _End, where: str) -> None:
        tail, head = self._direction(a, b)
        if graph.has_edge(tail, head) or graph.has_edge(head, tail):
            raise BGTFileError(f"{where}: a second bond between {tail!r} and {head!r}, which our models (one bond "
                                 "per pair) cannot hold")
        graph.add_edge(tail, head)

    def _direction(self, a: _End, b: _End) -> tuple[str, str]:
        for end, other in ((a, b), (b, a)):
            sign = self._sign(end)
            if sign is not None:
                sign *= self._find(end.path)[1]
                return (other.path, end.path) if sign > 0 else (end.path, other.path)
        # both ends take either direction: sources give power, R, C and I take it, else as written
        if self.atoms[a.path].kind in ("R", "C", "I") or self.atoms[b.path].kind in ("Se", "Sf"):
            return b.path, a.path
        return a.path, b.path

    def _free_id(self, graph: nx.DiGraph, wanted: str) -> str:
        candidate, number = wanted, 1
        while candidate in graph or candidate in self.atoms:
            number += 1
            candidate = f"{wanted}_{number}"
        return candidate

    def _sensor_bonds(self) -> dict[int, tuple[str, str]]:
        """Source-sensors left as boundaries: sources, or sensors (bond index -> (junction, sensor))."""
        sensors = {}
        for index, (a, b, where) in enumerate(self.bonds):
            for end, other in ((a, b), (b, a)):
                atom = self.atoms[end.path]
                if atom.kind != "SS":
                    continue
                kind = _boundary_kind(atom)
                atom.kind = kind
                if kind in el.DETECTORS:
                    junction = self.atoms[other.path].kind
                    if junction != el.DETECTOR_JUNCTION[kind]:
                        raise BGTFileError(f"{atom.where}: a source-sensor with "
                                             f"{'f' if kind == 'De' else 'e'}=0 is our {kind}, which sits on a "
                                             f"{el.DETECTOR_JUNCTION[kind]}-junction, not on {junction} "
                                             f"{other.path!r}")
                    sensors[index] = (other.path, end.path)
        for atom in self.atoms.values():
            if atom.kind == "SS":
                raise BGTFileError(f"{atom.where}: a source-sensor without a bond")
        return sensors

    def _attributes(self, atom: _Atom, sensors: Mapping) -> dict:
        kind, values = atom.kind, atom.values
        if kind in ("0", "1"):
            return {"kind": kind}
        if kind in el.DETECTORS:
            return {"kind": kind, "signal": _name(atom.path)}
        if kind in ("Se", "Sf"):
            value = values.get("e" if kind == "Se" else "f")
            if isinstance(value, str):
                return {"kind": kind, "signal": value}
            attributes = {"kind": kind, "signal": _name(atom.path)}
            if value is not None:
                attributes["value"] = value
            return attributes
        value = values.get(BGT_KINDS[kind][1][0], _DEFAULTS[kind])
        if isinstance(value, str):
            raise BGTFileError(f"{atom.where}: parameter {value!r} has no value, and our models need a nominal "
                                 "value for every parameter")
        attributes = {"kind": kind, "value": value, "param": _name(atom.path)}
        if kind in ("TF", "GY") and self._find(atom.path)[1] > 0:   # entered at port 0
            attributes["modulus"] = f"1/{_name(atom.path)}" if kind == "TF" else f"-{_name(atom.path)}"
        return attributes


def _boundary_kind(atom: _Atom) -> str:
    """What a source-sensor that is no bonded port stands for (module docstring)."""
    given = {k: v for k, v in atom.values.items() if v is not None}
    if len(given) != 1:
        raise BGTFileError(f"{atom.where}: an open source-sensor needs exactly one of e= (an effort source; e=0: "
                             "a flow sensor) or f= (a flow source; f=0: an effort sensor)")
    (key, value), = given.items()
    if value == 0:
        atom.values = {}
        return "De" if key == "f" else "Df"
    atom.values = {key: value}
    return "Se" if key == "e" else "Sf"


def _name(path: str) -> str:
    """A path as a parameter or signal name: as it is (BondGraphTools names are free; ours are checked)."""
    return path


# ------------------------------------------------------------------------------------------- writing

def write_bgt(bg: BondGraph) -> str:
    """The ``.bg`` text of a linear bond graph, which :func:`read_bgt` and BondGraphTools read back.

    R, C, I, Se, Sf, TF, GY, the junctions and the detectors (a source-sensor with ``f=0`` or ``e=0``)
    are written; modulated elements and laws have no BondGraphTools base component and are refused, as
    are a TF or GY modulus other than the parameter (or ``1/p``, ``-p``).  What BondGraphTools cannot
    hold (uncertainties, units, parameter names other than the element's, bond labels, the model's own
    ports) is left out: a parameter is read back under its element's name.

    A model composed of parts (:func:`bondgraph.composition.compose`, node ids ``motor.R_a``) is written
    nested: each path prefix is a BondGraphTools model (``/motor``, ``/drive/motor``) holding the
    elements under it, and a bond between two parts goes through a source-sensor ``SS_<port>`` exposed
    as the port ``<port>`` of each model it leaves, which :func:`read_bgt` splices back into one bond.

    No YAML library is needed: the lines are plain ``name template value`` texts.

    Examples
    --------
    >>> from bondgraph.library import dc_motor
    >>> text = write_bgt(dc_motor())
    >>> [line.strip() for line in text.splitlines() if "GY" in line]
    ['- GY base/GY R=0.0389', '- 1_e.inverting GY.1', '- GY.0 1_m.non_inverting']

    A composed model: the part ``rc`` is the model ``/rc``, bonded through its port ``in``:

    >>> from bondgraph import BondGraph, compose
    >>> load = BondGraph(name="load")
    >>> _ = load.add("in", "0"), load.add("C", "C", value=1e-3), load.add("R", "R", value=50.0)
    >>> _ = load.bond("in", "C"), load.bond("in", "R"), load.port("in", "in")
    >>> source = BondGraph(name="source")
    >>> _ = source.add("U", "Se"), source.add("out", "1"), source.add("R", "R", value=1.0)
    >>> _ = source.bond("U", "out"), source.bond("out", "R"), source.port("out", "out")
    >>> print(write_bgt(compose({"supply": source, "rc": load}, [("supply.out", "rc.in")], name="RC")))
    ... # doctest: +NORMALIZE_WHITESPACE
    version: '0.1'
    root: RC
    models:
      /:
        components:
        - supply /supply
        - rc /rc
        netlist:
        - supply.out rc.in
      /supply:
        components:
        - U base/Se
        - out base/1
        - R base/R r=1.0
        - SS_out base/SS
        netlist:
        - U out.non_inverting
        - out.inverting R
        - out.inverting SS_out
        ports:
        - SS_out out
      /rc:
        components:
        - in base/0
        - C base/C C=0.001
        - R base/R r=50.0
        - SS_in base/SS
        netlist:
        - SS_in in
        - in C
        - in R
        ports:
        - SS_in in
    <BLANKLINE>
    """
    require_model(bg, "write_bgt")
    structure = bg.structure()
    power = {name: [b for b in structure.at[name] if not b.is_signal] for name in structure.elements}
    ports: dict[tuple, str] = {}
    kinds = {name: element.kind for name, element in structure.elements.items()}
    tree = _ModelTree()
    for name, element in structure.elements.items():
        key, leaf = _place(name)
        tree.add(key, leaf, _component_line(name, leaf, element, power[name], ports), name)
    for bond in structure.bonds:
        ends = [(node, _place(node)[0], _token(node, bond, kinds, ports)) for node in (bond.tail, bond.head)]
        common = _common(ends[0][1], ends[1][1])
        tokens = [tree.reach(key, token, common, leaving=node == bond.tail, node=node) for node, key, token in ends]
        tree.models[common]["netlist"].append(f"{tokens[0]} {tokens[1]}")
    lines = [f"version: '{BGT_VERSION}'", f"root: {_quoted(bg.name)}", "models:"]
    for key, body in tree.models.items():
        lines.append(f"  {key}:")
        for field_name in ("components", "netlist", "ports"):
            if body[field_name]:
                lines += [f"    {field_name}:"] + [f"    - {line}" for line in body[field_name]]
    return "\n".join(lines) + "\n"


def _place(node) -> tuple[str, str]:
    """The BondGraphTools model holding a node and its name there: ``a.b.R1`` -> (``/a/b``, ``R1``)."""
    *parts, leaf = str(node).split(PATH_SEPARATOR)
    return "/" + "/".join(parts), leaf


def _common(a: str, b: str) -> str:
    """The innermost model holding both models ``a`` and ``b``: where a bond between them is written."""
    shared = []
    for x, y in zip(a.strip("/").split("/"), b.strip("/").split("/")):
        if x != y or not x:
            break
        shared.append(x)
    return "/" + "/".join(shared)


class _ModelTree:
    """The nested models :func:`write_bgt` writes: model key -> components, netlist and ports lines."""

    def __init__(self):
        self.models: dict[str, dict[str, list[str]]] = {}
        self.names: dict[str, dict[str, str]] = {}    # model key -> component name -> what holds it

    def model(self, key: str) -> dict[str, list[str]]:
        """The model ``key``, created with its parents (each a component of the one above) if new."""
        if key not in self.models:
            if key != "/":
                parent, _, name = key.rpartition("/")
                self._name(parent or "/", name, f"the sub-model {key!r}")
                self.model(parent or "/")["components"].append(f"{name} {key}")
            self.models[key] = {"components": [], "netlist": [], "ports": []}
            self.names[key] = {}
        return self.models[key]

    def _name(self, key: str, name: str, holder: str) -> None:
        self.model(key)
        taken = self.names[key].get(name)
        if taken is not None and taken != holder:
            raise ModelError(f"write_bgt: {holder} and {taken} would both be {name!r} in the BondGraphTools "
                             f"model {key!r}")
        self.names[key][name] = holder

    def add(self, key: str, leaf: str, line: str, node) -> None:
        self._name(key, leaf, f"node {node!r}")
        self.model(key)["components"].append(line)

    def reach(self, key: str, token: str, target: str, *, leaving: bool, node) -> str:
        """``token`` of model ``key`` as seen from its ancestor ``target``, through one port per level.

        Each level gets a source-sensor bonded to the token (``leaving``: power flows from the token into
        it) and exposed as a port named after the node, so the bond keeps its direction across levels.
        """
        while key != target:
            body = self.model(key)
            label = _free(str(node).split(PATH_SEPARATOR)[-1], {p.split()[1] for p in body["ports"]})
            sensor = _free(f"SS_{label}", self.names[key])
            self._name(key, sensor, f"the port {label!r} of node {node!r}")
            body["components"].append(f"{sensor} base/SS")
            body["netlist"].append(f"{token} {sensor}" if leaving else f"{sensor} {token}")
            body["ports"].append(f"{sensor} {label}")
            parent, _, name = key.rpartition("/")
            key, token = parent or "/", f"{name}.{label}"
        return token


def _free(wanted: str, taken) -> str:
    """``wanted``, or ``wanted_2``, ``wanted_3``... if taken; never all digits (BondGraphTools reads those as
    port numbers)."""
    wanted = f"port_{wanted}" if wanted.isdigit() else wanted
    candidate, number = wanted, 1
    while candidate in taken:
        number += 1
        candidate = f"{wanted}_{number}"
    return candidate


def _component_line(name, leaf: str, element, bonds: list, ports: dict) -> str:
    kind, where = element.kind, f"write_bgt: {element.kind} {name!r}"
    if " " in str(name):
        raise ModelError(f"{where}: BondGraphTools names hold no space")
    if element.law is not None:
        raise ModelError(f"{where}: a law has no BondGraphTools base component (only linear R, C, I)")
    if kind in el.MODULATED_TWO_PORTS or kind in ("MSe", "MSf"):
        raise ModelError(f"{where}: modulated elements have no BondGraphTools base component")
    if kind in ("0", "1"):
        return f"{leaf} base/{kind}"
    if kind in el.DETECTORS:
        return f"{leaf} base/SS {'f' if kind == 'De' else 'e'}=0"
    if kind in el.SOURCES:
        key = "e" if kind == "Se" else "f"
        value = element.value if element.value is not None else (element.signal if element.signal != name else None)
        return f"{leaf} base/{kind}" + (f" {key}={_number(value)}" if value is not None else "")
    value = element.value
    key = BGT_KINDS[kind][1][0]
    if kind in ("TF", "GY"):
        ports.update(_two_port_ports(name, element, bonds, where))
    return f"{leaf} base/{kind} {key}={_number(value)}"


def _two_port_ports(name, element, bonds: list, where: str) -> dict:
    """The BondGraphTools port of each of a two-port's bonds, from its modulus (module docstring)."""
    p = sp.Symbol(str(element.param))
    modulus = sp.sympify(element.modulus)
    entering = next(b for b in bonds if b.head == name)
    leaving = next(b for b in bonds if b.tail == name)
    natural = 1 / p if element.kind == "TF" else -p   # entered at BondGraphTools port 0
    if sp.simplify(modulus - natural) == 0:
        return {(name, entering.label): "0", (name, leaving.label): "1"}
    if sp.simplify(modulus - p) == 0:
        return {(name, entering.label): "1", (name, leaving.label): "0"}
    raise ModelError(f"{where}: modulus {modulus} is not one BondGraphTools can write ({p}, "
                     f"{natural} or its parameter's value alone)")


def _token(node, bond, kinds: Mapping, ports: dict) -> str:
    """A bond's end in the netlist of the node's own model: its name there, and its port if it has several."""
    leaf = _place(node)[1]
    key = (node, bond.label)
    if key in ports:
        return f"{leaf}.{ports[key]}"
    if kinds[node] == "1":
        return f"{leaf}.{'non_inverting' if node == bond.head else 'inverting'}"
    return leaf


def _number(value) -> str:
    if isinstance(value, str):
        return value
    return repr(float(value))


def _quoted(text: str) -> str:
    if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_ .-]*", text or "") and not text.endswith(" "):
        return text
    return "'" + str(text).replace("'", "''") + "'"
