"""Generated residual code (diagnosis.codegen): Python and C equal to the library's stream on zoo records.

Each zoo model's noisy step record comes from the independent reference simulator (tests.zoo.reference);
the library's StreamingEvaluation (same dt, margin, persistence; steps not masked: a stream never masks
them) is the reference.  Contract checked, per ARR, for the generated Python and the C compiled by ``cc``:

* the residual within 1e-12 of the library's, relative to the magnitude of its terms (a residual is a
  small difference of large terms; where the derivative windows are the library's, it is equal bit for
  bit but for numpy's own SIMD ``pow``);
* the bounds within 1e-12 relative, and containing the library's wherever the derivative estimates are
  the library's bit for bit: every sample but the first and last ``window // 2``, whose one-sided fit the
  library computes with numpy's polyfit (LAPACK) and the generated code with exact least squares;
* the same alarms.

No test measures speed (see benchmarks/bench_codegen.py).
"""

from __future__ import annotations

import ast
import importlib
import math

import numpy as np
import pytest
import sympy as sp

from diagnosis import ARR, CodegenError, derive_arrs, generate_code
from tests.diagnosis.generated_code import (CStream, compile_c, differences, library_run, load_python, python_run,
                                            write)
from tests.zoo.reference import record, simulate_reference

OPTIONS = {"margin": 1e-6, "persistence": 3}
T = sp.Symbol("t")


def _model(name: str, tmp_path_factory):
    """Everything one model's tests need: ARRs, a noisy record, the generated modules loaded and compiled."""
    case = importlib.import_module(f"tests.zoo.models.{name}").CASE
    arrs = derive_arrs(case.build())
    data = record(simulate_reference(case, inputs="step"), noise=case.noise, seed=7)
    folder = tmp_path_factory.mktemp(name)
    write(generate_code(arrs, "python", dt=case.dt, name=name, **OPTIONS), folder)
    c_files = generate_code(arrs, "c", dt=case.dt, name=name, **OPTIONS)
    write(c_files, folder)
    lib, warnings = compile_c(folder, name)
    return {"name": name, "case": case, "arrs": arrs, "record": data, "python": load_python(folder, name),
            "lib": lib, "warnings": warnings, "files": c_files}


@pytest.fixture(scope="module")
def rc_ladder2(tmp_path_factory):
    return _model("rc_ladder2", tmp_path_factory)


def _check_model(model) -> dict:
    """Compare the generated Python and C with the library on every ARR of ``model``; the figures."""
    figures = {}
    for arr in model["arrs"]:
        reference = library_run(arr, model["record"], dt=model["case"].dt, **OPTIONS)
        python = model["python"].ARRStream(arr.name)
        columns = [model["record"][c] for c in python.columns]
        half = python._spec["half"]
        n = len(reference)
        for kind, got in (("python", python_run(python, model["record"]["t"], columns)),
                          ("c", CStream(model["lib"], model["name"], arr.name).run(model["record"]["t"], columns))):
            assert not isinstance(got, int), f"{arr.name} ({kind}): error code {got}"
            assert got["t"].size == n and np.array_equal(got["t"], reference.t), f"{arr.name} ({kind}): samples"
            d = differences(arr, reference, got)
            assert d["residual"] <= 1e-12, f"{arr.name} ({kind}): residual off by {d['residual']:.3g}"
            assert d["bounds"] <= 1e-12, f"{arr.name} ({kind}): bounds off by {d['bounds']:.3g}"
            inner = d["outside"][(d["outside"] >= half) & (d["outside"] < n - half)]
            assert inner.size == 0, f"{arr.name} ({kind}): band not containing the library's at samples {inner[:5]}"
            assert d["alarms"].size == 0, f"{arr.name} ({kind}): alarms differ at samples {d['alarms'][:5]}"
            figures[(arr.name, kind)] = d
    return figures


def test_rc_ladder2_generated_python_and_c_equal_the_library_stream(rc_ladder2):
    figures = _check_model(rc_ladder2)
    # where the windows are the library's (all but the ends), the values are bitwise equal
    assert all(d["equal"] >= len(rc_ladder2["record"]["t"]) - 10 for d in figures.values())


@pytest.mark.slow
@pytest.mark.parametrize("name", ["orifice_tanks", "loudspeaker"])
def test_zoo_generated_python_and_c_equal_the_library_stream(name, tmp_path_factory):
    """A non-linear orifice law (sqrt, Abs, sign), and a loudspeaker with an integral and a cubic spring."""
    _check_model(_model(name, tmp_path_factory))


def test_the_c_compiles_without_a_warning(rc_ladder2):
    assert rc_ladder2["warnings"] == ""


def test_generated_python_needs_math_alone(rc_ladder2):
    tree = ast.parse(generate_code(rc_ladder2["arrs"], "python", dt=0.001, name="m")["m.py"])
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    imported |= {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert imported == {"math"}


def test_gaps_are_nan_as_in_the_library(rc_ladder2, tmp_path):
    """A gap (NaN) leaves the samples whose windows reach it undecided, in the generated code as in the library."""
    data = {k: v.copy() for k, v in rc_ladder2["record"].items()}
    data["v_1"][500] = np.nan
    arr = rc_ladder2["arrs"][0]
    reference = library_run(arr, data, dt=0.001, **OPTIONS)
    python = rc_ladder2["python"].ARRStream(arr.name)
    columns = [data[c] for c in python.columns]
    for got in (python_run(python, data["t"], columns),
                CStream(rc_ladder2["lib"], "rc_ladder2", arr.name).run(data["t"], columns)):
        assert np.isnan(got["residual"][495:506]).all() and not np.isnan(got["residual"][:495]).any()
        d = differences(arr, reference, got)
        assert d["residual"] <= 1e-12 and d["bounds"] <= 1e-12 and d["alarms"].size == 0


def test_python_stream_refuses_what_the_library_refuses(rc_ladder2):
    module = rc_ladder2["python"]
    stream = module.ARRStream("ARR_0_1")
    stream.push(0.0, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="t must increase"):
        stream.push(0.0, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="step is 0.001"):
        stream.push(0.0015, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="infinite or too large"):
        stream.push(0.001, [math.inf, 0.0, 0.0])
    with pytest.raises(ValueError, match="fewer than the 11"):
        stream.flush()
    monitor = module.Monitor()
    with pytest.raises(ValueError, match=r"missing signal\(s\) \['v_2'\]"):
        monitor.push(0.0, {"V_s": 1.0, "v_1": 0.0})
    short = module.ARRStream("ARR_0_1")
    for k in range(11):
        short.push(0.001 * k, [1.0, 0.0, 0.0])
    assert len(short.flush()) == 5 and short.flush() == []
    with pytest.raises(ValueError, match="ended"):
        short.push(1.0, [1.0, 0.0, 0.0])


def test_c_stream_error_codes(rc_ladder2):
    lib, t = rc_ladder2["lib"], np.arange(20) * 0.001
    columns = [np.ones(20), np.zeros(20), np.zeros(20)]

    def run(times, cols=columns, flush=True):
        return CStream(lib, "rc_ladder2", "ARR_0_1").run(times, cols, flush)

    assert run(np.array([0.0, 0.001, 0.001]), [c[:3] for c in columns]) == -1  # t not increasing
    assert run(np.array([0.0, 0.001, 0.0025]), [c[:3] for c in columns]) == -2  # a step off dt
    assert run(t, [np.full(20, np.inf), columns[1], columns[2]]) == -3   # an infinite value
    assert run(t[:5], [c[:5] for c in columns]) == -5                     # flushed before the first window
    assert len(run(t, flush=False)["t"]) == 15 and len(run(t)["t"]) == 20
    header = rc_ladder2["files"]["rc_ladder2.h"]
    for name, code in (("TIME", -1), ("STEP", -2), ("VALUE", -3), ("ENDED", -4), ("SHORT", -5)):
        assert f"#define RC_LADDER2_ERR_{name} ({code})" in header


# -- what cannot be generated -------------------------------------------------------------------------


def _arr(name: str, nominal) -> ARR:
    return ARR(name, "J", nominal, sp.Integer(0), {}, frozenset(), {}, {})


def test_bad_options_and_sets_are_refused(rc_ladder2):
    arrs = rc_ladder2["arrs"]
    with pytest.raises(CodegenError, match="lang must be one of 'python', 'c', got 'rust'"):
        generate_code(arrs, "rust", dt=0.001)
    with pytest.raises(CodegenError, match="dt: the sampling step must be a finite number > 0"):
        generate_code(arrs, "c", dt=0.0)
    with pytest.raises(CodegenError, match="no ARR"):
        generate_code([], "c", dt=0.001)
    with pytest.raises(CodegenError, match="ARR_0_1: method='central': only Savitzky-Golay derivatives"):
        generate_code(arrs, "c", dt=0.001, method="central")
    with pytest.raises(CodegenError, match="persistence must be a whole number"):
        generate_code(arrs, "c", dt=0.001, persistence=0)
    with pytest.raises(CodegenError, match="ARR_0_1: .*window"):
        generate_code(arrs, "c", dt=0.001, window=4)


def test_a_piecewise_relation_is_refused_naming_the_arr():
    x = sp.Function("x")(T)
    arr = _arr("ARR_pw", sp.Piecewise((x, x > 0), (-x, True)))
    with pytest.raises(CodegenError, match="ARR_pw: cannot generate code for the function Piecewise in r_n"):
        generate_code([arr], "python", dt=0.1)


def test_names_become_identifiers_and_collisions_are_refused(tmp_path):
    a, b = sp.Function("v-1")(T), sp.Function("v 1")(T)
    arr = _arr("ARR 1", a - 2 * b)
    with pytest.raises(CodegenError, match="'v 1' and 'v-1' both become the identifier 'v_1'"):
        generate_code([arr], "c", dt=0.1)
    with pytest.raises(CodegenError, match="'ARR-1' and 'ARR 1' both become the identifier 'ARR_1'"):
        generate_code([_arr("ARR-1", a), arr], "python", dt=0.1)
    odd = _arr("1 ARR\"*/", sp.Function("é*/\"")(T) - sp.Function("w")(T))
    files = write(generate_code([odd], "c", dt=0.1, name="9 m"), tmp_path)
    lib, warnings = compile_c(files, "_9_m")
    assert warnings == ""
    got = CStream(lib, "_9_m", "_1_ARR___").run(np.arange(3) * 0.1, [np.ones(3), np.array([1.0, 2.0, 3.0])])
    assert got["residual"].tolist() == [0.0, 1.0, 2.0]
    python = load_python(write(generate_code([odd], "python", dt=0.1, name="m"), tmp_path / "py"), "m")
    assert python.Monitor().signals == ("w", "é*/\"")


@pytest.mark.slow
def test_the_benchmark_runs_and_reports_agreement(capsys):
    """benchmarks/bench_codegen.py on a few samples: its JSON and agreement figures (its speed is not asserted)."""
    import json
    import runpy

    from pathlib import Path

    bench = runpy.run_path(str(Path(__file__).resolve().parents[2] / "benchmarks" / "bench_codegen.py"),
                           run_name="bench_codegen")
    assert bench["main"](["--json", "--samples", "20", "--repeat", "1", "rc_ladder2"]) == 0
    (row,) = json.loads(capsys.readouterr().out)["models"]
    assert row["model"] == "rc_ladder2" and row["alarms_equal"]
    assert row["residual_rel"] <= 1e-12 and row["bounds_rel"] <= 1e-12
    assert {"library_us", "python_us", "c_us", "speedup"} <= set(row)
