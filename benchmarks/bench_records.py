"""Reading records: diagnosis.read_csv against numpy's loadtxt.

    python benchmarks/bench_records.py [--json] [--rows 200000] [--repeats 7]

A record of ``--rows`` rows and 4 columns (t and three signals, 10 significant digits) is read by
``numpy.loadtxt`` (the reference: no checks, no gaps), by ``read_csv(parser="pyarrow")`` (what it
uses when pyarrow is installed), by ``read_csv(parser="numpy")`` (what a machine without pyarrow
gets), and by ``read_csv(parser="cells")`` (cell by cell: the reader that names a bad cell, and what
``read_csv`` took for every file before).  The same again on a record with 1 % of its
cells empty (gaps).  CPU time per read after one untimed read (the first imports pyarrow's CSV
module, about 0.2 s once per process), mean and worst over the repeats; the ratios are of the means.
Targets: pyarrow <= 1x loadtxt, numpy <= 1.5x.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from diagnosis.csv_reading import read_csv  # noqa: E402


def write_record(path: Path, rows: int, gaps: float, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    values = np.column_stack([np.arange(rows) * 1e-3, rng.standard_normal((rows, 3))])
    text = [f"{t:.10g},{a:.10g},{b:.10g},{c:.10g}" for t, a, b, c in values]
    if gaps:
        cells = [line.split(",") for line in text]
        for i in rng.choice(rows, int(gaps * rows * 3), replace=False):
            cells[i][1 + int(rng.integers(0, 3))] = ""
        text = [",".join(c) for c in cells]
    path.write_text("t,a,b,c\n" + "\n".join(text) + "\n")


def cpu(read, repeats: int) -> dict:
    read()  # once untimed: the first read of a process imports pyarrow's CSV module (about 0.2 s)
    times = []
    for _ in range(repeats):
        start = time.process_time()
        read()
        times.append(time.process_time() - start)
    return {"mean_s": float(np.mean(times)), "worst_s": float(np.max(times))}


def measure(path: Path, repeats: int, gaps: bool) -> dict:
    ways = {}
    if not gaps:  # loadtxt reads no empty cell
        ways["loadtxt"] = cpu(lambda: np.loadtxt(path, delimiter=",", skiprows=1), repeats)
    try:
        import pyarrow  # noqa: F401
        ways["read_csv_pyarrow"] = cpu(lambda: read_csv(path, parser="pyarrow"), repeats)
    except ImportError:
        pass
    ways["read_csv_numpy"] = cpu(lambda: read_csv(path, parser="numpy"), repeats)
    ways["read_csv_cell_by_cell"] = cpu(lambda: read_csv(path, parser="cells"), max(1, repeats // 3))
    return ways


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--rows", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        plain, gapped = Path(folder) / "plain.csv", Path(folder) / "gaps.csv"
        write_record(plain, args.rows, 0.0)
        write_record(gapped, args.rows, 0.01)
        result = {"rows": args.rows, "columns": 4, "repeats": args.repeats,
                  "plain": measure(plain, args.repeats, gaps=False),
                  "gaps_1pct": measure(gapped, args.repeats, gaps=True)}
    reference = result["plain"]["loadtxt"]["mean_s"]
    for case in ("plain", "gaps_1pct"):
        result[f"{case}_ratio_to_loadtxt"] = {way: figures["mean_s"] / reference
                                              for way, figures in result[case].items() if way != "loadtxt"}
    if args.json:
        print(json.dumps(result))
    else:
        for case in ("plain", "gaps_1pct"):
            for way, figures in result[case].items():
                ratio = figures["mean_s"] / reference
                print(f"{case:10s} {way:24s} {1e3 * figures['mean_s']:8.1f} ms (worst {1e3 * figures['worst_s']:7.1f})"
                      f"  {ratio:5.2f}x loadtxt")
    return 0


if __name__ == "__main__":
    sys.exit(main())
