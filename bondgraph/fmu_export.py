"""A bond graph as an FMI 2.0 co-simulation FMU, for 20-sim, Dymola, OpenModelica, Simulink and the rest.

:func:`to_fmu` writes a self-contained FMU (Modelica Association (2014), the FMI 2.0 standard): a zip with

* ``modelDescription.xml``: FMI 2.0, co-simulation, the variables below, and ``<SourceFiles>`` so that a tool
  on another platform can build the binary itself;
* ``sources/<id>.c`` and ``sources/bondgraph_fmi2.h``: the model generated from
  :func:`~bondgraph.equations.state_equations` with sympy's C99 printer, the FMI 2.0 declarations and a
  co-simulation runtime written from the specification (no header of the standard copied);
* ``binaries/linux64/<id>.so``: those sources compiled here with the system C compiler (``$CC``, ``cc`` or
  ``gcc``).  Windows and macOS binaries are out of scope; a tool there builds the sources.

The FMU needs no Python at run time.  Its variables, all Real, in this order (the value references count
from 0):

* the model's parameters: causality ``parameter``, variability ``tunable`` (settable before initialization
  and between steps: a degrading parameter);
* the inputs (source and modulating signals): causality ``input``, held constant over a communication step;
* the states (``q_<C>``, ``p_<I>``): causality ``output``, ``initial="exact"`` (their start is the initial
  state, settable before initialization);
* the measured signals (the detectors): causality ``output``, computed from the states and inputs.

Each variable carries its unit where the model declares or implies one (a state's is its bond's effort, for an
I, or flow, for a C, times a second), defined in ``UnitDefinitions`` by its SI base exponents (and ``rad``);
a unit with a fractional exponent or a solid angle, which FMI 2.0 cannot write, is left out.  Each output
lists the inputs it reads at once (``ModelStructure``: none for a state; a sensor across a source reads it),
so that an importer knows which outputs feed through and which loops are algebraic.

``fmi2DoStep`` integrates the states with the embedded Runge-Kutta pair of Dormand and Prince (1980), 5(4)
with error control: the error of each state over a step is kept below ``tolerance`` times the largest
magnitude the state has reached plus ``0.01 * tolerance`` times its nominal value (the FMI 2.0 absolute
tolerance; the nominal value is the element's value, the state at unit effort or flow, or 1 under a law);
``fmi2SetupExperiment``'s tolerance, when given, replaces the exported one.  FMI 3.0 is not
written: its co-simulation differs in the instantiation, the variable types and the clocks, and no consumer
here needs it.

Examples
--------
The FMU's texts need no compiler (:func:`fmu_sources`); :func:`to_fmu` compiles them and writes the zip:

>>> from bondgraph.library import rlc_circuit
>>> files = fmu_sources(rlc_circuit(), "rlc")
>>> sorted(files)
['modelDescription.xml', 'sources/bondgraph_fmi2.h', 'sources/rlc.c']
>>> "fmi2DoStep" in files["sources/rlc.c"], 'causality="input"' in files["modelDescription.xml"]
(True, True)
"""

from __future__ import annotations

import hashlib
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path

import sympy as sp
from sympy.printing.c import C99CodePrinter

from ._fmi2_c import HEADER, HEADER_NAME, RUNTIME
from .equations import StateEquations
from .errors import FmuError
from .structure import T, require_model, signal_function
from .units import BASE, SECOND, Unit

__all__ = ["DEFAULT_STEP", "DEFAULT_TOLERANCE", "fmu_sources", "to_fmu"]

#: The communication step of the FMU's default experiment (s).
DEFAULT_STEP = 1e-3
#: The relative error per state over a step that the FMU's integrator keeps to by default.
DEFAULT_TOLERANCE = 1e-9
#: A fixed time stamp for the zip's entries, so that one model gives the same FMU bytes every time.
_ZIP_TIME = (2000, 1, 1, 0, 0, 0)


def to_fmu(bg, path: str | os.PathLike, *, inputs: Mapping | None = None, x0: Mapping | None = None,
           parameters: Mapping | None = None, step: float = DEFAULT_STEP, tolerance: float = DEFAULT_TOLERANCE,
           model_identifier: str | None = None, compiler: str | None = None) -> Path:
    """Write ``bg`` as an FMI 2.0 co-simulation FMU at ``path`` (see the module).

    Parameters
    ----------
    bg : BondGraph
    path : path-like
        The FMU to write, ending in ``.fmu``; written whole or not at all.
    inputs : mapping, optional
        Input signal -> start value (default: the source's constant ``value``, else 0).
    x0 : mapping, optional
        Initial state by state (``q_C``) or element (``C``) name (default 0).
    parameters : mapping, optional
        Parameter -> start value, overriding the nominal values.
    step : float
        The default experiment's communication step (s); an importer may take any other.
    tolerance : float
        The integrator's relative tolerance per state (see the module).
    model_identifier : str, optional
        The C identifier naming the binary and the sources (default: the file name's stem made an identifier).
    compiler : str, optional
        The C compiler (default: ``$CC``, else ``cc``, else ``gcc``).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    FmuError
        Naming what is wrong: the path, an input, state or parameter, an expression the C printer cannot
        write, a missing compiler or a failed compilation.

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> to_fmu(rlc_circuit(), "rlc.zip")
    Traceback (most recent call last):
    ...
    bondgraph.errors.FmuError: to_fmu: path 'rlc.zip' must end in .fmu
    """
    require_model(bg, "to_fmu")
    path = Path(path)
    if path.suffix.lower() != ".fmu":
        raise FmuError(f"to_fmu: path {str(path)!r} must end in .fmu")
    if not path.parent.is_dir():
        raise FmuError(f"to_fmu: the folder of path {str(path)!r} does not exist")
    identifier = model_identifier if model_identifier is not None else _identifier(path.stem)
    files = fmu_sources(bg, identifier, inputs=inputs, x0=x0, parameters=parameters, step=step,
                        tolerance=tolerance)
    cc = _compiler(compiler)
    if not (sys.platform.startswith("linux") and platform.machine().lower() in ("x86_64", "amd64")):
        raise FmuError(f"to_fmu builds binaries/linux64 only; this machine is {sys.platform} {platform.machine()} "
                       "(fmu_sources gives the sources to build there)")
    with tempfile.TemporaryDirectory(prefix="bondgraph-fmu-") as work:
        binary = _compiled(files, identifier, Path(work), cc)
        _write_zip(path, files, {f"binaries/linux64/{identifier}.so": binary})
    return path


def fmu_sources(bg, model_identifier: str, *, inputs: Mapping | None = None, x0: Mapping | None = None,
                parameters: Mapping | None = None, step: float = DEFAULT_STEP,
                tolerance: float = DEFAULT_TOLERANCE) -> dict[str, str]:
    """The texts of the FMU :func:`to_fmu` writes, by their path in the zip, without a compiler.

    ``modelDescription.xml``, ``sources/bondgraph_fmi2.h`` and ``sources/<model_identifier>.c``; the options
    are :func:`to_fmu`'s.

    >>> from bondgraph.library import dc_motor
    >>> xml = fmu_sources(dc_motor(), "dc_motor", parameters={"b": 2e-4})["modelDescription.xml"]
    >>> import re
    >>> re.findall(r'name="(\\w+)" valueReference="(\\d+)"', xml)[:3]
    [('R_a', '0'), ('L_a', '1'), ('k_m', '2')]
    >>> re.search(r'name="b".*?start="([^"]+)"', xml, re.S).group(1)
    '0.0002'
    """
    require_model(bg, "fmu_sources")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", str(model_identifier)):
        raise FmuError(f"to_fmu: model_identifier {model_identifier!r} is not a C identifier")
    for name, value in (("step", step), ("tolerance", tolerance)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise FmuError(f"to_fmu: {name} must be a positive number, got {value!r}")
    if tolerance >= 1:
        raise FmuError(f"to_fmu: tolerance must be below 1, got {tolerance!r}")
    equations = bg.state_equations()
    model = _Variables(equations, bg, inputs or {}, x0 or {}, parameters or {})
    code = _model_code(equations, model)
    guid = _guid(bg.name or "", model, code, step, tolerance)
    c_text = _c_file(model, code, guid, tolerance)
    xml = _model_description(bg.name or model_identifier, model_identifier, guid, model, step, tolerance)
    return {"modelDescription.xml": xml, f"sources/{HEADER_NAME}": HEADER, f"sources/{model_identifier}.c": c_text}


# ------------------------------------------------------------------------------------------------ variables


def _number(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FmuError(f"to_fmu: {what} must be a finite number, got {value!r}")
    return float(value)


def _nominal(element) -> float:
    """A state's nominal magnitude: its energy variable at unit effort or flow (a linear C's ``q = C e``, a
    linear I's ``p = I f``), the element's value; 1 (the FMI default) for an element with a law."""
    value = getattr(element, "value", None)
    if element.law is None and isinstance(value, (int, float)) and math.isfinite(value) and value != 0:
        return abs(float(value))
    return 1.0


class _Variables:
    """The FMU's variables in value-reference order: parameters, inputs, states, signals; their start values."""

    def __init__(self, equations: StateEquations, bg, inputs: Mapping, x0: Mapping, parameters: Mapping):
        self.parameters = list(equations.parameters)
        self.inputs = list(equations.inputs)
        self.states = [str(s) for s in equations.states]
        self.signals = list(equations.outputs)
        self.elements = [str(e) for e in equations.elements]
        for key in parameters:
            if key not in self.parameters:
                raise FmuError(f"to_fmu: parameter {key!r} is not in the model; it has {self.parameters}")
        for key in inputs:
            if key not in self.inputs:
                raise FmuError(f"to_fmu: input {key!r} is not an input of the model; its inputs are {self.inputs}")
        nominal = {**equations.parameters, **parameters}
        self.parameter_start = [_number(nominal[p], f"parameter {p!r}") for p in self.parameters]
        constants = {e.signal: e.value for e in bg.elements.values() if getattr(e, "value", None) is not None
                     and e.kind in ("Se", "Sf", "MSe", "MSf") and e.signal}
        self.input_start = [_number(inputs.get(u, constants.get(u, 0.0)), f"input {u!r}") for u in self.inputs]
        self.state_start = [0.0] * len(self.states)
        self.state_nominal = [_nominal(bg.elements[e]) for e in equations.elements]
        for key, value in x0.items():
            if str(key) in self.states:
                index = self.states.index(str(key))
            elif str(key) in self.elements:
                index = self.elements.index(str(key))
            else:
                raise FmuError(f"to_fmu: x0 names {key!r}, which is not a state; states are {self.states} "
                               f"(or elements {self.elements})")
            self.state_start[index] = _number(value, f"x0[{key!r}]")
        names = [*self.parameters, *self.inputs, *self.states, *self.signals]
        seen: set = set()
        for name in names:
            if name in seen:
                raise FmuError(f"to_fmu: the name {name!r} is taken by two FMU variables (a parameter, input, "
                               "state or signal); rename one")
            seen.add(name)
        self.names = names
        self.units = _units(bg, equations, self)
        self.feedthrough = [[i for i, u in enumerate(self.inputs) if expression.has(signal_function(u))]
                            for expression in map(sp.sympify, equations.outputs.values())]


def _units(bg, equations: StateEquations, model: _Variables) -> dict[str, Unit]:
    """Each variable's unit, where the model declares or implies one: a parameter's and a signal's, and a
    state's, its bond's effort (I) or flow (C) times a second."""
    units = bg.units
    found = {name: units.parameters[name] for name in model.parameters if name in units.parameters}
    found.update({name: units.signals[name] for name in [*model.inputs, *model.signals] if name in units.signals})
    bond_of = {str(end): bond for bond in bg.bonds if not bond.is_signal for end in (bond.tail, bond.head)}
    for state, element in zip(model.states, equations.elements):
        bond = bond_of.get(str(element))   # a storage element has one bond
        rate = None if bond is None else (units.efforts if state.startswith("p_") else units.flows).get(
            (bond.tail, bond.head))
        if rate is not None:
            found[state] = rate * SECOND
    return found


def _base_units(unit: Unit) -> dict[str, str] | None:
    """FMI 2.0's ``BaseUnit`` exponents of ``unit`` (SI bases and ``rad``), None when one is not an integer or
    the unit has a solid angle (FMI 2.0 has no ``sr``)."""
    exponents = dict(zip(BASE, unit.dimension))
    exponents["rad"] = sum((power for symbol, power in unit.factors if symbol == "rad"), Fraction(0))
    if any(symbol == "sr" for symbol, _ in unit.factors) or any(e.denominator != 1 for e in exponents.values()):
        return None
    return {name: str(int(e)) for name, e in exponents.items() if e != 0}


# ------------------------------------------------------------------------------------------------ C code


class _ModelPrinter(C99CodePrinter):
    """C99 with the runtime's names for the model's symbols, doubles to the last bit, a NaN-propagating sign."""

    def __init__(self, names: dict):
        super().__init__({"strict": True})
        self._names = names

    def _print_Symbol(self, expr):
        return self._names[expr]

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_sign(self, expr):
        return f"bg_sign({self._print(expr.args[0])})"


def _model_code(equations: StateEquations, model: _Variables) -> dict[str, list[str]]:
    """The C statements of the derivatives and the signals, with their common subexpressions."""
    names = {T: "t"}
    names.update({sp.Symbol(p): f"p[{i}]" for i, p in enumerate(model.parameters)})
    names.update({s: f"x[{i}]" for i, s in enumerate(equations.states)})
    inputs = {signal_function(u): sp.Symbol(f"_fmu_input_{i}") for i, u in enumerate(model.inputs)}
    names.update({s: f"u[{i}]" for i, s in enumerate(inputs.values())})
    code = {}
    for part, targets, expressions, labels in (
            ("derivatives", "dx", equations.rhs, [f"d{x}/dt" for x in model.states]),
            ("signals", "y", list(equations.outputs.values()), [f"signal {y!r}" for y in model.signals])):
        expressions = [sp.sympify(e).xreplace(inputs) for e in expressions]
        for label, expression in zip(labels, expressions):
            _check_expression(expression, label, names)
        temporaries, results = sp.cse(expressions, symbols=sp.numbered_symbols("_fmu_w"))
        local = {**names, **{s: f"w{k}" for k, (s, _) in enumerate(temporaries)}}
        printer = _ModelPrinter(local)
        lines = []
        for k, (_, expression) in enumerate(temporaries):
            lines.append(f"    const double w{k} = {_printed(printer, expression, labels)};")
        lines += [f"    {targets}[{i}] = {_printed(printer, e, [label])};" for i, (e, label)
                  in enumerate(zip(results, labels))]
        code[part] = lines
    return code


def _check_expression(expression: sp.Expr, label: str, names: dict) -> None:
    if expression.has(sp.Derivative):
        raise FmuError(f"to_fmu: {label} needs {sorted(map(str, expression.atoms(sp.Derivative)))[0]}: a storage "
                       "element in derivative causality is driven directly by an input")
    unknown = sorted(str(s) for s in expression.free_symbols if s not in names)
    if unknown:
        raise FmuError(f"to_fmu: {label} uses {unknown[0]!r}, which is no parameter, state or input of the model")


def _printed(printer: _ModelPrinter, expression: sp.Expr, labels: list) -> str:
    try:
        return printer.doprint(expression)
    except Exception as error:   # sympy's printers raise several types for what they cannot write
        functions = sorted({type(f).__name__ for f in expression.atoms(sp.Function)})
        what = f" (its functions: {', '.join(functions)})" if functions else ""
        raise FmuError(f"to_fmu: the C printer cannot write {' / '.join(labels)}{what}: "
                       f"{str(error).splitlines()[0]}") from None


def _c_array(name: str, values: list, kind: str = "double") -> str:
    if kind == "double":
        items = [repr(float(v)) for v in values] or ["0.0"]
        return f"static const double {name}[BG_SIZE({len(values)})] = {{{', '.join(items)}}};"
    items = [f'"{v}"' for v in values] or ['""']   # the names are identifiers: nothing to escape in C
    return f"static const char *const {name}[BG_SIZE({len(values)})] = {{{', '.join(items)}}};"


def _c_file(model: _Variables, code: dict, guid: str, tolerance: float) -> str:
    header = [
        "/* FMI 2.0 co-simulation FMU of a bond graph, written by bondgraph.fmu_export (bondgraph-phm).",
        f"   States {', '.join(model.states) or '(none)'}; inputs {', '.join(model.inputs) or '(none)'}. */",
        "#include <math.h>", "#include <stdio.h>", "#include <stdlib.h>", "#include <string.h>",
        f'#include "{HEADER_NAME}"', "",
        "#define BG_SIZE(n) ((n) > 0 ? (n) : 1)",
        f'#define BG_GUID "{guid}"',
        f"#define BG_NP {len(model.parameters)}", f"#define BG_NU {len(model.inputs)}",
        f"#define BG_NX {len(model.states)}", f"#define BG_NY {len(model.signals)}",
        f"#define BG_DEFAULT_TOLERANCE {tolerance!r}", "",
        _c_array("bg_parameter_start", model.parameter_start),
        _c_array("bg_input_start", model.input_start),
        _c_array("bg_state_start", model.state_start),
        _c_array("bg_state_nominal", model.state_nominal),
        _c_array("bg_variable_names", model.names, "text"), "",
        "/* sign(x), NaN for NaN (C's comparisons would give 0) */",
        "static inline double bg_sign(double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : x); }", "",
        "static void bg_derivatives(double t, const double *x, const double *u, const double *p, double *dx) {",
        "    (void)t; (void)x; (void)u; (void)p;", *code["derivatives"], "}", "",
        "static void bg_signals(double t, const double *x, const double *u, const double *p, double *y) {",
        "    (void)t; (void)x; (void)u; (void)p;", *code["signals"], "}",
    ]
    return "\n".join(header) + "\n" + RUNTIME


def _guid(name: str, model: _Variables, code: dict, step: float, tolerance: float) -> str:
    """A GUID from everything the FMU holds, so that the same model gives the same FMU (and another, another)."""
    digest = hashlib.sha256(repr((name, model.names, model.parameter_start, model.input_start, model.state_start,
                                  code, step, tolerance, RUNTIME)).encode()).hexdigest()
    return "{" + "-".join((digest[:8], digest[8:12], digest[12:16], digest[16:20], digest[20:32])) + "}"


# ------------------------------------------------------------------------------------------------ XML

#: Characters XML 1.0 cannot hold, even escaped: a model's free-text name is cleaned of them.
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")


def _model_description(title: str, identifier: str, guid: str, model: _Variables, step: float,
                       tolerance: float) -> str:
    """modelDescription.xml (FMI 2.0, co-simulation); ElementTree escapes every text."""
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": _NOT_XML.sub("?", title), "guid": guid,
        "description": _NOT_XML.sub("?", f"bond graph '{title}' exported by bondgraph-phm"),
        "generationTool": "bondgraph-phm (bondgraph.fmu_export)", "variableNamingConvention": "flat",
        "numberOfEventIndicators": "0"})
    cs = ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": identifier, "canHandleVariableCommunicationStepSize": "true",
        "canGetAndSetFMUstate": "true", "canSerializeFMUstate": "true", "canNotUseMemoryManagementFunctions": "false",
        "canInterpolateInputs": "false", "maxOutputDerivativeOrder": "0", "canRunAsynchronuously": "false",
        "providesDirectionalDerivative": "false"})
    sources = ET.SubElement(cs, "SourceFiles")
    ET.SubElement(sources, "File", {"name": f"{identifier}.c"})
    written = {}   # unit text -> its base-unit exponents, for the units FMI 2.0 can write
    for unit in model.units.values():
        if str(unit) not in written and _base_units(unit) is not None:
            written[str(unit)] = _base_units(unit)
    if written:
        definitions = ET.SubElement(root, "UnitDefinitions")
        for text, exponents in written.items():
            ET.SubElement(ET.SubElement(definitions, "Unit", {"name": text}), "BaseUnit", exponents)
    categories = ET.SubElement(root, "LogCategories")
    ET.SubElement(categories, "Category", {"name": "logError", "description": "errors (always logged)"})
    ET.SubElement(root, "DefaultExperiment", {"startTime": "0.0", "stepSize": repr(float(step)),
                                              "tolerance": repr(float(tolerance))})
    variables = ET.SubElement(root, "ModelVariables")
    rows = [(p, "parameter", "tunable", "exact", v, f"parameter {p}")
            for p, v in zip(model.parameters, model.parameter_start)]
    rows += [(u, "input", "continuous", None, v, f"input signal {u}") for u, v in zip(model.inputs, model.input_start)]
    rows += [(x, "output", "continuous", "exact", (v, n), f"state of storage element {e}")
             for x, e, v, n in zip(model.states, model.elements, model.state_start, model.state_nominal)]
    rows += [(y, "output", "continuous", None, None, f"measured signal {y}") for y in model.signals]
    for reference, (name, causality, variability, initial, start, description) in enumerate(rows):
        attributes = {"name": name, "valueReference": str(reference), "description": description,
                      "causality": causality, "variability": variability}
        if initial:
            attributes["initial"] = initial
        variable = ET.SubElement(variables, "ScalarVariable", attributes)
        start, nominal = start if isinstance(start, tuple) else (start, None)
        real = {} if start is None else {"start": repr(float(start))}
        if name in model.units and str(model.units[name]) in written:
            real["unit"] = str(model.units[name])
        if nominal is not None:
            real["nominal"] = repr(float(nominal))
        ET.SubElement(variable, "Real", real)
    structure = ET.SubElement(root, "ModelStructure")
    first_output = len(model.parameters) + len(model.inputs) + 1   # ModelVariables count from 1
    if model.states or model.signals:
        outputs = ET.SubElement(structure, "Outputs")
        first_input = len(model.parameters) + 1
        # the inputs each output reads at once (none for a state; for a signal, those in its expression): an
        # importer sees which outputs feed through, and which loops are algebraic
        feedthrough = [[]] * len(model.states) + model.feedthrough
        for k, inputs in enumerate(feedthrough):
            ET.SubElement(outputs, "Unknown", {"index": str(first_output + k),
                                               "dependencies": " ".join(str(first_input + i) for i in inputs)})
    if model.signals:   # outputs computed at initialization: the signals (the states' start is exact)
        initial = ET.SubElement(structure, "InitialUnknowns")
        for k in range(len(model.signals)):
            ET.SubElement(initial, "Unknown", {"index": str(first_output + len(model.states) + k)})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


# ------------------------------------------------------------------------------------------------ build


def _identifier(stem: str) -> str:
    """A C identifier from a file name's stem: other characters become ``_``, a leading digit gets one."""
    text = re.sub(r"\W", "_", stem, flags=re.ASCII) or "model"
    return text if not text[0].isdigit() else "_" + text


def _compiler(name: str | None) -> str:
    if name is not None:
        found = shutil.which(name)
        if not found:
            raise FmuError(f"to_fmu: the C compiler {name!r} is not on the PATH")
        return found
    environment = os.environ.get("CC")
    if environment:
        found = shutil.which(environment.split()[0])
        if not found:
            raise FmuError(f"to_fmu: the C compiler {environment!r} of $CC is not on the PATH")
        return found
    for candidate in ("cc", "gcc"):
        found = shutil.which(candidate)
        if found:
            return found
    raise FmuError("to_fmu: no C compiler found ($CC, cc or gcc) to build binaries/linux64; install one (gcc)")


def _compiled(files: dict, identifier: str, work: Path, cc: str) -> bytes:
    """The shared library built from ``files`` in ``work`` with ``cc``."""
    for name, text in files.items():
        target = work / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
    binary = work / f"{identifier}.so"
    command = [cc, "-std=c99", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-o", str(binary),
               str(work / "sources" / f"{identifier}.c"), "-lm"]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    except (OSError, subprocess.TimeoutExpired) as error:
        raise FmuError(f"to_fmu: the C compiler {cc!r} did not run: {error}") from None
    if done.returncode != 0 or not binary.is_file():
        lines = [line for line in (done.stderr or done.stdout).splitlines() if "error" in line] or \
            (done.stderr or done.stdout or "no message").splitlines()
        raise FmuError(f"to_fmu: the C compiler {cc!r} failed on sources/{identifier}.c: {lines[0].strip()}")
    return binary.read_bytes()


def _write_zip(path: Path, files: dict, binaries: dict) -> None:
    """The zip at ``path``, whole or not at all: written beside it under a temporary name, then renamed."""
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(handle)
    try:
        with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
            for name, text in files.items():
                archive.writestr(zipfile.ZipInfo(name, _ZIP_TIME), text.encode("utf-8"), zipfile.ZIP_DEFLATED)
            for name, data in binaries.items():
                entry = zipfile.ZipInfo(name, _ZIP_TIME)
                entry.external_attr = 0o755 << 16   # executable, as a shared library is
                archive.writestr(entry, data, zipfile.ZIP_DEFLATED)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
