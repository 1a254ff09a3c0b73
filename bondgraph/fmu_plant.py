"""An FMI 2.0 co-simulation FMU, ours or another tool's, run as a plant from Python (fmpy, the ``fmi`` extra).

:class:`FmuPlant` instantiates the FMU once and steps it: the inputs set at a communication point are held
over the step, as FMI 2.0 co-simulation does without input derivatives, and the outputs are read at the
step's end.  It is the plant of a loop written in Python: an estimator fed its noisy outputs, a controller,
a parameter that degrades between steps (a tunable parameter).  :func:`simulate_fmu` runs it over a time grid
and returns a record (``t``, the inputs, the outputs), the columns :meth:`SimulationResult.record
<bondgraph.simulation.SimulationResult.record>` and the data files have.

fmpy (Modelica Association's FMI tooling for Python, ``pip install 'bondgraph-phm[fmi]'``) is imported when a
plant is made; without it the rest of the toolkit works as before.

Errors name the FMU file and the variable: a path that is no FMU, an FMU without co-simulation, an output,
input or parameter it does not have, a call the FMU refuses (with the FMU's own logged message).

An FMU's binary is native code, loaded into this process: like a Python model file, run only FMUs you trust.

Examples
--------
Without fmpy nothing here runs; with it (``tests/interop/test_fmi.py``), on an FMU :func:`~bondgraph.to_fmu`
wrote::

    record = simulate_fmu("dc_motor.fmu", np.linspace(0.0, 0.5, 501), {"U": 12.0}, parameters={"b": 2e-4})
    record["omega"][-1]   # rad/s, as bondgraph.simulate gives it

The inputs of a simulation (:func:`input_schedule`) need no FMU:

>>> import numpy as np
>>> t = np.array([0.0, 0.5, 1.0])
>>> {name: values.tolist() for name, values in input_schedule(t, {"U": 12.0, "T_L": lambda t: -t}).items()}
{'U': [12.0, 12.0, 12.0], 'T_L': [-0.0, -0.5, -1.0]}
"""

from __future__ import annotations

import math
import os
import shutil
import weakref
import zipfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from .errors import FmuError
from .optional import import_optional

__all__ = ["FmuPlant", "input_schedule", "simulate_fmu"]

_INSTALL = "pip install 'bondgraph-phm[fmi]'"


def _fmpy():
    return import_optional("fmpy", f"running an FMU needs fmpy: {_INSTALL}")


def simulate_fmu(path: str | os.PathLike, t: Sequence[float], inputs: Mapping | None = None,
                 parameters: Mapping | None = None, *, outputs: Sequence[str] | None = None,
                 tolerance: float | None = None) -> dict[str, np.ndarray]:
    """Run the co-simulation FMU at ``path`` over the times ``t`` and return its record.

    Parameters
    ----------
    path : path-like
        An FMI 2.0 FMU with a co-simulation interface and a binary for this platform.
    t : sequence of float
        Increasing communication points; the first is the start time.
    inputs : mapping, optional
        Input name -> a number, a callable ``u(t)`` or an array of ``len(t)`` values; each is set at
        ``t[k]`` and held to ``t[k + 1]``.  Inputs not given keep the FMU's start value.
    parameters : mapping, optional
        Parameters and other start values (an initial state of an FMU of ours) set before initialization.
    outputs : sequence of str, optional
        The outputs to record (default: every output of the FMU).
    tolerance : float, optional
        Passed to ``fmi2SetupExperiment`` (default: the FMU's own).

    Returns
    -------
    dict
        ``t``, the inputs given (as held) and the outputs, each an array of ``len(t)``.

    Raises
    ------
    FmuError
        Naming the FMU and what is wrong (see the module).
    ImportError
        Without fmpy: one line naming the extra.

    Examples
    --------
    The times and the file are checked before fmpy is needed (a run: the module's example):

    >>> simulate_fmu("motor.fmu", [0.0])
    Traceback (most recent call last):
    ...
    bondgraph.errors.FmuError: simulate_fmu: t must be at least two finite, increasing times
    >>> simulate_fmu("no_such_motor.fmu", [0.0, 0.1])
    Traceback (most recent call last):
    ...
    bondgraph.errors.FmuError: FMU 'no_such_motor.fmu': no such file (no_such_motor.fmu)
    """
    times = np.asarray(t, dtype=float)
    if times.ndim != 1 or times.size < 2 or not np.all(np.isfinite(times)) or not np.all(np.diff(times) > 0):
        raise FmuError("simulate_fmu: t must be at least two finite, increasing times")
    with FmuPlant(path, parameters=parameters, start_time=float(times[0]), tolerance=tolerance) as plant:
        names = plant.outputs if outputs is None else [plant.output_name(name) for name in outputs]
        schedule = input_schedule(times, inputs or {}, plant.inputs, f"FMU {Path(path).name!r}")
        columns = {name: np.empty(times.size) for name in names}
        for k in range(times.size):
            if k:
                plant.step(times[k] - times[k - 1], {name: values[k - 1] for name, values in schedule.items()})
            elif schedule:
                plant.set_inputs({name: values[0] for name, values in schedule.items()})
            for name, value in plant.read(names).items():
                columns[name][k] = value
    return {"t": times, **schedule, **columns}


def input_schedule(t: np.ndarray, inputs: Mapping, known: Sequence[str] | None = None,
                   where: str = "the FMU") -> dict[str, np.ndarray]:
    """The value of each input at each time of ``t``: a number repeated, a callable ``u(t)`` evaluated, an
    array of ``len(t)`` values taken as it is; ``known`` (when given) the inputs there are.

    >>> input_schedule(np.array([0.0, 1.0]), {"U": [1.0, 2.0, 3.0]})
    Traceback (most recent call last):
    ...
    bondgraph.errors.FmuError: input 'U' of the FMU: 3 values for 2 times
    """
    schedule = {}
    for name, spec in inputs.items():
        if known is not None and name not in known:
            raise FmuError(f"{where} has no input {name!r}; its inputs are {list(known)}")
        if callable(spec):
            values = np.array([float(spec(float(s))) for s in t])
        elif np.ndim(spec) == 0:
            values = np.full(t.size, _real(spec, f"input {name!r} of {where}"))
        else:
            values = np.asarray(spec, dtype=float)
            if values.shape != t.shape:
                raise FmuError(f"input {name!r} of {where}: {values.size} values for {t.size} times")
        if not np.all(np.isfinite(values)):
            raise FmuError(f"input {name!r} of {where} is NaN or infinite at t = {t[~np.isfinite(values)][0]:g}")
        schedule[name] = values
    return schedule


def _real(value: object, what: str) -> float:
    if isinstance(value, (bool, str, bytes)):
        raise FmuError(f"{what} must be a number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise FmuError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(number):
        raise FmuError(f"{what} must be finite, got {value!r}")
    return number


class FmuPlant:
    """An FMI 2.0 co-simulation FMU instantiated, initialized and stepped (see the module).

    Parameters
    ----------
    path : path-like
        The FMU file.
    parameters : mapping, optional
        Parameters and other start values set before initialization, by variable name.
    start_time : float
    tolerance : float, optional
        Passed to ``fmi2SetupExperiment`` (default: the FMU's own).

    Attributes
    ----------
    inputs, outputs : list of str
        The FMU's input and output variables, in its order.
    parameters : dict
        Parameter name -> start value (as the FMU declares it).
    time : float
        The present communication point.

    Use it as a context manager, or call :meth:`close`: it frees the instance and the unpacked files.

    Examples
    --------
    With an FMU (``tests/interop/test_fmi.py``, tutorial 8)::

        with FmuPlant("dc_motor.fmu", parameters={"R_a": 1.5}) as plant:
            readings = plant.step(1e-3, {"U": 12.0})   # {'p_L_a': ..., 'p_J': ..., 'i': ..., 'omega': ...}

    A file that is no FMU is named before fmpy is needed:

    >>> FmuPlant("notes.txt")
    Traceback (most recent call last):
    ...
    bondgraph.errors.FmuError: FMU 'notes.txt': no such file (notes.txt)
    """

    def __init__(self, path: str | os.PathLike, *, parameters: Mapping | None = None, start_time: float = 0.0,
                 tolerance: float | None = None):
        self.path = Path(path)
        self._where = f"FMU {self.path.name!r}"
        _check_archive(self.path)
        fmpy = _fmpy()
        description = _description(fmpy, self.path)
        self._variables = {v.name: v for v in description.modelVariables}
        self.inputs = [v.name for v in description.modelVariables if v.causality == "input"]
        self.outputs = [v.name for v in description.modelVariables if v.causality == "output"]
        self.parameters = {v.name: _start(v) for v in description.modelVariables if v.causality == "parameter"}
        settable = [v.name for v in description.modelVariables if _settable_at_start(v)]
        for name in parameters or {}:
            if name not in settable:
                raise FmuError(f"{self._where} has no parameter {name!r} to set; its parameters and start values "
                               f"are {settable}")
        self._messages: list[str] = []
        self._unpacked = fmpy.extract(str(self.path))
        self._cleanup = weakref.finalize(self, shutil.rmtree, self._unpacked, True)
        self._fmu = None
        try:
            try:
                self._fmu = fmpy.fmi2.FMU2Slave(guid=description.guid, unzipDirectory=self._unpacked,
                                                modelIdentifier=description.coSimulation.modelIdentifier,
                                                instanceName="plant")
            except Exception as error:   # no binary for this platform, or one that does not load
                raise FmuError(f"{self._where}: its binary does not load here: "
                               f"{str(error).strip().splitlines()[0]}") from None
            self._call("fmi2Instantiate", self._fmu.instantiate, callbacks=self._callbacks(fmpy))
            self._call("fmi2SetupExperiment", self._fmu.setupExperiment, tolerance=tolerance,
                       startTime=float(start_time))
            for name, value in (parameters or {}).items():
                self._set(name, value)
            self._call("fmi2EnterInitializationMode", self._fmu.enterInitializationMode)
            self._call("fmi2ExitInitializationMode", self._fmu.exitInitializationMode)
        except BaseException:
            self.close()
            raise
        self.time = float(start_time)

    def output_name(self, name: str) -> str:
        """``name`` if the FMU has that output, else an :class:`FmuError` naming it and the outputs there are."""
        if name not in self.outputs:
            raise FmuError(f"{self._where} has no output {name!r}; its outputs are {self.outputs}")
        return name

    def read(self, names: Sequence[str] | None = None) -> dict[str, float]:
        """The present values of ``names`` (default: every output), by name."""
        names = self.outputs if names is None else [self.output_name(name) for name in names]
        by_type: dict = {}
        for name in names:
            by_type.setdefault(self._variables[name].type, []).append(name)
        values = {}
        for kind, group in by_type.items():
            getter = {"Real": self._fmu.getReal, "Integer": self._fmu.getInteger, "Boolean": self._fmu.getBoolean}
            if kind not in getter:
                raise FmuError(f"{self._where}: output {group[0]!r} is a {kind}; only numbers are read")
            read = self._call(f"fmi2Get{kind}", getter[kind], [self._variables[n].valueReference for n in group])
            values.update(zip(group, (float(v) for v in read)))
        return {name: values[name] for name in names}

    def set_inputs(self, inputs: Mapping) -> None:
        """Set inputs (name -> number) at the present communication point."""
        for name, value in inputs.items():
            if name not in self.inputs:
                raise FmuError(f"{self._where} has no input {name!r}; its inputs are {self.inputs}")
            self._set(name, value)

    def set_parameter(self, name: str, value: float) -> None:
        """Change a tunable parameter between steps (a degradation the plant undergoes)."""
        variable = self._variables.get(name)
        if variable is None or variable.causality != "parameter":
            raise FmuError(f"{self._where} has no parameter {name!r}; its parameters are {list(self.parameters)}")
        if variable.variability != "tunable":
            raise FmuError(f"{self._where}: parameter {name!r} is {variable.variability}, not tunable after start")
        self._set(name, value)

    def step(self, dt: float, inputs: Mapping | None = None) -> dict[str, float]:
        """Set ``inputs``, advance by ``dt`` and return the outputs at the new time."""
        dt = _real(dt, f"{self._where}: the step dt")
        if dt <= 0:
            raise FmuError(f"{self._where}: the step dt must be positive, got {dt!r}")
        self.set_inputs(inputs or {})
        self._call("fmi2DoStep", self._fmu.doStep, self.time, dt)
        self.time += dt
        return self.read()

    def close(self) -> None:
        """Terminate and free the instance, and remove the unpacked files (again: nothing)."""
        fmu, self._fmu = self._fmu, None
        if fmu is not None and fmu.component is not None:
            try:
                fmu.terminate()
            except Exception:   # an instance that failed may refuse to terminate; it is freed all the same
                pass
            fmu.freeInstance()
        self._cleanup()

    def __enter__(self) -> "FmuPlant":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -------------------------------------------------------------------------------------------- helpers

    def _callbacks(self, fmpy):
        """fmpy's callbacks with a logger that keeps the FMU's messages for the errors raised here."""
        fmi2 = fmpy.fmi2
        callbacks = fmi2.fmi2CallbackFunctions()

        def log(environment, instance, status, category, message):
            self._messages.append((message or b"").decode("utf-8", "replace"))

        self._logger = fmi2.fmi2CallbackLoggerTYPE(log)   # kept: the FMU calls it as long as it lives
        callbacks.logger = self._logger
        callbacks.allocateMemory = fmi2.defaultCallbacks.allocateMemory
        callbacks.freeMemory = fmi2.defaultCallbacks.freeMemory
        try:   # fmpy's proxy formats a printf-style message before it reaches the Python logger
            from fmpy.logging import addLoggerProxy
            from ctypes import byref
            addLoggerProxy(byref(callbacks))
        except Exception:
            pass
        self._callback_struct = callbacks
        return callbacks

    def _set(self, name: str, value: object) -> None:
        variable = self._variables[name]
        number = _real(value, f"{self._where}: {name!r}")
        setters = {"Real": (self._fmu.setReal, number),
                   "Integer": (self._fmu.setInteger, int(number)),
                   "Boolean": (self._fmu.setBoolean, bool(number))}
        if variable.type not in setters:
            raise FmuError(f"{self._where}: {name!r} is a {variable.type}; only numbers are set")
        setter, converted = setters[variable.type]
        self._call(f"fmi2Set{variable.type} of {name!r}", setter, [variable.valueReference], [converted])

    def _call(self, what: str, function: Callable, *args, **kwargs):
        before = len(self._messages)
        try:
            return function(*args, **kwargs)
        except Exception as error:
            said = "; ".join(m for m in self._messages[before:] if m) or str(error).splitlines()[0]
            time = getattr(self, "time", None)
            at = f" at t = {time:g}" if time is not None else ""
            raise FmuError(f"{self._where}: {what} failed{at}: {said}") from None


def _check_archive(path: Path) -> None:
    """An :class:`FmuError` unless ``path`` is a zip holding a ``modelDescription.xml`` (no fmpy needed)."""
    if not path.is_file():
        raise FmuError(f"FMU {path.name!r}: no such file ({path})")
    if not zipfile.is_zipfile(path):
        raise FmuError(f"{path.name!r} is not an FMU: not a zip archive")
    with zipfile.ZipFile(path) as archive:
        if "modelDescription.xml" not in archive.namelist():
            raise FmuError(f"{path.name!r} is not an FMU: it holds no modelDescription.xml")


def _description(fmpy, path: Path):
    """The FMU's model description, validated, or an :class:`FmuError` saying why ``path`` is no usable FMU."""
    where = f"FMU {path.name!r}"
    try:
        description = fmpy.read_model_description(str(path), validate=True)
    except Exception as error:
        raise FmuError(f"{where}: invalid modelDescription.xml: {str(error).strip().splitlines()[0]}") from None
    if description.fmiVersion != "2.0":
        raise FmuError(f"{where} is FMI {description.fmiVersion}; FmuPlant runs FMI 2.0 co-simulation FMUs")
    if description.coSimulation is None:
        raise FmuError(f"{where} has no co-simulation interface (model exchange only)")
    return description


def _start(variable) -> object:
    """A variable's declared start, a number where it is one (FMI writes Booleans as ``true``/``false``)."""
    try:
        return None if variable.start is None else float(variable.start)
    except (TypeError, ValueError):
        return variable.start


def _settable_at_start(variable) -> bool:
    """Settable before initialization (FMI 2.0, section 2.2.7): a parameter, an input, or a variable whose
    start value is exact or approximate and not a constant."""
    if variable.causality in ("parameter", "input"):
        return True
    return variable.variability != "constant" and variable.initial in ("exact", "approx")
