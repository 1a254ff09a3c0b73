"""Write docs/tutorial/scripts/ from the tutorials: each tutorial's code blocks, in order, as one script.

A tutorial is the source.  Its code sits in ```` ```python ```` blocks (tutorials 1 to 3) or ```` ```bash ````
blocks (tutorial 4), which run in order; a ```` ```text ```` block that comes right after a code block (only
blank lines between) is what that block prints.  Any other ```` ```text ```` block (a sketch, a formula) is
prose.  This program writes the code blocks as ``scripts/<n>_<name>.py`` or ``.sh``, one cell per block: a
``# %%`` line, the cell marker of Jupyter, VS Code and Spyder, followed by the block.

    python docs/tutorial/build_scripts.py        # after editing a tutorial

tests/cases/test_tutorials.py checks that the scripts are up to date, runs each one cell by cell in a fresh
process and compares what each cell prints with the text block shown after its code block.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCRIPTS = HERE / "scripts"

#: The code languages, and the suffix of the script they make.
CODE = {"python": ".py", "bash": ".sh"}
#: The languages a fence of a tutorial may have: code, and text (an output, or prose).
LANGUAGES = {*CODE, "text"}
#: The line that starts a cell (a code block) in a script.
CELL = "# %%"


@dataclass(frozen=True)
class Fence:
    """A fenced block of a tutorial."""

    language: str
    line: int              # line number of the opening fence in the markdown
    text: str              # the lines between the fences, each ending with a newline
    section: str           # the heading above it
    after_code: bool       # only blank lines between it and the code block before it


@dataclass(frozen=True)
class Step:
    """A code block and the output the tutorial shows for it (None: it prints nothing)."""

    code: Fence
    output: Fence | None


def fences(text: str) -> list[Fence]:
    """The fenced blocks of a markdown text, in order (fences at the start of a line, as the tutorials write them)."""
    found: list[Fence] = []
    section, opened, body, blank_since_code = "", None, [], False
    for number, line in enumerate(text.splitlines(), start=1):
        if opened is not None:
            if line.rstrip() == "```":
                kind, start = opened
                found.append(Fence(kind, start, "".join(f"{part}\n" for part in body), section, blank_since_code))
                # a text block is the output of the code block before it only if nothing but blank lines is between
                blank_since_code, opened = kind in CODE, None
            else:
                body.append(line)
        elif line.startswith("```"):
            opened, body = (line[3:].strip(), number), []
        elif line.startswith("#"):
            section, blank_since_code = line.lstrip("#").strip(), False
        elif line.strip():
            blank_since_code = False
    if opened is not None:
        raise ValueError(f"line {opened[1]}: the ``` fence is never closed")
    return found


def steps(path: Path) -> list[Step]:
    """The code blocks of the tutorial at ``path``, each with the output shown right after it."""
    blocks = fences(path.read_text(encoding="utf-8"))
    found = []
    for index, fence in enumerate(blocks):
        if fence.language in CODE:
            after = blocks[index + 1] if index + 1 < len(blocks) else None
            shown = after if after is not None and after.language == "text" and after.after_code else None
            found.append(Step(fence, shown))
    return found


def language(path: Path) -> str:
    """The one code language of a tutorial (a tutorial is a Python script or a shell script, not both)."""
    used = {step.code.language for step in steps(path)}
    if len(used) != 1:
        raise ValueError(f"{path.name}: code blocks in {sorted(used) or 'no language'}; expected one of {sorted(CODE)}")
    return used.pop()


def script_path(path: Path) -> Path:
    """Where the script of a tutorial goes: ``1-model.md`` gives ``scripts/1_model.py``."""
    return SCRIPTS / (path.stem.replace("-", "_") + CODE[language(path)])


def script(path: Path) -> str:
    """The script of the tutorial at ``path``: a header, then one cell per code block."""
    title = path.read_text(encoding="utf-8").splitlines()[0].lstrip("#").strip()
    run = f"docs/tutorial/scripts/{script_path(path).name}"
    about = [f"{title} (docs/tutorial/{path.name}), as a script.", ""]
    origin = ["Each cell (a `# %%` line) is a code block of the tutorial, which explains it and shows what it",
              "prints.  Written by docs/tutorial/build_scripts.py: edit the tutorial, then run that."]
    if language(path) == "python":
        header = ['"""' + about[0], "", f"Run it with `python {run}`.", *origin, '"""',
                  "# each cell imports what it first needs, as the tutorial does:", "# ruff: noqa: E402"]
    else:
        header = ["#!/usr/bin/env bash", *(f"# {line}".rstrip() for line in about),
                  "# Run it in an empty directory, where it writes its files; from the repository's root:",
                  f'#     (cd "$(mktemp -d)" && bash "$OLDPWD/{run}")',
                  *(f"# {line}" for line in origin), "set -euo pipefail"]
    cells = []
    for step in steps(path):
        if any(line.startswith(CELL) for line in step.code.text.splitlines()):
            raise ValueError(f"{path.name} line {step.code.line}: a code line starts with {CELL!r}, the cell marker")
        cells.append(f"\n{CELL} {step.code.section}\n{step.code.text}")
    return "".join(f"{line}\n" for line in header) + "".join(cells)


def cells(text: str) -> list[tuple[int, str]]:
    """The cells of a script: the line number of each cell's first line of code, and its code."""
    lines = text.splitlines(keepends=True)
    starts = [number for number, line in enumerate(lines) if line.startswith(CELL)]
    return [(start + 2, "".join(lines[start + 1:end])) for start, end in zip(starts, [*starts[1:], len(lines)])]


def tutorials() -> list[Path]:
    """The tutorials, in reading order."""
    return sorted(path for path in HERE.glob("*.md") if path.name != "README.md")


def build() -> dict[Path, str]:
    """Every script, by path."""
    return {script_path(path): script(path) for path in tutorials()}


def main() -> None:
    SCRIPTS.mkdir(exist_ok=True)
    for path, text in build().items():
        path.write_text(text, encoding="utf-8")
        print(f"wrote {path.relative_to(HERE.parents[1])}")


if __name__ == "__main__":
    main()
