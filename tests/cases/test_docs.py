"""The documentation runs: every tutorial in docs/tutorial/ as a doctest, and docs/api.md is up to date.

A tutorial is markdown whose code sits in ```` ```pycon ```` blocks: ``>>>`` lines with the expected
output, as in a Python console.  Only those blocks are executed (other fences, e.g. ```` ```bash ````, are
illustrations); every other line is blanked so doctest reports the markdown file's own line numbers.
The tutorials that write files make their own temporary directory and remove it at the end.
"""

from __future__ import annotations

import doctest
import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorial"
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE

#: The least number of examples each tutorial must keep (a tutorial that loses its code fails).
MIN_EXAMPLES = {"1-model.md": 85, "2-diagnosis.md": 70, "3-prognosis.md": 70, "4-command-line.md": 40}

#: Optional packages a tutorial needs (the test extra installs them; without them the tutorial is skipped).
NEEDS = {"2-diagnosis.md": ["matplotlib"], "3-prognosis.md": ["matplotlib"], "4-command-line.md": ["matplotlib"]}

FENCE = re.compile(r"^\s*```+\s*([\w+-]*)")


def pycon_source(text: str) -> tuple[str, list[int]]:
    """The lines inside ```` ```pycon ```` fences, other lines blanked; and the numbers of ``>>>`` lines outside."""
    kept, stray, language = [], [], None
    for number, line in enumerate(text.splitlines(), start=1):
        match = FENCE.match(line)
        if match:
            language = (match.group(1) or "") if language is None else None
            kept.append("")
            continue
        if language == "pycon":
            kept.append(line)
        else:
            kept.append("")
            if line.lstrip().startswith(">>>"):
                stray.append(number)
    return "\n".join(kept) + "\n", stray


def run_tutorial(path: Path) -> tuple[doctest.DocTest, doctest.DocTestRunner, str]:
    source, _ = pycon_source(path.read_text(encoding="utf-8"))
    test = doctest.DocTestParser().get_doctest(source, {"__name__": "__tutorial__"}, path.name, str(path), 0)
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    report: list[str] = []
    runner.run(test, out=report.append)
    return test, runner, "".join(report)


def test_every_tutorial_is_listed():
    names = {path.name for path in TUTORIALS.glob("*.md") if path.name != "README.md"}
    assert names == set(MIN_EXAMPLES), "add the new tutorial to MIN_EXAMPLES in tests/cases/test_docs.py"
    index = (TUTORIALS / "README.md").read_text(encoding="utf-8")
    for name in sorted(names):
        assert f"({name})" in index, f"docs/tutorial/README.md does not link {name}"


#: Tutorials that run a ``bgphm demo`` (marked slow).
DEMOS = {"4-command-line.md"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in DEMOS else n
                                  for n in sorted(MIN_EXAMPLES)])
@pytest.mark.slow
def test_tutorial_runs(name):
    for package in NEEDS.get(name, ()):
        pytest.importorskip(package)
    path = TUTORIALS / name
    _, stray = pycon_source(path.read_text(encoding="utf-8"))
    assert not stray, f"{name}: '>>>' outside a ```pycon block (never executed) at lines {stray}"
    test, runner, report = run_tutorial(path)
    assert runner.failures == 0, f"{name}: {runner.failures} of {runner.tries} examples failed\n{report}"
    assert len(test.examples) >= MIN_EXAMPLES[name], (
        f"{name} has {len(test.examples)} examples; it should keep at least {MIN_EXAMPLES[name]}")


def _build_api():
    """docs/build_api.py as a module (registered in sys.modules: its dataclasses look their module up)."""
    if "build_api" not in sys.modules:
        spec = importlib.util.spec_from_file_location("build_api", ROOT / "docs" / "build_api.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["build_api"] = module
        spec.loader.exec_module(module)
    return sys.modules["build_api"]


def test_api_reference_is_up_to_date():
    build_api = _build_api()
    expected = build_api.build()
    current = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert current == expected, "docs/api.md is out of date with the docstrings: run `python docs/build_api.py`"
