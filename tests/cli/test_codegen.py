"""``bgphm codegen``: the module, manifest and README written whole; bad input exit 2 in one line, nothing written."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bondgraph import simulate
from bondgraph.library import rlc_circuit
from diagnosis import derive_arrs
from tests.cli.test_calibrate import run
from tests.diagnosis.generated_code import CStream, compile_c, differences, library_run, load_python, python_run

OPTIONS = {"margin": 1e-4, "persistence": 2}


@pytest.fixture(scope="module")
def rlc_record():
    t = np.arange(0.0, 0.3, 0.001)
    clean = simulate(rlc_circuit(), (0.0, 0.3), {"V": lambda t: 1.0 + 0.5 * np.sin(40 * t)}, t_eval=t).record()
    rng = np.random.default_rng(5)
    return {"t": t, "V": clean["V"], "i": clean["i"] + 1e-4 * rng.standard_normal(t.size), "v_C": clean["v_C"]}


@pytest.mark.parametrize("lang", ["python", "c"])
def test_the_written_module_equals_the_library_stream(lang, tmp_path, rlc_record):
    out = tmp_path / "generated"
    code, stdout, stderr = run("--quiet", "codegen", "rlc", "--lang", lang, "--dt", "0.001", "--out", out,
                               "--margin", OPTIONS["margin"], "--persistence", OPTIONS["persistence"])
    assert code == 0, stderr
    module = "series_rlc_circuit"
    expected = {"manifest.json", "README.md", *([f"{module}.py"] if lang == "python" else [f"{module}.c",
                                                                                          f"{module}.h"])}
    assert {p.name for p in out.iterdir()} == expected and stdout.startswith(f"wrote {out}")
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["signals"] == ["V", "i", "v_C"] and manifest["options"]["persistence"] == 2
    assert [a["name"] for a in manifest["arrs"]] == ["ARR_J1", "ARR_J0"]
    assert "| ARR_J1 | `V`, `i`, `v_C` | 5 | affine |" in (out / "README.md").read_text()
    lib = compile_c(out, module)[0] if lang == "c" else None
    python = load_python(out, module) if lang == "python" else None
    for arr, entry in zip(derive_arrs(rlc_circuit()), manifest["arrs"]):
        columns = [rlc_record[c] for c in entry["columns"]]
        if lang == "python":
            got = python_run(python.ARRStream(arr.name), rlc_record["t"], columns)
        else:
            got = CStream(lib, module, entry["identifier"]).run(rlc_record["t"], columns)
        d = differences(arr, library_run(arr, rlc_record, dt=0.001, **OPTIONS), got)
        assert d["residual"] <= 1e-12 and d["bounds"] <= 1e-12 and d["alarms"].size == 0


def test_an_existing_directory_is_kept_unless_forced(tmp_path):
    out = tmp_path / "generated"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    code, _, stderr = run("--quiet", "codegen", "rlc", "--lang", "python", "--dt", "0.001", "--out", out)
    assert code == 2 and "is not empty; give --force" in stderr and len(stderr.splitlines()) == 1
    assert [p.name for p in out.iterdir()] == ["keep.txt"]
    assert run("--quiet", "codegen", "rlc", "--lang", "python", "--dt", "0.001", "--out", out, "--force")[0] == 0
    assert {p.name for p in out.iterdir()} == {"keep.txt", "manifest.json", "README.md", "series_rlc_circuit.py"}


@pytest.mark.parametrize("extra, words", [
    (["--lang", "rust", "--dt", "0.001"], "argument --lang: invalid choice: 'rust'"),
    (["--lang", "c"], "the following arguments are required: --dt"),
    (["--lang", "c", "--dt", "0"], "dt: the sampling step must be a finite number > 0, got 0.0"),
    (["--lang", "c", "--dt", "0.001", "--method", "central"],
     "ARR_J1: method='central': only Savitzky-Golay derivatives are generated"),
    (["--lang", "c", "--dt", "0.001", "--window", "4"], "ARR_J1: signal 'i': window must be an odd number"),
    (["--lang", "c", "--dt", "0.001", "--persistence", "0"], "persistence must be a whole number"),
])
def test_bad_input_is_one_line_and_writes_nothing(extra, words, tmp_path):
    out = tmp_path / "generated"
    code, _, stderr = run("--quiet", "codegen", "rlc", *extra, "--out", out)
    assert code == 2 and words in stderr and len(stderr.strip().splitlines()) == 1, stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []
