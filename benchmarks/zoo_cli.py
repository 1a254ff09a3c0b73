"""The command line over the whole zoo: ``arr`` (md, html, tex), ``simulate``, ``detect``, ``prognose`` per model.

    python benchmarks/zoo_cli.py [NAME ...]

Runs tests/zoo/test_cli_chain.py's chain on every zoo model (its slow tier runs a subset) and prints one
JSON object: model -> command -> exit code.  An exit other than 0 or 2 (or a message of more than one
line) stops with the model and the command named; exit status 1 then.
"""

from __future__ import annotations

import json
import sys
import tempfile
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.zoo.test_cli_chain import BY_NAME, run_the_chain  # noqa: E402


def main() -> int:
    warnings.simplefilter("ignore")
    names = sys.argv[1:] or sorted(BY_NAME)
    codes = {}
    for name in names:
        with tempfile.TemporaryDirectory() as scratch:
            try:
                codes[name] = run_the_chain(BY_NAME[name], Path(scratch))
            except AssertionError as failure:
                print(json.dumps({"model": name, "failure": str(failure)}))
                return 1
        print(f"{name}: {codes[name]}", file=sys.stderr)
    print(json.dumps(codes, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
