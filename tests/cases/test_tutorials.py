"""The tutorials run as printed.

Each tutorial in docs/tutorial/ is the source of a script in docs/tutorial/scripts/, written by
docs/tutorial/build_scripts.py: one cell per code block (```` ```python ```` in tutorials 1 to 3,
```` ```bash ```` in tutorial 4).  The test checks that the scripts are up to date, then runs each script cell
by cell in a fresh process, in an empty temporary directory, and compares what each cell prints with the
```` ```text ```` block the tutorial shows right after that code block (no block: it must print nothing).
A shell cell must exit with 0 (a command meant to fail is followed by ``|| echo "exit code $?"``), and a file
it says it wrote (``wrote PATH``) must be there.  Only the elapsed time of ``bgphm``'s progress lines may
differ from what the tutorial shows.
"""

from __future__ import annotations

import difflib
import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TUTORIALS = ROOT / "docs" / "tutorial"

#: The least each tutorial must keep: lines of code, and lines of output compared (a tutorial that loses its
#: code or stops showing what it prints fails).
MINIMUM = {"1-model.md": (100, 50), "2-diagnosis.md": (90, 45), "3-prognosis.md": (90, 24),
           "4-command-line.md": (75, 110), "5-calibration.md": (35, 16), "6-fault-diagnosis-toolbox.md": (15, 7),
           "7-progpy.md": (50, 8), "8-fmi.md": (35, 18),
           "9-bondgraphtools.md": (45, 20), "10-sub-models.md": (75, 15)}

#: Heavy tutorials (slow tier): tutorial 4 runs ``bgphm demo`` and twenty more commands, each in its own
#: process.  Tutorial 1 stays in the fast tier, as does the check that every script is up to date.
SLOW = {"2-diagnosis.md", "3-prognosis.md", "4-command-line.md", "5-calibration.md", "6-fault-diagnosis-toolbox.md",
        "7-progpy.md", "8-fmi.md", "9-bondgraphtools.md", "10-sub-models.md"}
#: Tutorials that need an optional interop package (the ``interop`` marker): 6 runs the Fault Diagnosis Toolbox,
#: 7 NASA's ProgPy, 8 fmpy (and a C compiler), 9 reads BondGraphTools files with PyYAML.
INTEROP = {"6-fault-diagnosis-toolbox.md", "7-progpy.md", "8-fmi.md", "9-bondgraphtools.md"}
#: Tutorials that draw with matplotlib (the plot extra; ``bgphm demo`` in 4 prints the figures it writes).
PLOTS = {"2-diagnosis.md", "3-prognosis.md", "4-command-line.md"}

#: What may differ from one run to the next, and only that: the elapsed time a ``bgphm`` progress line starts with.
ELAPSED = re.compile(r"^\[ *\d+\.\d s\] ", re.MULTILINE)
#: A number with at least 12 significant digits: printed at full precision, so its last bits are the machine's.
NUMBER = re.compile(r"(?<![\w.])(-?\d+\.\d{11,}(?:e[-+]?\d+)?|-?\d\.\d{11,}e[-+]?\d+)(?![\w.])")
#: The relative difference allowed between two such numbers.
DIGITS = 1e-9
#: A file a command says it wrote.
WROTE = re.compile(r"^wrote (\S+)$", re.MULTILINE)

#: Run before each shell cell: the script's shell options, and ``bgphm`` and ``python`` mapped to the Python
#: that runs the tests, importing this checkout (PYTHONPATH), whichever ``bgphm`` console script is on the PATH.
PRELUDE = 'set -euo pipefail\nbgphm() { "$TUTORIAL_PYTHON" -m bgphm "$@"; }\npython() { "$TUTORIAL_PYTHON" "$@"; }\n'

#: Runs the cells of a Python script (JSON on stdin: first line, code) in one namespace, as ``python script``
#: would, and prints what each cell printed, one JSON string per line, as soon as the cell is done.
RUNNER = """
import contextlib, io, json, sys
script = sys.argv[1]
namespace = {"__name__": "__main__", "__file__": script}
for first_line, code in json.load(sys.stdin):
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        exec(compile("\\n" * (first_line - 1) + code, script, "exec"), namespace)  # tracebacks: the script's lines
    print(json.dumps(printed.getvalue()), flush=True)
"""


def build_scripts():
    """docs/tutorial/build_scripts.py as a module (registered in sys.modules: its dataclasses look their module up)."""
    if "build_scripts" not in sys.modules:
        spec = importlib.util.spec_from_file_location("build_scripts", TUTORIALS / "build_scripts.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["build_scripts"] = module
        spec.loader.exec_module(module)
    return sys.modules["build_scripts"]


def environment() -> dict[str, str]:
    """The environment of a run: this checkout on the path, unbuffered output (stderr and stdout in the order a
    terminal shows them), and a fixed locale (the order of ``ls``)."""
    return {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONUNBUFFERED": "1", "LC_ALL": "C.UTF-8",
            "TUTORIAL_PYTHON": sys.executable}


def run(script: Path, cwd: Path) -> list[tuple[str, int]]:
    """Run ``script`` cell by cell in ``cwd``: what each cell printed and its exit status, up to the first
    cell that fails (its output is then its stderr)."""
    cells = build_scripts().cells(script.read_text(encoding="utf-8"))
    if script.suffix == ".py":
        done = subprocess.run([sys.executable, "-c", RUNNER, str(script)], input=json.dumps(cells), cwd=cwd,
                              env=environment(), capture_output=True, text=True)
        results = [(json.loads(line), 0) for line in done.stdout.splitlines()]
        return results + [(done.stderr, done.returncode)] if done.returncode else results
    results = []
    for _, code in cells:
        done = subprocess.run(["bash", "-c", PRELUDE + code], cwd=cwd, env=environment(), stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
        results.append((done.stdout, done.returncode))
        if done.returncode:
            break
    return results


def normalised(text: str) -> str:
    return ELAPSED.sub("[... s] ", text)


def same_output(shown: str, printed: str) -> bool:
    """``printed`` is what the tutorial shows: the same text, its numbers the same to :data:`DIGITS` (an ODE
    solver's or a sum's last bits differ between machines: 1.3904838519333682 and 1.3904838519332785)."""
    shown, printed = normalised(shown), normalised(printed)
    if shown == printed:
        return True
    words, numbers = NUMBER.split(shown), NUMBER.split(printed)
    if len(words) != len(numbers) or words[::2] != numbers[::2]:
        return False
    return all(a == b or abs(float(a) - float(b)) <= DIGITS * max(abs(float(a)), abs(float(b))) + 1e-15
               for a, b in zip(words[1::2], numbers[1::2]))


def problems(tutorial: Path, script: Path, cwd: Path) -> list[str]:
    """How running ``script`` in ``cwd`` differs from what ``tutorial`` shows (nothing: it runs as printed)."""
    found = []
    for step, (printed, status) in zip(build_scripts().steps(tutorial), run(script, cwd)):
        where = f"{tutorial.name} line {step.code.line} ({step.code.section})"
        if status:
            return [*found, f"{where}: exit status {status}\n{printed}"]
        shown = step.output.text if step.output else ""
        if not same_output(shown, printed):
            diff = difflib.unified_diff(shown.splitlines(), printed.splitlines(), "shown", "printed", lineterm="")
            found.append(f"{where} printed what the tutorial does not show:\n" + "\n".join(diff))
        found += [f"{where}: says 'wrote {name}', but there is no such file" for name in WROTE.findall(printed)
                  if not (cwd / name).is_file()]
    return found


def test_every_tutorial_is_listed():
    names = {path.name for path in build_scripts().tutorials()}
    assert names == set(MINIMUM), "add the new tutorial to MINIMUM in tests/cases/test_tutorials.py"
    index = (TUTORIALS / "README.md").read_text(encoding="utf-8")
    for path in build_scripts().tutorials():
        assert f"({path.name})" in index, f"docs/tutorial/README.md does not link {path.name}"
        script = build_scripts().script_path(path).relative_to(ROOT).as_posix()
        assert script in index, f"docs/tutorial/README.md does not say how to run {script}"


@pytest.mark.parametrize("name", sorted(MINIMUM))
def test_tutorial_code_is_in_runnable_blocks(name):
    """Code only in blocks that run, and enough of it: no console transcript (``>>>``), no other language."""
    path = TUTORIALS / name
    text = path.read_text(encoding="utf-8")
    prompts = [number for number, line in enumerate(text.splitlines(), 1) if line.lstrip().startswith(">>>")]
    assert not prompts, f"{name}: '>>>' console lines at {prompts}: write the code as a script"
    fences = build_scripts().fences(text)
    assert {fence.language for fence in fences} <= build_scripts().LANGUAGES, (
        f"{name}: fences in {sorted({fence.language for fence in fences})}; only {sorted(build_scripts().LANGUAGES)} "
        "(other blocks would never run)")
    steps = build_scripts().steps(path)
    code = sum(1 for step in steps for line in step.code.text.splitlines() if line.strip())
    shown = sum(len(step.output.text.splitlines()) for step in steps if step.output)
    least_code, least_shown = MINIMUM[name]
    assert code >= least_code, f"{name} has {code} lines of code; it should keep at least {least_code}"
    assert shown >= least_shown, f"{name} shows {shown} lines of output; it should keep at least {least_shown}"


def test_scripts_are_up_to_date():
    built = build_scripts().build()
    on_disk = {path: path.read_text(encoding="utf-8") for path in (TUTORIALS / "scripts").iterdir()}
    assert sorted(on_disk) == sorted(built), "docs/tutorial/scripts/ holds other files than the tutorials' scripts"
    for path, text in built.items():
        assert on_disk[path] == text, f"{path.name} is out of date: run `python docs/tutorial/build_scripts.py`"


@pytest.mark.parametrize("name", [pytest.param(name, marks=[*([pytest.mark.slow] if name in SLOW else []),
                                                               *([pytest.mark.interop] if name in INTEROP else []),
                                                               *([pytest.mark.extras] if name in PLOTS else [])])
                                  for name in sorted(MINIMUM)])
def test_tutorial_runs_as_printed(name, tmp_path):
    path = TUTORIALS / name
    found = problems(path, build_scripts().script_path(path), tmp_path)
    assert not found, "\n\n".join(found)


@pytest.mark.slow   # tutorial 1 runs cell by cell in the fast tier already
def test_a_script_runs_as_the_readme_says(tmp_path):
    """``python docs/tutorial/scripts/1_model.py``, the whole script at once, prints every output shown."""
    path = TUTORIALS / "1-model.md"
    done = subprocess.run([sys.executable, str(build_scripts().script_path(path))], cwd=tmp_path, env=environment(),
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "".join(step.output.text for step in build_scripts().steps(path) if step.output)
    assert sorted(p.name for p in tmp_path.iterdir()) == [], "the tutorial writes only to its temporary directory"


DRIFTED = {
    "python": ("```python\nprint(1)\n```\n\n```text\n2\n```\n\n```python\nprint(3)\n```\n\n"
               "```python\nx = 4\n```\n\n```text\n4\n```\n\n```python\nraise SystemExit(5)\n```\n",
               ["printed what the tutorial does not show:\n--- shown\n+++ printed\n@@ -1 +1 @@\n-2\n+1",
                "printed what the tutorial does not show:\n--- shown\n+++ printed\n@@ -0,0 +1 @@\n+3",
                "printed what the tutorial does not show:\n--- shown\n+++ printed\n@@ -1 +0,0 @@\n-4",
                ": exit status 5"]),
    "bash": ('```bash\necho "wrote a.txt"\n```\n\n```text\nwrote a.txt\n```\n\n```bash\nfalse\necho never\n```\n',
             [": says 'wrote a.txt', but there is no such file", ": exit status 1"]),
}


@pytest.mark.parametrize("language", sorted(DRIFTED))
def test_a_tutorial_that_drifts_fails(language, tmp_path):
    """The check itself: a wrong output, an output not shown, one shown but not printed, a failing cell and a
    file said written but missing are each reported, with the tutorial's line."""
    text, expected = DRIFTED[language]
    tutorial = tmp_path / "9-drift.md"
    tutorial.write_text(f"# Tutorial 9: drift\n\n## Steps\n\n{text}", encoding="utf-8")
    script = tmp_path / f"drift{build_scripts().CODE[language]}"
    script.write_text(build_scripts().script(tutorial), encoding="utf-8")
    work = tmp_path / "work"
    work.mkdir()
    found = problems(tutorial, script, work)
    assert len(found) == len(expected)
    for problem, end in zip(found, expected):
        assert problem.startswith("9-drift.md line ") and " (Steps)" in problem and end in problem, problem


def test_only_the_last_bits_of_a_full_precision_number_may_differ():
    shown = "0.5,12.0,1.3904838519333682,264.5299385539015\n{'margin': 0.0023668804023255293, 'at': 1.403}\n"
    assert same_output(shown, shown.replace("1.3904838519333682", "1.3904838519332785")
                       .replace("0.0023668804023255293", "0.0023668804023248605"))
    assert not same_output(shown, shown.replace("1.3904838519333682", "1.3904858519333682"))  # 1.4e-6 apart
    assert not same_output(shown, shown.replace("1.403", "1.404"))       # a short number is compared as text
    assert not same_output(shown, shown.replace("12.0", "12.5"))
    assert not same_output(shown, shown.replace("margin", "margins"))
