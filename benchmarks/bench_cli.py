"""The command line's start-up: CPU time of ``bgphm --help`` and ``bgphm --version`` against ``python -c pass``.

Each command runs in a fresh interpreter (``python -m bgphm``) several times; the CPU time of a run is the
child's user + system time (``resource.getrusage``), and the figure is the median over the runs.  The
ratio to ``python -c pass`` is what carries from machine to machine.

    python benchmarks/bench_cli.py            # table
    python benchmarks/bench_cli.py --json     # {"python_pass_s": ..., "help_s": ..., "help_ratio": ..., ...}

Target: ``bgphm --help`` under 0.3 s of CPU (it loads neither sympy nor scipy nor networkx).
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys

COMMANDS = {"python_pass": ["-c", "pass"], "help": ["-m", "bgphm", "--help"], "version": ["-m", "bgphm", "--version"],
            "arr_help": ["-m", "bgphm", "arr", "--help"]}


def child_cpu(arguments: list[str]) -> float:
    """CPU seconds (user + system) of one ``python ARGUMENTS`` run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, *arguments], check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def measure(runs: int) -> dict:
    """Median CPU seconds of each command over ``runs`` runs, and its ratio to ``python -c pass``."""
    seconds = {name: statistics.median([child_cpu(arguments) for _ in range(runs)])
               for name, arguments in COMMANDS.items()}
    figures = {f"{name}_s": round(value, 4) for name, value in seconds.items()}
    figures.update({f"{name}_ratio": round(value / seconds["python_pass"], 2) for name, value in seconds.items()
                    if name != "python_pass"})
    return {"runs": runs, **figures}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=9)
    parser.add_argument("--json", action="store_true", help="one JSON line")
    args = parser.parse_args()
    figures = measure(args.runs)
    if args.json:
        print(json.dumps(figures))
        return
    for key, value in figures.items():
        print(f"{key:<16} {value}")


if __name__ == "__main__":
    main()
