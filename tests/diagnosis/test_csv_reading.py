"""CSV records: text columns, bad files named by file, line and column, number formats and gaps."""

import warnings

import numpy as np
import pytest

from diagnosis.csv_reading import read_csv
from diagnosis.records import RecordError, RecordWarning




# --- read_csv -------------------------------------------------------------------------------


def write(tmp_path, text, name="run.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_read_csv_ignores_a_text_column_it_does_not_read_with_one_warning(tmp_path):
    path = write(tmp_path, "t,x,label,note,y\n0,1,a,,5\n1,2,b,ok,6\n2,3,c,1,7\n")
    with pytest.warns(RecordWarning) as caught:
        record = read_csv(path, ["x"])
    assert record.signals == ("x",) and record["x"].tolist() == [1.0, 2.0, 3.0]
    assert len(caught) == 1  # one warning for every such column; 'y' is numeric, so not named
    assert str(caught[0].message) == (f"{path}: columns 'label', 'note' are not numeric and not among the signals "
                                      "read: ignored")
    with pytest.warns(RecordWarning, match=r"column 'label' is not numeric"):
        read_csv(write(tmp_path, "t,x,label\n0,1,a\n1,2,b\n2,3,c\n"), "x")


def test_read_csv_numeric_columns_it_does_not_read_are_not_checked(tmp_path):
    path = write(tmp_path, "t,x,big\n0,1,1e300\n1,2,inf\n2,3,\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_csv(path, ["x"]).signals == ("x",)
    with pytest.raises(RecordError, match=r"line 2, column 'big': '1e300' is larger in magnitude than 1e\+150"):
        read_csv(path)  # every column is read by default


def test_read_csv_text_in_a_column_it_reads_stays_an_error(tmp_path):
    path = write(tmp_path, "t,x,y\n0,1,1\n1,2,b\n2,3,3\n")
    with pytest.raises(RecordError, match=r"run.csv line 3, column 'y': 'b' is not a number$"):
        read_csv(path, ["x", "y"])
    with pytest.raises(RecordError, match=r"line 3, column 'y': 'b' is not a number"):
        read_csv(path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("t;x\n0;1\n1;2\n2;3\n", r"line 1: the file seems to be separated by ';', but read_csv expects commas"),
        ("t\tx\n0\t1\n1\t2\n2\t3\n", r"line 1: the file seems to be separated by tabs, but read_csv expects commas"),
        ("t|x\n0|1\n1|2\n2|3\n", r"line 1: the file seems to be separated by '\|'"),
        ("t,x\n0,1\n1;2\n2,3\n", r"line 3: 1 cells for 2 columns, as if separated by ';', but read_csv expects commas"),
        ("t,x\n0,1\n1,2,3\n2,3\n", r"line 3: 3 cells for 2 columns$"),
        ("t,x\n0,1_000\n1,2\n2,3\n", r"line 2, column 'x': '1_000' is not a number \(digit separators such as '_' "
                                     r"are not allowed\)"),
        ("t,x\n0,1\n1,\u0661\u0662\n2,3\n", r"line 3, column 'x': '\u0661\u0662' is not a number$"),
        ("t,x\n0,1\n1,0x10\n2,3\n", r"line 3, column 'x': '0x10' is not a number"),
        ("t,x\n0,1\n1,1e308\n2,3\n", r"line 3, column 'x': '1e308' is larger in magnitude than 1e\+150 "
                                     r"\(MAX_MAGNITUDE\): the residuals would overflow"),
        ("t,x\n0,1\n1e200,2\n2e200,3\n", r"line 3, column 't': '1e200' is larger in magnitude"),
        ("t,x\n0,1\n1,-Infinity\n2,3\n", r"line 3, column 'x': '-Infinity' is infinite \(leave the cell empty"),
        ("t,x\n0,1\n1,1e999\n2,3\n", r"line 3, column 'x': '1e999' is infinite"),
    ],
)
def test_read_csv_bad_files_name_file_line_and_column(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(RecordError, match=r"run.csv " + message):
        read_csv(path)


def test_read_csv_number_formats_and_gaps(tmp_path):
    path = write(tmp_path, "t,x\n0, 1.5e-3 \n1,.5\n2,3.\n3,-nan\n4,NA\n5,+2E+2\n")
    assert read_csv(path)["x"].tolist()[:3] == [1.5e-3, 0.5, 3.0]
    assert np.isnan(read_csv(path)["x"][3:5]).all() and read_csv(path)["x"][5] == 200.0
