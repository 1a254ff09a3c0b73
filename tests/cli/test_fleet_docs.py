"""docs/fleet.md runs: its ```pycon blocks and its `bgphm fleet` command lines, in order, in a temporary directory.

The cluster section's commands (dask scheduler, dask worker, --scheduler) need machines and are not run;
test_fleet_dask.py runs a scheduler address on a local cluster instead.  Slow tier: a local cluster starts.
"""

from __future__ import annotations

import doctest
import re
import shlex
from pathlib import Path

import pytest

from bgphm.cli import main

ROOT = Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "fleet.md"
FENCE = re.compile(r"^```(\w*)\s*$")

pytestmark = pytest.mark.slow


def blocks(text: str) -> list[tuple[str, str, int]]:
    """(language, content, first line) of each fenced block, in order."""
    found, language, lines, start = [], None, [], 0
    for number, line in enumerate(text.splitlines(), start=1):
        match = FENCE.match(line)
        if match and language is None:
            language, lines, start = match.group(1), [], number + 1
        elif line.startswith("```") and language is not None:
            found.append((language, "\n".join(lines) + "\n", start))
            language = None
        elif language is not None:
            lines.append(line)
    return found


def commands(bash: str) -> list[list[str]]:
    """The `bgphm fleet` lines of a bash block that run here (continuations joined, comments dropped)."""
    joined = re.sub(r"\\\n\s*", " ", bash)
    out = []
    for line in joined.splitlines():
        line = line.split("#")[0].strip()
        if line.startswith("bgphm fleet") and "--scheduler" not in line:
            out.append(shlex.split(line)[1:])
    return out


@pytest.mark.extras   # distributed, pandas
def test_the_guide_runs(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    pytest.importorskip("pandas")
    monkeypatch.chdir(tmp_path)
    globs = {"__name__": "__fleet_guide__"}
    ran = {"pycon": 0, "bgphm": 0}
    for language, content, line in blocks(GUIDE.read_text(encoding="utf-8")):
        if language == "pycon":
            test = doctest.DocTestParser().get_doctest(content, globs, "fleet.md", str(GUIDE), line - 1)
            runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
            report = []
            runner.run(test, out=report.append, clear_globs=False)
            assert runner.failures == 0, "".join(report)
            globs.update(test.globs)  # the DocTest worked on a copy: the next block continues from this one
            ran["pycon"] += 1
        elif language == "bash":
            for argv in commands(content):
                assert main(["--quiet", *argv]) == 0, argv
                ran["bgphm"] += 1
    assert ran["pycon"] >= 4 and ran["bgphm"] >= 1


def test_the_guide_is_linked_from_the_readme_and_the_api_reference():
    assert "(docs/fleet.md)" in (ROOT / "README.md").read_text(encoding="utf-8")
    assert "fleet.md" in (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
