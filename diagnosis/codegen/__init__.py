"""Residual code to deploy: standalone Python or C evaluating a model's ARRs sample by sample.

:func:`generate_code` writes, for a set of ARRs, a module that does what
:class:`~diagnosis.streaming.StreamingEvaluation` does (``method="savgol"``, ``threshold="interval"``, the
given ``dt``, ``margin`` and ``persistence``), with no sympy, numpy or networkx at run time:

* the Savitzky-Golay derivative estimates: the coefficients (``scipy.signal.savgol_coeffs`` for the step
  ``dt``) and the one-sided fits of the first and the last window (exact least squares, computed in
  rationals at generation time) are constants of the module; a ring buffer of one window per ARR is
  all the memory a stream keeps;
* running trapezoid sums for the integrals of the ARR (from 0 at the stream's first sample);
* the nominal residual ``r_n``, printed from the same common-subexpression form the library evaluates;
* the interval threshold ``[B_lo, B_hi]``: the same interval operations, in the same order, as
  :func:`~diagnosis.intervals.affine_range` (or :func:`~diagnosis.intervals.compile_interval`, the natural
  extension, when Psi_2 is not affine in its deltas), each bound rounded outward by one ``nextafter``
  (transcendental results widened as the library widens them);
* violations ``-r_n`` outside ``[B_lo - margin, B_hi + margin]`` and alarms after ``persistence``
  consecutive violations.

A sample becomes final once its derivative window has arrived (``window // 2`` samples later); the
stream's end (``flush``) finalizes the rest with the one-sided fit.  The values are the library's up to
rounding: the interior derivative sums are done in scipy's order (bitwise equal), the bounds of ``+ - *
/ sqrt`` are bitwise equal, the one-sided fits and the residual's expression agree to a few ulps.  The
thresholds are sound up to IEEE 754 rounding to nearest (each bound stepped one ulp outward after a
correctly rounded operation); compile the C without ``-ffast-math`` (``-ffp-contract=off`` on machines
with fused multiply-add).

Not generated (a :class:`CodegenError` says so): ``method="central"`` for an ARR with derivatives,
antiderivative columns, the BG-LFT threshold, and functions outside ``Abs``, ``sign``, ``sqrt``, powers,
``exp``, ``log``, ``tanh``, ``Min``, ``Max`` (and, in the residual alone, the trigonometric and hyperbolic
functions): ``Piecewise`` for instance.

Examples
--------
>>> from bondgraph.library import rlc_circuit
>>> from diagnosis import derive_arrs
>>> files = generate_code(derive_arrs(rlc_circuit()), "python", dt=0.001, name="rlc")
>>> sorted(files)
['manifest.json', 'rlc.py']
>>> import importlib.util, pathlib, tempfile
>>> path = pathlib.Path(tempfile.mkdtemp()) / "rlc.py"
>>> _ = path.write_text(files["rlc.py"])
>>> spec = importlib.util.spec_from_file_location("rlc", path)
>>> rlc = importlib.util.module_from_spec(spec)
>>> spec.loader.exec_module(rlc)
>>> monitor = rlc.Monitor()
>>> monitor.signals
('V', 'i', 'v_C')
>>> out = [monitor.push(0.001 * k, {"V": 1.0, "i": 0.0, "v_C": 1.0}) for k in range(20)]
>>> [len(o["ARR_J1"]) for o in out[9:12]]    # the first window (11 samples) finalizes 6 samples at once
[0, 6, 1]
>>> index, t, residual, lower, upper, violation, alarm = out[11]["ARR_J1"][0]
>>> index, residual, violation
(6, 0.0, False)
"""

from __future__ import annotations

import json
import math
import numbers

from ._c import c_module
from ._errors import CodegenError
from ._identifiers import identifier, unique
from ._plan import Plan
from ._python import python_module

# The private modules, one job each: _errors (CodegenError), _identifiers (names made identifiers), _plan (what
# an ARR's stream needs: filters, fits, the interval form), _printers (sympy to Python and C), _interval_code
# (the threshold's interval operations as straight-line code), _python and _c (the module of each language).

__all__ = ["LANGUAGES", "CodegenError", "generate_code"]

#: The languages :func:`generate_code` writes.
LANGUAGES = ("python", "c")

CodegenError.__module__ = __name__  # documented, raised and pickled as diagnosis.codegen.CodegenError


def generate_code(arrs, lang: str = "python", *, dt: float, method: str = "savgol", window: int | None = None,
                  polyorder: int | None = None, margin: float = 0.0, persistence: int = 1,
                  name: str = "residuals") -> dict[str, str]:
    """Standalone code evaluating ``arrs`` sample by sample as :class:`~diagnosis.StreamingEvaluation` does.

    Parameters
    ----------
    arrs : sequence of ARR
        The ARR set (e.g. ``derive_arrs(model)``); every ARR gets its stream in the one module.
    lang : {"python", "c"}
        Python 3 with the ``math`` module alone, or C99 with ``libm`` alone.
    dt : float
        The sampling step: the Savitzky-Golay coefficients are computed for it, and a stream refuses a
        step off it by more than a relative 1e-6 (as ``StreamingEvaluation(dt=dt)``).
    method, window, polyorder, margin, persistence
        As for :class:`~diagnosis.StreamingEvaluation` (``method="central"`` only for ARRs without
        derivatives).
    name : str
        The module's name: the Python file ``NAME.py``; the C files ``NAME.h``, ``NAME.c`` and the prefix of
        their public names (made a valid identifier).

    Returns
    -------
    dict
        File name -> text: the module's files and ``manifest.json`` (the signals, each ARR's columns,
        the options).

    Raises
    ------
    CodegenError
        An unknown language, a bad option, a set without ARRs, two ARRs whose names map to one identifier,
        or an ARR that cannot be generated (named, with the reason).

    Examples
    --------
    >>> from bondgraph.library import rlc_circuit
    >>> from diagnosis import derive_arrs
    >>> files = generate_code(derive_arrs(rlc_circuit()), "c", dt=0.001, name="rlc")
    >>> sorted(files)
    ['manifest.json', 'rlc.c', 'rlc.h']
    >>> "int rlc_ARR_J1_push(rlc_ARR_J1_state *s, double t, const double *x, rlc_sample *out);" in files["rlc.h"]
    True
    """
    if lang not in LANGUAGES:
        raise CodegenError(f"lang must be one of {', '.join(map(repr, LANGUAGES))}, got {lang!r}")
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real) or not math.isfinite(dt) or dt <= 0:
        raise CodegenError(f"dt: the sampling step must be a finite number > 0, got {dt!r}")
    arrs = list(arrs)
    if not arrs:
        raise CodegenError("no ARR to generate code for (an empty set)")
    for arr in arrs:
        if getattr(arr, "simulation", False):
            raise CodegenError(f"{arr.name}: a simulation residual (its states integrated over the record) has no "
                               "closed form to generate code from; derive the ARRs without simulated=True")
    prefix = identifier(name, "name")
    plans = [Plan(arr, index, dt=float(dt), method=method, window=window, polyorder=polyorder, margin=margin,
                   persistence=persistence) for index, arr in enumerate(arrs)]
    unique([(p.ident, p.name) for p in plans], "ARR names")
    signals = tuple(dict.fromkeys(s for p in plans for s in p.columns))
    options = {"method": method, "window": window, "polyorder": polyorder, "dt": float(dt), "margin": float(margin),
               "persistence": int(persistence), "threshold": "interval"}
    manifest = {"module": prefix, "language": lang, "signals": list(signals), "options": options,
                "arrs": [{"name": p.name, "identifier": p.ident, "columns": list(p.columns), "window": p.window,
                          "delay": p.lag, "interval": p.interval_form} for p in plans],
                "generator": "bondgraph-phm diagnosis.codegen"}
    files = {"manifest.json": json.dumps(manifest, indent=1) + "\n"}
    if lang == "python":
        files[f"{prefix}.py"] = python_module(plans, signals, options)
    else:
        header, source = c_module(plans, prefix, options)
        files[f"{prefix}.h"], files[f"{prefix}.c"] = header, source
    return files

