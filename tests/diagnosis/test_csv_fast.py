"""read_csv's fast paths (pyarrow, numpy) read exactly what the cell-by-cell reader reads, or leave the file to it.

Every file is read three ways: as read_csv reads it (``parser="auto"``: pyarrow first), with numpy
(``parser="numpy"``), and cell by cell (``parser="cells"``).  The records must be equal to the bit,
the warnings the same, and a file the careful reader refuses must be refused with its message
whatever the path.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import diagnosis._csv_fast as fast
from diagnosis.csv_reading import read_csv
from diagnosis.records import RecordError

CELLS = ["1.5", " 1.5", "+.5e-3", "-0", "00012", "5.", "1e5", "", "NA", "nan", "NaN", "-nan", "null", '"1.5"', '"NA"',
         "1_000", "inf", "-Infinity", "1e400", "1e200", "0x10", "  ", "#N/A", "1d5", "text", "2.5e-300"]


def three_ways(path, wanted):
    """(outcome as read_csv reads, with numpy only, cell by cell): each a record's columns or the error."""
    outcomes = []
    for parser in ("auto", "numpy", "cells"):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                record = read_csv(path, wanted, parser=parser)
                outcome = {"t": record.t, **record.columns}
            except RecordError as error:
                outcome = str(error)
        outcomes.append((outcome, [str(w.message) for w in caught]))
    return outcomes


def same(a, b) -> bool:
    if isinstance(a[0], str) or isinstance(b[0], str):
        return a == b
    return a[1] == b[1] and a[0].keys() == b[0].keys() and all(
        a[0][k].dtype == b[0][k].dtype and a[0][k].tobytes() == b[0][k].tobytes() for k in a[0])


@pytest.mark.parametrize("cell", CELLS)
@pytest.mark.parametrize("where", ["signal", "time", "unused"])
def test_one_odd_cell_is_read_alike_three_ways(tmp_path, cell, where):
    rows = [["0", "1", "7"], ["1", "2", "8"], ["2", "3", "9"]]
    rows[1][{"time": 0, "signal": 1, "unused": 2}[where]] = cell
    path = tmp_path / "odd.csv"
    path.write_text("t,x,note\n" + "\n".join(",".join(r) for r in rows) + "\n")
    default, numpy_only, careful = three_ways(path, ["x"])
    assert same(default, careful) and same(numpy_only, careful), (cell, where, default, numpy_only, careful)


@pytest.mark.parametrize("text", [
    "t,x\n0,1\n1,2\n2,3",                    # no final newline
    "t,x\r\n0,1\r\n1,2\r\n2,3\r\n",          # Windows line ends
    "\ufefft,x\n0,1\n1,2\n2,3\n",            # a byte-order mark
    "t,x\n0,1\n1,2\n2,3\n\n\n",              # trailing blank lines
    "t,x\n0,1\n1,2\n2,3\n,\n",               # a trailing row of empty cells
    "t,x\n0,1\n\n1,2\n2,3\n",                # a blank line inside
    "t,x,y\n0,1,\n1,,2\n2,3,4\n",            # empty cells at a row's end and inside
    "t,x,y\n0,,\n1,2,3\n2,3,4\n",            # two empty cells in a row
    "t,x\n0,1,2\n1,2\n2,3\n",                # a row too long
    "t,x\n0,1\n1\n2,3\n",                    # a row too short
    "t;x\n0;1\n1;2\n2;3\n",                  # semicolons
    "t,x,x\n0,1,1\n1,2,2\n2,3,3\n",          # a duplicate column
    " t , x \n0,1\n1,2\n2,3\n",              # spaces around the names
    "time,x\n0,1\n1,2\n2,3\n",               # no t
    "t,x\n0,1\n1,2\n1,3\n",                  # t does not increase
    "t,x\n0,1\n,2\n2,3\n",                   # a missing time
    "t,x\n0,1\n1,2\n",                       # two samples
    "t,x\n",                                 # no sample
    "",                                      # empty
    "t,x,label\n0,1,a\n1,2,b\n2,3,c\n",      # an unused text column
    "t,x\n0,#1\n1,2\n2,3\n",                 # a comment sign
])
def test_files_of_every_shape_are_read_alike_three_ways(tmp_path, text):
    path = tmp_path / "run.csv"
    path.write_bytes(text.encode("utf-8"))
    default, numpy_only, careful = three_ways(path, ["x"])
    assert same(default, careful) and same(numpy_only, careful), (text, default, numpy_only, careful)


def test_a_long_record_of_numbers_and_gaps_is_read_alike_and_by_a_fast_path(tmp_path, monkeypatch):
    rng = np.random.default_rng(5)
    n = 5000
    values = rng.standard_normal((n, 3)) * 10.0 ** rng.integers(-8, 8, (n, 3))
    cells = [[f"{v:.17g}" for v in row] for row in values]
    for i in rng.integers(0, n, 200):
        cells[i][int(rng.integers(0, 3))] = ""
    path = tmp_path / "long.csv"
    path.write_text("t,a,b,c\n" + "\n".join(f"{k * 1e-3:.6f}," + ",".join(row) for k, row in enumerate(cells)) + "\n")
    default, numpy_only, careful = three_ways(path, ["a", "b", "c"])
    assert same(default, careful) and same(numpy_only, careful)
    assert np.isnan(careful[0]["a"]).sum() + np.isnan(careful[0]["b"]).sum() + np.isnan(careful[0]["c"]).sum() > 150
    used = []
    monkeypatch.setattr(fast, "_by_numpy", lambda *a: used.append("numpy"))
    read_csv(path, ["a"])
    assert used == [] or used == ["numpy"]   # pyarrow read it, or numpy was asked (no pyarrow here)


@pytest.mark.extras   # pyarrow
def test_pyarrow_reads_alike_when_installed_and_a_bad_parser_is_named(tmp_path):
    pytest.importorskip("pyarrow")
    path = tmp_path / "run.csv"
    path.write_text("t,x,note\n0,1,a\n1,,b\n2,3,c\n")
    careful = three_ways(path, ["x"])[2]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        record = read_csv(path, ["x"], parser="pyarrow")
    assert same(({"t": record.t, **record.columns}, [str(w.message) for w in caught]), careful)
    with pytest.raises(RecordError, match="parser must be one of 'auto', 'pyarrow', 'numpy', 'cells', got 'fast'"):
        read_csv(path, parser="fast")


@pytest.mark.parametrize("raw", [b"t,x\n0,1\n1,\xe9\n2,3\n", b"t,x,n\xe9\n0,1,2\n1,2,3\n2,3,4\n"])
def test_bytes_that_are_not_utf8_are_left_to_the_careful_reader(tmp_path, raw):
    path = tmp_path / "latin.csv"
    path.write_bytes(raw)
    default, numpy_only, careful = three_ways(path, ["x"])
    assert isinstance(careful[0], str) and "cannot be read" in careful[0]
    assert same(default, careful) and same(numpy_only, careful)
