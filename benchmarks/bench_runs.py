"""How long a multi-seed run (bgphm.runs.over_seeds on two workers) takes to stop after Ctrl-C.

A child script runs six jobs on two worker processes: the first takes 0.2 s, the others 60 s.  Once the
first is reported done (two 60 s jobs are then running), the benchmark sends SIGINT to the child's
process group, as Ctrl-C does, and measures the time until the child has exited with "interrupted".
Baseline, in the same process: the whole run of the same script when every job takes 0.2 s (interpreter
start, worker pool, six jobs, shut-down).

    python benchmarks/bench_runs.py            # table
    python benchmarks/bench_runs.py --json     # {"interrupt_seconds": ..., "ratio_vs_short_run": ..., ...}

Target (moved here from tests/cli/test_runs.py, which checks the clean exit): stopped within 10 s,
not after the 60 s jobs; the README quotes about 0.25 s for examples/three_tank.py.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = """
import signal, sys, time
sys.path.insert(0, {root!r})
signal.signal(signal.SIGINT, signal.default_int_handler)  # a background shell may have ignored it
from bgphm.runs import over_seeds, progress_line, run_main

def job(seed):
    time.sleep(0.2 if seed == 0 or {short} else 60.0)
    return seed

if __name__ == "__main__":
    run_main(lambda: over_seeds(job, [(s,) for s in range(6)], workers=2, progress=progress_line(False)))
"""


def start(folder: Path, short: bool) -> subprocess.Popen:
    script = folder / ("short.py" if short else "long.py")
    script.write_text(textwrap.dedent(SCRIPT.format(root=str(ROOT), short=short)))
    return subprocess.Popen([sys.executable, str(script)], start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)


def short_run(folder: Path) -> float:
    begin = time.perf_counter()
    run = start(folder, short=True)
    _, err = run.communicate(timeout=120)
    if run.returncode != 0:
        raise RuntimeError(err)
    return time.perf_counter() - begin


def interrupted_run(folder: Path) -> float:
    run = start(folder, short=False)
    try:
        for line in run.stderr:  # wait for the first job: the 60 s jobs are then running
            if "seed 1/6 done" in line:
                break
        time.sleep(0.2)
        os.killpg(run.pid, signal.SIGINT)
        begin = time.perf_counter()
        rest = run.stderr.read()
        run.wait(timeout=120)
        seconds = time.perf_counter() - begin
    finally:
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGKILL)
    if run.returncode != 1 or rest.strip().splitlines()[-1:] != ["interrupted"]:
        raise RuntimeError(f"exit code {run.returncode}, stderr {rest!r}")
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as folder:
        baseline = min(short_run(Path(folder)) for _ in range(args.repeat))
        latency = min(interrupted_run(Path(folder)) for _ in range(args.repeat))
    figures = {"interrupt_seconds": round(latency, 3), "short_run_seconds": round(baseline, 3),
               "ratio_vs_short_run": round(latency / baseline, 2), "target_seconds": 10.0,
               "meets_target": latency < 10.0}
    if args.json:
        print(json.dumps(figures))
        return
    print("over_seeds, 2 workers, Ctrl-C while two 60 s jobs run")
    print(f"  stopped {latency:.3f} s after SIGINT (best of {args.repeat}); target < 10 s: "
          f"{'met' if figures['meets_target'] else 'NOT met'}")
    print(f"  baseline, the whole run with six 0.2 s jobs: {baseline:.3f} s; ratio {figures['ratio_vs_short_run']}")


if __name__ == "__main__":
    main()
