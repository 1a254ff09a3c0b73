"""Helpers for the tests and the benchmark of generated residual code: write, load, compile and run it.

The C is compiled with the system compiler (``cc``) into a shared library and run through ctypes, a
whole record per call (``<module>_<ARR>_run``, which pushes the samples one by one inside C).
"""

from __future__ import annotations

import ctypes
import importlib.util
import shutil
import subprocess
from pathlib import Path

import numpy as np
import sympy as sp

from diagnosis import StreamChunk, StreamingEvaluation

CFLAGS = ("-O2", "-std=c99", "-ffp-contract=off", "-Wall", "-Wextra", "-pedantic")


def write(files: dict, folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (folder / name).write_text(text)
    return folder


def load_python(folder: Path, module: str):
    """The generated Python module ``module.py`` in ``folder``, imported under a unique name."""
    spec = importlib.util.spec_from_file_location(f"generated_{module}_{id(folder)}", folder / f"{module}.py")
    loaded = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(loaded)
    return loaded


def compile_c(folder: Path, module: str) -> tuple[ctypes.CDLL, str]:
    """``module.c`` compiled with ``cc`` into a shared library; the library and the compiler's warnings.

    A missing compiler is an error (an AssertionError), never a skip: the C is part of the contract.
    """
    cc = shutil.which("cc")
    assert cc, "no C compiler (cc) on PATH: the generated C cannot be tested"
    library = folder / f"lib{module}.so"
    done = subprocess.run([cc, *CFLAGS, "-shared", "-fPIC", "-o", str(library), str(folder / f"{module}.c"), "-lm"],
                          capture_output=True, text=True)
    assert done.returncode == 0, f"cc failed:\n{done.stderr}"
    return ctypes.CDLL(str(library)), done.stderr


def _pointer(array: np.ndarray):
    return array.ctypes.data_as(ctypes.c_void_p)


class CStream:
    """One ARR's generated C stream, driven through ctypes."""

    def __init__(self, lib: ctypes.CDLL, module: str, ident: str) -> None:
        self.lib, self.name = lib, f"{module}_{ident}"
        size = getattr(lib, f"{self.name}_size")
        size.restype = ctypes.c_size_t
        self.state = ctypes.create_string_buffer(size())
        getattr(lib, f"{self.name}_init")(self.state)
        self._run = getattr(lib, f"{self.name}_run")
        self._run.restype = ctypes.c_long
        self._run.argtypes = [ctypes.c_void_p, ctypes.c_long] + [ctypes.c_void_p] * 2 + [ctypes.c_int] + \
            [ctypes.c_void_p] * 5

    def run(self, t: np.ndarray, columns: list[np.ndarray], flush: bool = True) -> dict | int:
        """The final samples of ``t`` and the columns pushed one by one (then flushed): arrays by field, or the
        negative error code."""
        t = np.ascontiguousarray(t, dtype=float)
        x = np.ascontiguousarray(np.column_stack(columns), dtype=float) if columns else np.zeros((t.size, 0))
        n = t.size
        out = {k: np.zeros(n + 64) for k in ("t", "residual", "lower", "upper")}
        alarm = np.zeros(n + 64, np.intc)
        m = self._run(ctypes.cast(self.state, ctypes.c_void_p), n, _pointer(t), _pointer(x), int(flush),
                      _pointer(out["t"]), _pointer(out["residual"]), _pointer(out["lower"]), _pointer(out["upper"]),
                      _pointer(alarm))
        if m < 0:
            return int(m)
        result = {k: v[:m].copy() for k, v in out.items()}
        result["alarm"] = alarm[:m].astype(bool)
        return result


def python_run(stream, t: np.ndarray, columns: list[np.ndarray]) -> dict:
    """A generated Python ARRStream fed the samples one by one, then flushed: arrays by field."""
    rows = []
    for k in range(t.size):
        rows += stream.push(t[k], [c[k] for c in columns])
    rows += stream.flush()
    fields = list(zip(*rows)) if rows else [()] * 7
    return {"index": np.array(fields[0], int), "t": np.array(fields[1], float),
            "residual": np.array(fields[2], float), "lower": np.array(fields[3], float),
            "upper": np.array(fields[4], float), "violation": np.array(fields[5], bool),
            "alarm": np.array(fields[6], bool)}


def library_run(arr, record: dict, **options) -> StreamChunk:
    """The library's stream of ``arr`` over the whole record (one batch, then flushed)."""
    stream = StreamingEvaluation(arr, **options)
    return StreamChunk.concatenate([stream.push(record["t"], {c: record[c] for c in stream.columns}),
                                    stream.flush()])


def term_scale(arr, chunk: StreamChunk) -> np.ndarray:
    """Per sample, the sum of the magnitudes of ``r_n``'s additive terms: the scale its rounding error is
    relative to (a residual is a small difference of large terms)."""
    compiled = arr.compiled
    total = np.zeros(len(chunk))
    for term in sp.Add.make_args(compiled.nominal):
        values = sp.lambdify(compiled.points, term, "numpy")(*chunk.points)
        total += np.abs(np.broadcast_to(np.asarray(values, float), total.shape))
    return total


def differences(arr, chunk: StreamChunk, got: dict) -> dict:
    """How far ``got`` (generated code's samples) is from the library's ``chunk``.

    ``residual``: the largest ``|r - r_lib|`` relative to :func:`term_scale`; ``bounds``: the largest
    relative difference of the bounds; ``outside``: the samples (by index) whose generated band does not
    contain the library's; ``alarms``: the samples whose alarm differs.  NaN (an undecided sample) must be
    NaN in both.
    """
    def same_nan(a, b):
        return np.array_equal(np.isnan(a), np.isnan(b))

    assert same_nan(got["residual"], chunk.residual), "NaN residuals differ"
    assert same_nan(got["lower"], chunk.lower) and same_nan(got["upper"], chunk.upper), "NaN bounds differ"
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.abs(got["residual"] - chunk.residual) / term_scale(arr, chunk)
        r[got["residual"] == chunk.residual] = 0.0
        bounds = []
        for key, lib in (("lower", chunk.lower), ("upper", chunk.upper)):
            d = np.abs(got[key] - lib) / np.abs(lib)
            d[got[key] == lib] = 0.0
            bounds.append(d)
    outside = np.flatnonzero((got["lower"] > chunk.lower) | (got["upper"] < chunk.upper))
    return {"residual": float(np.nanmax(r, initial=0.0)), "bounds": float(np.nanmax(np.maximum(*bounds), initial=0.0)),
            "outside": outside, "alarms": np.flatnonzero(got["alarm"] != chunk.alarm),
            "equal": int(np.sum(got["residual"] == chunk.residual))}
